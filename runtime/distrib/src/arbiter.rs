//! The arbiter: control arbitration (docs/distribution.md, "Control arbitration") at the
//! site that owns the vehicles' links. Every vehicle under `root.vehicles` gets an
//! `arbitration` object (`holder`, `requested_by`, `policy`, `holder_connected`; methods
//! `request()`, `release()`, `takeover()`, `answer(accept)`) that other sites mirror like
//! the rest of the vehicle; calls from other sites are screened (`calls.rs` asks
//! [`Arbiter::screen`]) with the operator and site their payload carries; a holder whose site
//! disappears loses control `release_after` later on the DataServer's clock.

use crate::control::{Answer, Caller, Control, Grant, Takeover};
use mocu_dataserver::{
    Call, CallOutcome, DataServer, Guid, Kind, MethodSpec, Notification, ObjectInfo, ParamSpec,
    PathWatch, PropMeta, Subject, SubscriptionId, Topic, Value, ValueKind,
};
use parking_lot::Mutex;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

/// The name of the object under each vehicle.
pub const OBJECT: &str = "arbitration";

/// How a site arbitrates its vehicles (the `distrib` module's `takeover*`, `free`,
/// `release_after_ms` and `ask_timeout_ms` settings).
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// The policy of a vehicle not named in `vehicles`.
    pub takeover: Takeover,
    /// Per-vehicle policies, by vehicle name.
    pub vehicles: HashMap<String, Takeover>,
    /// Whether a vehicle nobody holds takes commands from anyone.
    pub open_when_free: bool,
    /// How long after its site disappears a holder loses control.
    pub release_after: Duration,
    /// How long a holder has to answer a takeover it is asked for.
    pub ask_timeout: Duration,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            takeover: Takeover::Allowed,
            vehicles: HashMap::new(),
            open_when_free: true,
            release_after: Duration::from_secs(5),
            ask_timeout: Duration::from_secs(8),
        }
    }
}

impl Settings {
    pub fn policy(&self, vehicle: &str) -> Takeover {
        self.vehicles.get(vehicle).copied().unwrap_or(self.takeover)
    }
}

/// What the arbiter says of a call from another site.
pub(crate) enum Screen {
    /// Not a vehicle's, or allowed: carry it out.
    Pass,
    /// Refused, with the reason.
    Refuse(String),
    /// A method of a vehicle's `arbitration` object: [`Arbiter::arbitrate`] answers it.
    Arbitrate(String),
}

/// Where an outcome goes: a local call's responder or a query's reply.
pub(crate) type Reply = Box<dyn FnOnce(CallOutcome) + Send>;

struct Vehicle {
    object: Guid,
    /// The vehicle's own object (its `control`, `gcs_in_control`; its control methods).
    vehicle: Guid,
    /// Whether the vehicle granted this site control through MAVLink's operator-control
    /// protocol (`gcs.rs`): given back when no operator here holds it any more.
    granted: bool,
    control: Control,
    /// The pending takeover's caller, answered when the holder does (or the ask times out).
    asking: Option<Reply>,
}

#[derive(Default)]
struct State {
    vehicles: HashMap<String, Vehicle>,
    epoch: u64,
    watch: Option<PathWatch>,
    subs: Vec<SubscriptionId>,
}

struct Inner {
    ds: DataServer,
    settings: Settings,
    /// This site's own operator: the caller of the methods called here, not over Zenoh.
    local: Caller,
    state: Mutex<State>,
}

/// A site's arbiter; cloning shares it.
#[derive(Clone)]
pub struct Arbiter {
    inner: Arc<Inner>,
}

impl Arbiter {
    /// Starts arbitrating the vehicles under `root.vehicles`, those there now and those to
    /// come.
    pub fn start(ds: &DataServer, settings: Settings, local: Caller) -> Result<Arbiter, String> {
        let inner = Arc::new(Inner {
            ds: ds.clone(),
            settings,
            local,
            state: Mutex::new(State::default()),
        });
        let weak = Arc::downgrade(&inner);
        let watch = ds
            .watch_object(ds.root(), &["vehicles"], None, move |e| {
                if e.kind == Kind::New
                    && let Some(inner) = weak.upgrade()
                {
                    Arbiter { inner }.follow(e.object);
                }
            })
            .map_err(|e| format!("control arbitration: {e}"))?;
        inner.state.lock().watch = Some(watch);
        Ok(Arbiter { inner })
    }

