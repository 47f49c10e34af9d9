//! Staleness: a widget is stale when the data it shows is old, never merely unchanged.
//!
//! Each widget gets an output `stale` (a bool property of the widget object, drawn by the
//! renderer as a veil and a STALE tag): true while any vehicle it reads from says its data
//! is old — the vehicle's `stale` or `link_lost` flag, which the vehicle's protocol module
//! keeps (the simulator and MAVLink raise both when the link is lost, lower them when it is
//! back). It is an ordinary compiled expression over those flags, so it follows them through
//! the same path watches as every other output: no timer, no polling, nothing to do while
//! nothing changes. A vehicle is the object `root.vehicles.<name>` a path goes through, or a
//! template's object (`for each v in root.vehicles …`). A stopped boat with a good link
//! writes the same speed over and over and is never stale.

use crate::graph::{Shared, resolve};
use mocu_dataserver::DataServer;
use mocu_jit as jit;
use mocu_lower::{Base, Lowerer, Source};
use mocu_value::{Guid, Value};
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Duration;

/// Flags of a vehicle that say its data is old.
pub const FLAGS: [&str; 2] = ["stale", "link_lost"];

/// The vehicles (base and object names) `slots` read from.
fn vehicles(slots: &[(Source, jit::Ty)]) -> Vec<(Base, Vec<String>)> {
    let mut out: Vec<(Base, Vec<String>)> = Vec::new();
    for (src, _) in slots {
        let Source::Path { base, objects, .. } = src else { continue };
        let v = match base {
            Base::Root if objects.len() >= 2 && objects[0] == "vehicles" => {
                (Base::Root, objects[..2].to_vec())
            }
            Base::Var(name) => (Base::Var(name.clone()), Vec::new()),
            _ => continue,
        };
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

/// The `stale` output of a widget whose outputs were lowered with `lw`, reading `through`
/// (its slots and the vehicle paths it reads through shared `let`s, `graph/lets.rs`):
/// absent flags count as fresh. `None` when the widget reads no vehicle.
pub(crate) fn widget_stale(lw: &mut Lowerer, through: &[(Source, jit::Ty)]) -> Option<jit::Expr> {
    let mut out: Option<jit::Expr> = None;
    for (base, objects) in vehicles(through) {
        for flag in FLAGS {
            let src = Source::Path {
                base: base.clone(),
                objects: objects.clone(),
                property: flag.into(),
            };
            lw.slots.push((src, jit::Ty::Bool));
            let input = jit::Expr::Input((lw.slots.len() - 1) as u32, jit::Ty::Bool);
            let x = jit::Expr::Coalesce(Box::new(input), Box::new(jit::Expr::Bool(false)));
            out = Some(match out {
                None => x,
                Some(prev) => jit::Expr::Or(Box::new(prev), Box::new(x)),
            });
        }
    }
    out
}

/// Age: a widget is also stale — property `aged` — while one of the numbers or flags it
/// reads from a vehicle has received no write (an unchanged one counts:
/// `DataServer::received_at`) for that input's period ([`period`]: the schema's
/// `stale_after`, the vehicle's, or three periods of the rate its module declared). One delayed
/// call per widget on the server's clock, armed when the widget's data first arrives and
/// re-armed for the next deadline; once aged, a changed value makes it fresh at once, and the
/// check still comes back once per period ([`MIN_POLL`] at least), so that a publisher that
/// resumes with unchanged values (a stopped boat) makes it fresh too.
pub(crate) struct Age {
    /// (base, object names, property) of each input the age applies to.
    inputs: Vec<(Base, Vec<String>, String)>,
    instance: Option<Guid>,
    armed: bool,
    aged: bool,
}

/// Registers widget `g`'s age inputs (its numeric and boolean paths through a vehicle).
pub(crate) fn register(
    sh: &Arc<Shared>,
    g: Guid,
    slots: &[(Source, jit::Ty)],
    instance: Option<Guid>,
) {
    let mut inputs = Vec::new();
    for (src, ty) in slots {
        let Source::Path { base, objects, property } = src else { continue };
        let under_vehicle = match base {
            Base::Root => objects.len() >= 2 && objects[0] == "vehicles",
            Base::Var(_) => true,
            _ => false,
        };
        if under_vehicle
            && matches!(ty, jit::Ty::Num | jit::Ty::Bool)
            && !FLAGS.contains(&property.as_str())
        {
            inputs.push((base.clone(), objects.clone(), property.clone()));
        }
    }
    if !inputs.is_empty() {
        sh.ages.lock().insert(g, Age { inputs, instance, armed: false, aged: false });
    }
}

/// An output of `g` was written (its data changed): fresh, and the age check armed.
pub(crate) fn on_output(sh: &Arc<Shared>, g: Guid) {
    let arm = {
        let mut ages = sh.ages.lock();
        let Some(a) = ages.get_mut(&g) else { return };
        if a.aged {
            a.aged = false;
            let _ = sh.ds.set(g, "aged", Value::Bool(false));
        }
        !std::mem::replace(&mut a.armed, true)
    };
    if arm {
        check(sh, g);
    }
}

/// The vehicle object and the object of one input.
fn objects_of(
    ds: &DataServer,
    base: &Base,
    objects: &[String],
    instance: Option<Guid>,
) -> Option<(Guid, Guid)> {
    match base {
        Base::Root => {
            let v = resolve(ds, Guid::ROOT, &objects[..2])?;
            Some((v, resolve(ds, v, &objects[2..])?))
        }
        Base::Var(_) => {
            let v = instance?;
            Some((v, resolve(ds, v, objects)?))
        }
        _ => None,
    }
}

/// A value whose publisher declares a rate (`PropMeta::rate_hz`) and whose schema gives no
/// `stale_after` is stale after this many periods without a write.
pub const RATE_PERIODS: f64 = 3.0;

fn seconds(s: f64) -> Option<Duration> {
    (s.is_finite() && s > 0.0).then(|| Duration::from_secs_f64(s))
}

/// How long an input stays fresh, first found of: the schema's `stale_after` for the
/// property (by its object's type), the vehicle's own `stale_after`, and
/// [`RATE_PERIODS`] periods of the rate its publisher declared. `None`: it never ages.
fn period(sh: &Shared, vehicle: Guid, obj: Guid, property: &str) -> Option<Duration> {
    let ds = &sh.ds;
    if !sh.config.stale_after.is_empty()
        && let Ok(info) = ds.info(obj)
        && let Some(d) = sh.config.stale_after.get(&(info.kind.to_string(), property.to_string()))
    {
        return Some(*d);
    }
    if let Some(d) = ds.try_get(vehicle, "stale_after".into()).and_then(|v| v.as_f64()) {
        return seconds(d);
    }
    seconds(RATE_PERIODS / ds.meta(obj, property).ok()?.rate_hz?)
}

impl crate::LayoutConfig {
    /// The `stale_after` of every schema property that has one, by (object type, property).
    pub fn stale_after_from(schema: &mocu_language::Schema) -> HashMap<(String, String), Duration> {
        let mut out = HashMap::new();
        for (ty, t) in &schema.types {
            for (name, p) in &t.properties {
                if let Some(d) = p.stale_after.and_then(seconds) {
                    out.insert((ty.clone(), name.clone()), d);
                }
            }
        }
        out
    }
}

/// The shortest wait between two looks at an aged widget's inputs.
const MIN_POLL: Duration = Duration::from_millis(250);

/// Compares each input's last write with its vehicle's period; writes `aged` when that
/// changes; arms the next check (the earliest deadline, or one period while aged).
fn check(sh: &Arc<Shared>, g: Guid) {
    let ds = &sh.ds;
    let (inputs, instance) = {
        let ages = sh.ages.lock();
        let Some(a) = ages.get(&g) else { return };
        (a.inputs.clone(), a.instance)
    };
    if !ds.exists(g) {
        sh.ages.lock().remove(&g);
        return;
    }
    let now = ds.now();
    let (mut old, mut next): (bool, Option<Duration>) = (false, None);
    // While aged, the check comes back once per period of the aged inputs: a publisher that
    // resumes with unchanged values (a stopped boat whose link came back) changes no output,
    // so only a look at `received_at` can see that it is fresh again.
    let mut poll: Option<Duration> = None;
    for (base, objects, property) in &inputs {
        let Some((vehicle, obj)) = objects_of(ds, base, objects, instance) else { continue };
        let Some(p) = period(sh, vehicle, obj, property) else { continue };
        let Some(at) = ds.received_at(obj, property.as_str()).ok().flatten() else { continue };
        let age = now.saturating_duration_since(at);
        if age >= p {
            old = true;
            let p = p.max(MIN_POLL);
            poll = Some(poll.map_or(p, |n: Duration| n.min(p)));
            continue;
        }
        let wait = p - age;
        next = Some(next.map_or(wait, |n: Duration| n.min(wait)));
    }
    let changed = {
        let mut ages = sh.ages.lock();
        let Some(a) = ages.get_mut(&g) else { return };
        a.armed = if old { poll.is_some() } else { next.is_some() };
        std::mem::replace(&mut a.aged, old) != old
    };
    if changed {
        let _ = ds.set(g, "aged", Value::Bool(old));
    }
    let wait = if old { poll } else { next };
    if let Some(wait) = wait {
        let weak = Arc::downgrade(sh);
        ds.run_after(wait, Some(&sh.exec), move || {
            if let Some(sh) = weak.upgrade() {
                check(&sh, g);
            }
        });
    }
}
