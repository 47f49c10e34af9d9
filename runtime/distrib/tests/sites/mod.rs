//! An OCU site of the in-process tests: its own DataServer and Zenoh session, connected to
//! the adapter on loopback, returned once the adapter's snapshot is mirrored.

use crate::support::PATIENCE;
use mocu_dataserver::DataServer;
use mocu_distrib::{Config, Distrib};
use std::time::Duration;

/// The OCU of operator `name` (also its site's name), connected to `port`.
pub fn ocu(name: &str, port: u16) -> (DataServer, Distrib) {
    let ds = DataServer::default();
    let config = Config {
        site: name.into(),
        operator: name.into(),
        connect: vec![format!("tcp/127.0.0.1:{port}")],
        call_timeout: Duration::from_secs(15),
        ..Config::default()
    };
    let d = Distrib::start(&ds, &config, None).unwrap();
    assert!(d.wait_snapshots(1, PATIENCE), "{name}: the adapter's snapshot");
    (ds, d)
}