    /// Ends the watches (the `arbitration` objects stay, their methods answer "stopped").
    pub fn stop(&self) {
        let (watch, subs) = {
            let mut st = self.inner.state.lock();
            (st.watch.take(), std::mem::take(&mut st.subs))
        };
        drop(watch);
        for s in subs {
            self.inner.ds.unsubscribe(s);
        }
    }

    fn follow(&self, vehicles: Guid) {
        let weak = Arc::downgrade(&self.inner);
        let sub = self.inner.ds.subscribe(Topic::Children { object: vehicles }, move |n| {
            if let Some(inner) = weak.upgrade() {
                Arbiter { inner }.vehicle_event(n);
            }
        });
        if let Ok(id) = sub {
            self.inner.state.lock().subs.push(id);
        }
    }

    fn vehicle_event(&self, n: &Notification) {
        let Subject::Child { guid, name, .. } = &n.subject else { return };
        match n.kind {
            Kind::New => self.add_vehicle(*guid, name),
            Kind::Deleted => {
                self.inner.state.lock().vehicles.remove(&**name);
            }
            _ => {}
        }
    }

    fn add_vehicle(&self, vehicle: Guid, name: &str) {
        let ds = &self.inner.ds;
        let object = match ds.find_child(vehicle, OBJECT) {
            Ok(Some(g)) => g,
            _ => match ds.create_object(vehicle, ObjectInfo::new(OBJECT, OBJECT)) {
                Ok(g) => g,
                Err(_) => return,
            },
        };
        let policy = self.inner.settings.policy(name);
        let control = Control::new(policy, self.inner.settings.open_when_free);
        let string = || PropMeta::typed(ValueKind::String);
        for (prop, desc) in [
            ("holder", "The operator in control, empty when none"),
            ("requested_by", "An operator asking the holder for a takeover, empty when none"),
            ("policy", "What a takeover does: allowed, denied or ask (the holder answers)"),
        ] {
            let _ = ds.create_property(object, prop, Value::str(""), string().describe(desc));
        }
        let _ = ds.create_property(
            object,
            "holder_connected",
            Value::Bool(false),
            PropMeta::typed(ValueKind::Bool).describe("The holder's site is connected"),
        );
        let methods = [
            MethodSpec::new("request").describe("Take control of a vehicle nobody holds"),
            MethodSpec::new("release").describe("Give control back"),
            MethodSpec::new("takeover")
                .describe("Take control from its holder, as the vehicle's policy says"),
            MethodSpec::new("answer")
                .param(ParamSpec::new("accept", ValueKind::Bool))
                .describe("The holder's answer to a takeover it is asked for"),
        ];
        for spec in methods {
            let method = spec.name.as_str().to_string();
            let (weak, vname) = (Arc::downgrade(&self.inner), name.to_string());
            let _ = ds.publish_method(object, spec, move |call: Call| {
                let Some(inner) = weak.upgrade() else {
                    call.responder.fail("control arbitration has stopped");
                    return;
                };
                let me = Arbiter { inner };
                let caller = me.inner.local.clone();
                let responder = call.responder;
                me.arbitrate(
                    &vname,
                    &method,
                    &call.args,
                    caller,
                    None,
                    Box::new(move |o| {
                        responder.reply(o);
                    }),
                );
            });
        }
        // Another ground station taking or leaving a vehicle that speaks MAVLink's
        // operator-control protocol changes its `control`: the holder shown follows.
        let (weak, vname) = (Arc::downgrade(&self.inner), name.to_string());
        let sub = ds.subscribe(Topic::property_names(vehicle, &["control"]), move |_| {
            if let Some(inner) = weak.upgrade() {
                let me = Arbiter { inner };
                let st = me.inner.state.lock();
                if let Some(v) = st.vehicles.get(&vname) {
                    me.publish(v);
                }
            }
        });
        let mut st = self.inner.state.lock();
        if let Ok(id) = sub {
            st.subs.push(id);
        }
        let v = st.vehicles.entry(name.to_string()).or_insert(Vehicle {
            object,
            vehicle,
            granted: false,
            control,
            asking: None,
        });
        v.object = object;
        v.vehicle = vehicle;
        self.publish(v);
    }

