//! Security of sites on loopback (docs/distribution.md, "Security"): mutual TLS with
//! certificates made for this test by the `openssl` command (a throwaway CA, never a real
//! key), Zenoh's access control over calls, and malformed samples counted and dropped.

mod support;

use mocu_dataserver::{
    CallOutcome, DataServer, Guid, MethodSpec, ObjectInfo, ParamSpec, Value, ValueKind,
};
use mocu_distrib::security::{Security, Tls, grants};
use mocu_distrib::{Config, Distrib};
use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;
use support::{PATIENCE, free_port, until, watch};
use zenoh::Wait;

/// A directory of PEM files: `ca`, and for each name a key and a certificate whose common
/// name is that name, signed by `ca` (or by a second CA, `rogue`, for `mallory`).
struct Certs {
    dir: PathBuf,
}

impl Certs {
    /// `test`: a directory of its own for each test (they run at once).
    fn make(test: &str, names: &[&str]) -> Certs {
        let pid = std::process::id();
        let dir = std::env::temp_dir().join(format!("mocu-distrib-certs-{pid}-{test}"));
        std::fs::create_dir_all(&dir).unwrap();
        let ssl = |args: &[&str]| {
            let out = Command::new("openssl")
                .args(args)
                .current_dir(&dir)
                .output()
                .expect("the `openssl` command makes this test's certificates");
            assert!(
                out.status.success(),
                "openssl {args:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        };
        let ec = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"];
        for ca in ["ca", "rogue"] {
            let (key, pem, subj) = (format!("{ca}.key"), format!("{ca}.pem"), format!("/CN={ca}"));
            let mut a = vec!["req", "-x509", "-days", "2", "-subj", &subj, "-keyout", &key];
            a.extend(ec);
            a.extend(["-out", &pem]);
            ssl(&a);
        }
        std::fs::write(
            dir.join("ext.cnf"),
            "basicConstraints=CA:FALSE\nsubjectAltName=DNS:localhost,IP:127.0.0.1\n",
        )
        .unwrap();
        for n in names {
            let ca = if *n == "mallory" { "rogue" } else { "ca" };
            let (key, csr, pem) = (format!("{n}.key"), format!("{n}.csr"), format!("{n}.pem"));
            let subj = format!("/CN={n}");
            let mut a = vec!["req", "-subj", &subj, "-keyout", &key, "-out", &csr];
            a.extend(ec);
            ssl(&a);
            let (ca_pem, ca_key) = (format!("{ca}.pem"), format!("{ca}.key"));
            ssl(&[
                "x509",
                "-req",
                "-in",
                &csr,
                "-CA",
                &ca_pem,
                "-CAkey",
                &ca_key,
                "-CAcreateserial",
                "-days",
                "2",
                "-extfile",
                "ext.cnf",
                "-out",
                &pem,
            ]);
        }
        Certs { dir }
    }

    fn tls(&self, name: &str) -> Tls {
        let p = |f: String| self.dir.join(f);
        Tls {
            ca: p("ca.pem".into()),
            cert: p(format!("{name}.pem")),
            key: p(format!("{name}.key")),
        }
    }
}

impl Drop for Certs {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn site(name: &str, certs: &Certs, port: u16, listen: bool) -> Config {
    let ep = vec![format!("tls/127.0.0.1:{port}")];
    let (listen, connect) = if listen { (ep, vec![]) } else { (vec![], ep) };
    Config {
        site: name.into(),
        operator: name.into(),
        listen,
        connect,
        call_timeout: Duration::from_secs(2),
        security: Security { tls: Some(certs.tls(name)), acl: Vec::new() },
        ..Config::default()
    }
}

/// An adapter with `vehicles.usv1` (`armed`, `arm`) and a status object; returns its
/// world model, the vehicle and the status.
fn vehicle_world() -> (DataServer, Guid, Guid) {
    let ds = DataServer::default();
    let vs = ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap();
    let v = ds.create_object(vs, ObjectInfo::new("usv1", "usv")).unwrap();
    ds.set(v, "armed", Value::Bool(false)).unwrap();
    let d2 = ds.clone();
    let spec = MethodSpec::new("arm").param(ParamSpec::new("on", ValueKind::Bool));
    ds.publish_method_fn(v, spec, move |args| {
        let on = matches!(args.first(), Some(Value::Bool(true)));
        let _ = d2.set(v, "armed", Value::Bool(on));
        CallOutcome::Accepted(vec![])
    })
    .unwrap();
    let status = ds.create_object(ds.root(), ObjectInfo::new("distrib", "module")).unwrap();
    (ds, v, status)
}

fn arm(ds: &DataServer) -> CallOutcome {
    let v = ds.resolve(&["vehicles", "usv1"]).unwrap();
    ds.call_wait(v, "arm", vec![Value::Bool(true)], None)
}

#[test]
fn a_peer_without_a_certificate_of_the_ca_cannot_join_and_an_operator_without_the_right_cannot_command()
 {
    let certs = Certs::make("acl", &["adapter", "alice", "bob", "mallory"]);
    let port = free_port();
    let (a, v, status) = vehicle_world();
    let mut ac = site("adapter", &certs, port, true);
    ac.share = vec!["vehicles".into()];
    ac.security.acl = grants(&["alice: vehicles".into()]).unwrap();
    let da = Distrib::start(&a, &ac, Some(status)).unwrap();

    // Mallory's certificate is signed by another CA: the adapter never answers her.
    let m = DataServer::default();
    let mut mc = site("mallory", &certs, port, false);
    mc.security.tls.as_mut().unwrap().ca = certs.dir.join("rogue.pem");
    let dm = Distrib::start(&m, &mc, None).unwrap();

    // Alice and Bob join (both certified) and mirror the vehicle.
    let (alice, bob) = (DataServer::default(), DataServer::default());
    let dal = Distrib::start(&alice, &site("alice", &certs, port, false), None).unwrap();
    let dbo = Distrib::start(&bob, &site("bob", &certs, port, false), None).unwrap();
    assert!(dal.wait_snapshots(1, PATIENCE) && dbo.wait_snapshots(1, PATIENCE));

    // Bob may not command: Zenoh drops his call before the world model sees it.
    let refused = arm(&bob);
    assert!(
        matches!(&refused, CallOutcome::Failed(why) if why.contains("access control")),
        "bob's arm: {refused:?}"
    );
    assert_eq!(a.get(v, "armed").unwrap(), Value::Bool(false), "bob's call never ran");
    // Alice may.
    assert_eq!(arm(&alice), CallOutcome::Accepted(vec![]));
    assert_eq!(a.get(v, "armed").unwrap(), Value::Bool(true));

    // By now mallory would have had the snapshot twice over: she has nothing, and no peer.
    assert_eq!(dm.snapshots(), 0);
    assert!(m.resolve(&["vehicles"]).is_none(), "nothing mirrored by an uncertified peer");
    assert_eq!(dm.session().info().peers_zid().wait().count(), 0, "mallory has no peer");
    // The adapter lists a peer when its liveliness token comes, which may be after that
    // peer's snapshot: waited for, each.
    for name in ["alice", "bob"] {
        let (_w, alive) = watch(&a, &format!("distrib.peers.{name}.alive"));
        until(&alive, &format!("the adapter's peer {name}"), &Value::Bool(true));
    }
    let peers = a.resolve(&["distrib", "peers"]).unwrap();
    let mut seen: Vec<String> =
        a.children(peers).unwrap().iter().map(|g| a.info(*g).unwrap().name.to_string()).collect();
    seen.sort();
    assert_eq!(seen, ["alice", "bob"], "the adapter's peers");
    drop((dal, dbo, dm, da));
}

#[test]
fn a_malformed_payload_on_the_key_space_is_counted_and_dropped_never_fatal() {
    let certs = Certs::make("malformed", &["adapter", "alice", "tool"]);
    let port = free_port();
    let (a, _, status) = vehicle_world();
    let mut ac = site("adapter", &certs, port, true);
    ac.share = vec!["vehicles".into()];
    let da = Distrib::start(&a, &ac, Some(status)).unwrap();
    let (_w, malformed) = watch(&a, "distrib.malformed");

    // A certified tool that writes garbage under another site's keys.
    let tool = zenoh::open(mocu_distrib::zenoh_config(&site("tool", &certs, port, false)).unwrap())
        .wait()
        .unwrap();
    for (key, bytes) in [
        ("mocu/tool/prop/vehicles/x/speed", &b"not json"[..]),
        ("mocu/tool/prop/vehicles/x/speed", b"{\"value\":{\"kind\":\"kettle\",\"value\":1}}"),
        ("mocu/tool/obj/vehicles/x", b"[1,2]"),
    ] {
        tool.put(key, bytes).wait().unwrap();
    }
    until(&malformed, "the adapter's malformed count", &Value::Int(3));
    assert_eq!(da.mirror_stats.malformed.load(std::sync::atomic::Ordering::Relaxed), 3);

    // The adapter goes on: a joiner still gets its snapshot and can command.
    let alice = DataServer::default();
    let dal = Distrib::start(&alice, &site("alice", &certs, port, false), None).unwrap();
    assert!(dal.wait_snapshots(1, PATIENCE));
    assert_eq!(arm(&alice), CallOutcome::Accepted(vec![]));
    let _ = tool.close().wait();
    drop((dal, da));
}
