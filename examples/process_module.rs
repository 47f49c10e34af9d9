//! An out-of-process module in Rust (docs/modules.md): a program of its own that joins the
//! OCU's world model over the distributed DataServer, as `examples/geofence.py` does in
//! Python. It mirrors the vehicles the OCU shares and publishes `root.<module>` with how
//! many there are and their names, which the OCU mirrors in turn (layouts, `--dump` and the
//! recorder see it like any object).
//!
//! ```toml
//! [modules.fleet]
//! kind = "process"
//! command = ["target/release/examples/process_module"]   # cargo build --release --example process_module
//! ```
//!
//! `mocu run` starts it with `MOCU_CONNECT` (the OCU's endpoint) and `MOCU_MODULE` (its
//! name) and restarts it if it stops.

use mocu_dataserver::{DataServer, Guid, Kind, ObjectInfo, SubscriptionId, Topic, Value};
use mocu_distrib::{Config, Distrib};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// The module running: its own DataServer joined to the OCU's.
struct Fleet {
    _distrib: Distrib,
    ds: DataServer,
    subs: Arc<Mutex<Vec<SubscriptionId>>>,
    _watch: mocu_dataserver::PathWatch,
}

/// Joins `endpoint` as site `name`, sharing `root.<name>`.
fn join(endpoint: &str, name: &str) -> Result<Fleet, String> {
    let ds = DataServer::default();
    let out =
        ds.create_object(ds.root(), ObjectInfo::new(name, "fleet")).map_err(|e| e.to_string())?;
    ds.set(out, "vehicles", Value::Int(0)).map_err(|e| e.to_string())?;
    ds.set(out, "names", Value::str("")).map_err(|e| e.to_string())?;
    let config = Config {
        site: name.to_string(),
        connect: vec![endpoint.to_string()],
        share: vec![name.to_string()],
        ..Config::default()
    };
    let distrib = Distrib::start(&ds, &config, None)?;
    // The mirrored `root.vehicles`, when it appears: its children, counted at each change.
    let (ds2, subs) = (ds.clone(), Arc::new(Mutex::new(Vec::new())));
    let subs2 = subs.clone();
    let watch = ds
        .watch_object(ds.root(), &["vehicles"], None, move |e| {
            if e.kind != Kind::New {
                return;
            }
            let (ds3, vehicles) = (ds2.clone(), e.object);
            let sub = ds2.subscribe(Topic::Children { object: vehicles }, move |_| {
                count(&ds3, vehicles, out);
            });
            if let Ok(s) = sub {
                subs2.lock().unwrap().push(s);
            }
        })
        .map_err(|e| e.to_string())?;
    Ok(Fleet { _distrib: distrib, ds, subs, _watch: watch })
}

fn count(ds: &DataServer, vehicles: Guid, out: Guid) {
    let mut names: Vec<String> = ds
        .children(vehicles)
        .unwrap_or_default()
        .into_iter()
        .filter_map(|v| ds.info(v).ok().map(|i| i.name.to_string()))
        .collect();
    names.sort();
    let _ = ds.set(out, "vehicles", Value::Int(names.len() as i64));
    let _ = ds.set(out, "names", Value::str(&names.join(", ")));
}

impl Drop for Fleet {
    fn drop(&mut self) {
        let subs = std::mem::take(&mut *self.subs.lock().unwrap());
        for s in subs {
            self.ds.unsubscribe(s);
        }
    }
}

fn main() {
    let Ok(endpoint) = std::env::var("MOCU_CONNECT") else {
        eprintln!(
            "process_module: run me from a profile (kind = \"process\"): MOCU_CONNECT is not set"
        );
        std::process::exit(2);
    };
    let name = std::env::var("MOCU_MODULE").unwrap_or_else(|_| "fleet".into());
    match join(&endpoint, &name) {
        Ok(_fleet) => loop {
            // The work happens in the DataServer's callbacks; this thread only keeps the
            // process (and its Zenoh session) alive until the OCU stops it.
            std::thread::park_timeout(Duration::from_secs(3600));
        },
        Err(e) => {
            eprintln!("process_module: {e}");
            std::process::exit(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mocu_dataserver::{DottedPath, PathEvent};

    #[test]
    fn a_rust_process_module_mirrors_the_ocus_vehicles_and_the_ocu_mirrors_what_it_publishes() {
        let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
        let endpoint = format!("tcp/127.0.0.1:{port}");
        // The OCU: its world model with two vehicles, shared on a loopback endpoint.
        let ocu = DataServer::default();
        let vs = ocu.create_object(ocu.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
        for v in ["usv1", "usv2"] {
            ocu.create_object(vs, ObjectInfo::new(v, "usv")).unwrap();
        }
        let config = Config {
            site: "ocu".into(),
            listen: vec![endpoint.clone()],
            share: vec!["vehicles".into()],
            ..Config::default()
        };
        let _site = Distrib::start(&ocu, &config, None).unwrap();
        let (tx, rx) = crossbeam_channel::unbounded::<PathEvent>();
        let path = DottedPath::parse("fleet.names").unwrap();
        let _w = ocu
            .watch_path(path, None, move |e| {
                let _ = tx.send(e.clone());
            })
            .unwrap();
        let _module = join(&endpoint, "fleet").unwrap();
        // What the module published, mirrored back into the OCU (bounded: fails, never hangs).
        loop {
            let e = rx.recv_timeout(Duration::from_secs(30)).expect("root.fleet.names never came");
            if e.value == Some(Value::str("usv1, usv2")) {
                break;
            }
        }
    }
}