    /// What to do with a call from another site to the object at `path`.
    pub(crate) fn screen(&self, path: &[String], method: &str, caller: &Caller) -> Screen {
        let [first, vehicle, rest @ ..] = path else { return Screen::Pass };
        if first != "vehicles" {
            return Screen::Pass;
        }
        let st = self.inner.state.lock();
        let Some(v) = st.vehicles.get(vehicle) else { return Screen::Pass };
        if rest.len() == 1 && rest[0] == OBJECT {
            return Screen::Arbitrate(vehicle.clone());
        }
        if rest.is_empty() && matches!(method, "request_control" | "release_control") {
            return Screen::Refuse(format!(
                "control of {vehicle} is arbitrated by its adapter: call \
                 {vehicle}.{OBJECT}.request(), release() or takeover()"
            ));
        }
        if let Some(gcs) = crate::gcs::foreign_holder(&self.inner.ds, v.vehicle) {
            return Screen::Refuse(crate::gcs::held_elsewhere(vehicle, &gcs));
        }
        match v.control.command(caller, vehicle) {
            Ok(()) => Screen::Pass,
            Err(reason) => Screen::Refuse(reason),
        }
    }

    /// Carries out `method` of `vehicle`'s arbitration object for `caller`; `reply` gets the
    /// outcome (later, for a takeover the holder is asked for). `limit`: the caller's own
    /// timeout, which an ask must end before.
    pub(crate) fn arbitrate(
        &self,
        vehicle: &str,
        method: &str,
        args: &[Value],
        caller: Caller,
        limit: Option<Duration>,
        reply: Reply,
    ) {
        if let Some(ask) = self.ask_vehicle_first(vehicle, method) {
            // The vehicle decides first (MAVLink's operator-control protocol); then the rules
            // here choose among this site's operators as for any vehicle.
            let (me, vehicle, method, args) =
                (self.clone(), vehicle.to_string(), method.to_string(), args.to_vec());
            let operator = caller.operator.clone();
            return crate::gcs::request(
                &self.inner.ds,
                ask,
                &operator,
                move |outcome| match outcome {
                    CallOutcome::Accepted(_) => {
                        if let Some(v) = me.inner.state.lock().vehicles.get_mut(&vehicle) {
                            v.granted = true;
                        }
                        me.arbitrate_here(&vehicle, &method, &args, caller, limit, reply);
                        me.give_back_if_free(&vehicle);
                    }
                    other => reply(crate::gcs::refusal(&vehicle, other)),
                },
            );
        }
        self.arbitrate_here(vehicle, method, args, caller, limit, reply);
        self.give_back_if_free(vehicle);
    }

    /// The vehicle to ask first for `method`: a request or a takeover of a
    /// vehicle that speaks MAVLink's operator-control protocol while no operator of this site
    /// holds it (once one does, the vehicle's control is this site's already).
    fn ask_vehicle_first(&self, vehicle: &str, method: &str) -> Option<Guid> {
        if !matches!(method, "request" | "takeover") {
            return None;
        }
        let st = self.inner.state.lock();
        let v = st.vehicles.get(vehicle)?;
        let free = v.control.holder.is_none();
        (free && crate::gcs::speaks_protocol(&self.inner.ds, v.vehicle)).then_some(v.vehicle)
    }

    /// Gives the vehicle's control back (MAVLink's operator-control protocol) once no
    /// operator of this site holds it.
    fn give_back_if_free(&self, vehicle: &str) {
        let target = {
            let mut st = self.inner.state.lock();
            let Some(v) = st.vehicles.get_mut(vehicle) else { return };
            if !v.granted || v.control.holder.is_some() {
                return;
            }
            v.granted = false;
            v.vehicle
        };
        crate::gcs::release(&self.inner.ds, target);
    }

