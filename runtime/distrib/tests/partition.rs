//! A partition healed: an adapter and an OCU on loopback, their only link through a TCP
//! relay this test can silence (bytes swallowed, connections left open, as a cable cut or
//! a radio out of range would). The OCU finds the adapter gone when the lease passes and
//! shows its vehicle stale; when the relay carries bytes again the link comes back, the
//! snapshot brings what changed meanwhile and the same objects recover: no duplicates.

mod support;

use mocu_dataserver::{DataServer, ObjectInfo, Value};
use mocu_distrib::{Config, Distrib};
use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use support::{PATIENCE, free_port, until, watch};

/// Relays `listen` → `target`; while `cut`, every byte either way is swallowed.
struct Relay {
    cut: Arc<AtomicBool>,
    port: u16,
}

impl Relay {
    fn start(target: u16) -> Relay {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let cut = Arc::new(AtomicBool::new(false));
        let c = cut.clone();
        std::thread::spawn(move || {
            for inbound in listener.incoming().flatten() {
                let Ok(outbound) = TcpStream::connect(("127.0.0.1", target)) else { continue };
                for (from, to) in [
                    (inbound.try_clone().unwrap(), outbound.try_clone().unwrap()),
                    (outbound, inbound),
                ] {
                    let c = c.clone();
                    std::thread::spawn(move || pump(from, to, &c));
                }
            }
        });
        Relay { cut, port }
    }
}

fn pump(mut from: TcpStream, mut to: TcpStream, cut: &AtomicBool) {
    let mut buf = [0u8; 16 * 1024];
    while let Ok(n) = from.read(&mut buf) {
        if n == 0 || (!cut.load(Ordering::Relaxed) && to.write_all(&buf[..n]).is_err()) {
            break;
        }
    }
    let _ = to.shutdown(Shutdown::Both);
}

#[test]
fn a_partition_shows_the_vehicle_stale_and_healed_it_recovers_without_duplicates() {
    let port = free_port();
    let relay = Relay::start(port);
    let lease = Duration::from_millis(1000);

    let a = DataServer::default();
    let vs = a.create_object(a.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let v = a.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    a.set(v, "stale", Value::Bool(false)).unwrap();
    a.set(v, "speed", Value::Float(1.0)).unwrap();
    let ac = Config {
        site: "adapter".into(),
        listen: vec![format!("tcp/127.0.0.1:{port}")],
        share: vec!["vehicles".into()],
        lease,
        ..Config::default()
    };
    let da = Distrib::start(&a, &ac, None).unwrap();

    let b = DataServer::default();
    let (_ws, stale) = watch(&b, "vehicles.usv1.stale");
    let (_wv, speed) = watch(&b, "vehicles.usv1.speed");
    let bc = Config {
        site: "ocu".into(),
        connect: vec![format!("tcp/127.0.0.1:{}", relay.port)],
        lease,
        ..Config::default()
    };
    let db = Distrib::start(&b, &bc, None).unwrap();
    assert!(db.wait_snapshots(1, PATIENCE));
    until(&speed, "speed before the partition", &Value::Float(1.0));
    let before = b.resolve(&["vehicles", "usv1"]).unwrap();

    // The partition: the OCU shows the vehicle stale; what changes meanwhile does not pass.
    relay.cut.store(true, Ordering::Relaxed);
    until(&stale, "stale during the partition", &Value::Bool(true));
    a.set(v, "speed", Value::Float(7.5)).unwrap();

    // Healed: the same object, fresh, with the value it missed; one vehicle, not two.
    relay.cut.store(false, Ordering::Relaxed);
    until(&stale, "stale after the partition healed", &Value::Bool(false));
    until(&speed, "speed after the partition healed", &Value::Float(7.5));
    assert!(db.wait_snapshots(2, PATIENCE), "the adapter's snapshot taken again");
    assert_eq!(b.resolve(&["vehicles", "usv1"]), Some(before), "the same mirrored object");
    let bvs = b.resolve(&["vehicles"]).unwrap();
    assert_eq!(b.children(bvs).unwrap(), vec![before], "no duplicate vehicle");
    drop((db, da));
}
