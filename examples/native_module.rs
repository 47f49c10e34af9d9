//! A native Rust module: `fuel_watch` keeps `root.fuel_watch` up to date with the vehicles
//! whose fuel is under a threshold. It talks to the rest of the OCU only through the
//! DataServer (subscriptions in, properties out), on its own serial executor, and is
//! registered in a module registry beside the built-in simulator, as a project would
//! register it in its own build of `mocu` (`[modules.fuel_watch] threshold = 0.3`).
//!
//! ```sh
//! cargo run --example native_module        # the simulator's vehicles, watched for 5 s
//! ```

use mocu_dataserver::{
    DataServer, Guid, Kind, Notification, ObjectInfo, PathWatch, Subject, SubscriptionId, Topic,
    Value,
};
use mocu_host::{Module, ModuleContext, ModuleHost, ModuleSpec, Registry};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// The module: its setting, and what it keeps of the world model.
struct FuelWatch {
    threshold: f64,
    state: Arc<Mutex<Watched>>,
}

#[derive(Default)]
struct Watched {
    /// Fuel by vehicle name (0 to 1).
    fuel: BTreeMap<String, f64>,
    out: Option<Guid>,
    ds: Option<DataServer>,
    subs: Vec<SubscriptionId>,
    watch: Option<PathWatch>,
}

impl FuelWatch {
    fn new(spec: &ModuleSpec) -> Result<FuelWatch, String> {
        let threshold = spec.f64_or("threshold", 0.3).map_err(|e| e.to_string())?;
        if !(0.0..=1.0).contains(&threshold) {
            return Err(format!("`threshold` must be 0 to 1, got {threshold}"));
        }
        Ok(FuelWatch { threshold, state: Arc::default() })
    }
}

/// Writes `root.fuel_watch`: `low` (the names, comma-separated) and `count`.
fn publish(ds: &DataServer, w: &Watched, threshold: f64) {
    let Some(out) = w.out else { return };
    let low: Vec<&str> =
        w.fuel.iter().filter(|(_, f)| **f < threshold).map(|(n, _)| n.as_str()).collect();
    let _ = ds.set(out, "low", Value::str(&low.join(", ")));
    let _ = ds.set(out, "count", Value::Int(low.len() as i64));
}

impl Module for FuelWatch {
    fn start(&mut self, ctx: &ModuleContext) -> Result<(), String> {
        let ds = ctx.ds.clone();
        let out = ds
            .create_object(ds.root(), ObjectInfo::new("fuel_watch", "fuel_watch"))
            .map_err(|e| e.to_string())?;
        {
            let mut w = self.state.lock().unwrap();
            (w.out, w.ds) = (Some(out), Some(ds.clone()));
        }
        let (state, threshold, exec) = (self.state.clone(), self.threshold, ctx.executor.clone());
        // root.vehicles may appear later (system discovery): watch for it, then for its
        // children, then for each child's `fuel`; every callback on this module's executor.
        let watch = ctx
            .ds
            .watch_object(ctx.ds.root(), &["vehicles"], Some(&ctx.executor), move |e| {
                if e.kind != Kind::New {
                    return;
                }
                let (ds2, state2, exec2) = (ds.clone(), state.clone(), exec.clone());
                let children = Topic::Children { object: e.object };
                let sub = ds.subscribe_on(&exec, children, move |n: &Notification| {
                    let Subject::Child { guid, name, .. } = &n.subject else { return };
                    if n.kind != Kind::New {
                        return;
                    }
                    let (ds3, state3, name) = (ds2.clone(), state2.clone(), name.to_string());
                    let fuel = Topic::property_names(*guid, &["fuel"]);
                    let sub = ds2.subscribe_on(&exec2, fuel, move |n: &Notification| {
                        let Subject::Property { value, .. } = &n.subject else { return };
                        let mut w = state3.lock().unwrap();
                        match value.as_ref().and_then(Value::as_f64) {
                            Some(f) => w.fuel.insert(name.clone(), f),
                            None => w.fuel.remove(&name),
                        };
                        publish(&ds3, &w, threshold);
                    });
                    if let Ok(s) = sub {
                        state2.lock().unwrap().subs.push(s);
                    }
                });
                if let Ok(s) = sub {
                    state.lock().unwrap().subs.push(s);
                }
            })
            .map_err(|e| e.to_string())?;
        self.state.lock().unwrap().watch = Some(watch);
        Ok(())
    }

    /// Ends the watch and the subscriptions with the lock released (ending one waits for
    /// its running callback, which may need the lock).
    fn stop(&mut self) {
        let (watch, subs, ds) = {
            let mut w = self.state.lock().unwrap();
            (w.watch.take(), std::mem::take(&mut w.subs), w.ds.take())
        };
        drop(watch);
        if let Some(ds) = ds {
            for s in subs {
                ds.unsubscribe(s);
            }
        }
    }
}

/// A registry with the built-in simulator and this module.
fn registry() -> Registry {
    let mut r = Registry::new();
    mocu_sim::register(&mut r);
    r.register("fuel_watch", |spec| Ok(Box::new(FuelWatch::new(spec)?) as Box<dyn Module>));
    r
}

fn main() {
    let ds = DataServer::default();
    let mut host = ModuleHost::new(ds.clone(), registry());
    let specs = [ModuleSpec::new("sim"), ModuleSpec::new("fuel_watch").with("threshold", 0.8)];
    for e in host.start_all(&specs) {
        eprintln!("native_module: {e}");
    }
    for _ in 0..5 {
        std::thread::sleep(std::time::Duration::from_secs(1));
        let out = ds.resolve(&["fuel_watch"]).and_then(|g| ds.try_get(g, "low".into()));
        println!("fuel under 80%: {}", out.as_ref().and_then(Value::as_str).unwrap_or("—"));
    }
    host.stop_all();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_native_module_registered_beside_the_simulator_watches_its_vehicles() {
        let ds = DataServer::default();
        let mut host = ModuleHost::new(ds.clone(), registry());
        let sim = ModuleSpec::new("sim").with("seed", 7).with("appear_every", 0.0);
        let watch = ModuleSpec::new("fuel_watch").with("threshold", 1.0);
        assert!(host.start_all(&[sim, watch]).is_empty());
        // Every simulated vehicle has less than a full tank: all four are listed, waiting
        // on each change of the module's output (bounded: a failure fails, never hangs).
        let out = ds.resolve(&["fuel_watch"]).expect("the module's object");
        let (tx, rx) = std::sync::mpsc::channel();
        let sub = ds
            .subscribe(Topic::property_names(out, &["count"]), move |n| {
                if let Subject::Property { value: Some(v), .. } = &n.subject {
                    let _ = tx.send(v.as_i64().unwrap_or(0));
                }
            })
            .unwrap();
        let limit = std::time::Duration::from_secs(30);
        while rx.recv_timeout(limit).expect("the count never reached 4") < 4 {}
        ds.unsubscribe(sub);
        let low = ds.try_get(out, "low".into()).unwrap();
        assert_eq!(low, Value::str("uav1, ugv1, usv1, usv2"));
        // A bad setting is refused with the reason, and the rest keeps running.
        let bad = ModuleSpec::new("fuel_watch").named("other").with("threshold", 2.0);
        let err = host.start(&bad).unwrap_err().to_string();
        assert!(err.contains("`threshold` must be 0 to 1"), "{err}");
        host.stop_all();
    }
}