    fn arbitrate_here(
        &self,
        vehicle: &str,
        method: &str,
        args: &[Value],
        caller: Caller,
        limit: Option<Duration>,
        reply: Reply,
    ) {
        let mut replies: Vec<(Reply, CallOutcome)> = Vec::new();
        let accepted = || CallOutcome::Accepted(Vec::new());
        {
            let mut st = self.inner.state.lock();
            let Some(v) = st.vehicles.get_mut(vehicle) else {
                drop(st);
                return reply(CallOutcome::NoSuchObject);
            };
            let c = &mut v.control;
            let outcome = match method {
                "request" => c.request(&caller, vehicle).map(|()| accepted()),
                "release" => c.release(&caller, vehicle).map(|next| {
                    if let (Some(_), Some(r)) = (next, v.asking.take()) {
                        replies.push((r, accepted()));
                    }
                    accepted()
                }),
                "takeover" => match c.takeover(&caller, vehicle) {
                    Ok(Grant::Granted) => Ok(accepted()),
                    Ok(Grant::Asked) => {
                        if let Some(old) = v.asking.replace(reply) {
                            replies.push((old, CallOutcome::Refused("asked again".into())));
                        }
                        let mut wait = self.inner.settings.ask_timeout;
                        if let Some(l) = limit {
                            wait = wait.min(l.mul_f64(0.9));
                        }
                        self.ask_timer(vehicle, caller, wait);
                        self.publish(v);
                        drop(st);
                        return answer_all(replies);
                    }
                    Err(e) => Err(e),
                },
                "answer" => match args.first().and_then(Value::as_bool) {
                    None => Err("answer(accept) takes true or false".into()),
                    Some(accept) => c.answer(&caller, accept, vehicle).map(|a| {
                        let (asker, outcome) = match a {
                            Answer::Handed(_) => (v.asking.take(), accepted()),
                            Answer::Kept(_) => (
                                v.asking.take(),
                                CallOutcome::Refused(format!(
                                    "{} denied the takeover of {vehicle}",
                                    caller.operator
                                )),
                            ),
                        };
                        if let Some(r) = asker {
                            replies.push((r, outcome));
                        }
                        accepted()
                    }),
                },
                _ => {
                    drop(st);
                    return reply(CallOutcome::NoSuchMethod);
                }
            };
            self.publish(v);
            replies.push((reply, outcome.unwrap_or_else(CallOutcome::Refused)));
        }
        answer_all(replies);
    }

    fn ask_timer(&self, vehicle: &str, asker: Caller, wait: Duration) {
        let (weak, vehicle) = (Arc::downgrade(&self.inner), vehicle.to_string());
        self.inner.ds.run_after(wait, None, move || {
            let Some(inner) = weak.upgrade() else { return };
            let me = Arbiter { inner };
            let mut st = me.inner.state.lock();
            let Some(v) = st.vehicles.get_mut(&vehicle) else { return };
            if !v.control.ask_expired(&asker) {
                return;
            }
            let pending = v.asking.take();
            let holder = v.control.holder_name().to_string();
            me.publish(v);
            drop(st);
            if let Some(r) = pending {
                r(CallOutcome::Refused(format!(
                    "{holder} did not answer the takeover of {vehicle} within {:.0} s",
                    wait.as_secs_f64()
                )));
            }
        });
    }

    /// A site appeared (`up`) or disappeared: a holder's release timer starts or stops.
    pub fn site(&self, site: &str, up: bool) {
        let mut st = self.inner.state.lock();
        st.epoch += 1;
        let epoch = st.epoch;
        let mut timers = Vec::new();
        let mut withdrawn = Vec::new();
        for (name, v) in st.vehicles.iter_mut() {
            if up {
                v.control.site_back(site);
            } else {
                let (holder, asker) = v.control.site_gone(site, epoch);
                if holder {
                    timers.push(name.clone());
                }
                if asker.is_some()
                    && let Some(r) = v.asking.take()
                {
                    withdrawn.push(r);
                }
            }
            self.publish(v);
        }
        drop(st);
        for r in withdrawn {
            r(CallOutcome::Failed("the asking site is gone".into()));
        }
        for vehicle in timers {
            let weak = Arc::downgrade(&self.inner);
            self.inner.ds.run_after(self.inner.settings.release_after, None, move || {
                if let Some(inner) = weak.upgrade() {
                    Arbiter { inner }.release_timer(&vehicle, epoch);
                }
            });
        }
    }

    fn release_timer(&self, vehicle: &str, epoch: u64) {
        let mut st = self.inner.state.lock();
        let Some(v) = st.vehicles.get_mut(vehicle) else { return };
        let Some((_, next)) = v.control.release_timer(epoch) else { return };
        let pending = if next.is_some() { v.asking.take() } else { None };
        self.publish(v);
        drop(st);
        if let Some(r) = pending {
            r(CallOutcome::Accepted(Vec::new()));
        }
        self.give_back_if_free(vehicle);
    }

    /// The holder of `vehicle` (empty when none), for tools and tests.
    pub fn holder(&self, vehicle: &str) -> Option<String> {
        let st = self.inner.state.lock();
        st.vehicles.get(vehicle).map(|v| v.control.holder_name().to_string())
    }

    /// Writes a vehicle's control into its `arbitration` object (under the state's lock, so
    /// the world model sees the changes in the order they happened; a write only queues).
    fn publish(&self, v: &Vehicle) {
        let (ds, c) = (&self.inner.ds, &v.control);
        let asker = c.requested_by.as_ref().map_or("", |r| r.operator.as_str());
        let foreign = crate::gcs::foreign_holder(ds, v.vehicle);
        let holder = foreign.as_deref().unwrap_or(c.holder_name());
        let _ = ds.set(v.object, "holder", Value::str(holder));
        let _ = ds.set(v.object, "requested_by", Value::str(asker));
        let _ = ds.set(v.object, "policy", Value::str(c.takeover.name()));
        let connected = c.holder.is_some() && c.gone.is_none();
        let _ = ds.set(v.object, "holder_connected", Value::Bool(connected));
    }
}

fn answer_all(replies: Vec<(Reply, CallOutcome)>) {
    for (r, o) in replies {
        r(o);
    }
}

impl Arbiter {
    /// Follows the sites' liveliness tokens (`mocu/*/alive`; those there now count as
    /// appearing), so that a holder's departure starts its release timer.
    pub(crate) fn watch_sites(&self, session: &zenoh::Session) -> Result<(), String> {
        use zenoh::Wait;
        let weak = Arc::downgrade(&self.inner);
        session
            .liveliness()
            .declare_subscriber("mocu/*/alive")
            .history(true)
            .callback(move |s| {
                let up = s.kind() == zenoh::sample::SampleKind::Put;
                if let (Some(crate::keys::Key::Alive { site }), Some(inner)) =
                    (crate::keys::parse(s.key_expr().as_str()), weak.upgrade())
                {
                    Arbiter { inner }.site(&site, up);
                }
            })
            .background()
            .wait()
            .map_err(|e| format!("zenoh: {e}"))
    }
}

/// The arbitration settings of a `distrib` spec: `None` when `control = false`, or when the
/// site shares no `vehicles` and `control` is not set. The settings are checked either way:
/// a misspelt policy is an error, not a setting silently ignored.
pub fn settings_from(
    spec: &mocu_host::ModuleSpec,
    share: &[String],
) -> Result<Option<Settings>, String> {
    let shares_vehicles =
        share.iter().any(|s| crate::object_path(s).first().is_some_and(|f| f == "vehicles"));
    let on = spec.bool_or("control", shares_vehicles).map_err(|e| e.to_string())?;
    let d = Settings::default();
    let policy = |key: &str, text: &str| {
        Takeover::parse(text).ok_or_else(|| {
            format!("`{key}`: `{text}` is not a takeover policy (allowed, denied, ask)")
        })
    };
    let takeover = policy(
        "takeover",
        &spec.str_or("takeover", d.takeover.name()).map_err(|e| e.to_string())?,
    )?;
    let mut vehicles = HashMap::new();
    for p in [Takeover::Allowed, Takeover::Denied, Takeover::Ask] {
        let key = format!("takeover_{}", p.name());
        for v in crate::module::names(spec, &key)? {
            if let Some(other) = vehicles.insert(v.clone(), p).filter(|o| *o != p) {
                return Err(format!("`{key}`: {v} is also listed as takeover_{}", other.name()));
            }
        }
    }
    let open_when_free = match spec.str_or("free", "open").map_err(|e| e.to_string())?.as_str() {
        "open" => true,
        "closed" => false,
        other => return Err(format!("`free`: `{other}` is neither `open` nor `closed`")),
    };
    let settings = Settings {
        takeover,
        vehicles,
        open_when_free,
        release_after: crate::module::millis(spec, "release_after_ms", 5_000)?,
        ask_timeout: crate::module::millis(spec, "ask_timeout_ms", 8_000)?,
    };
    Ok(on.then_some(settings))
}

#[cfg(test)]
#[path = "arbiter_tests.rs"]
mod tests;
