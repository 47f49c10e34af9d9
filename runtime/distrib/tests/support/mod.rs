//! What the in-process tests of sites on loopback share: free ports and waits on a path's
//! values, bounded so that a failure fails instead of hanging.

#![allow(dead_code)] // each test binary uses the part of it that it needs
use crossbeam_channel::{Receiver, unbounded};
use mocu_dataserver::{DataServer, DottedPath, Kind, PathEvent, PathWatch, Value};
use std::net::TcpListener;
use std::time::Duration;

/// Long enough for a loaded CI machine, short enough that a hang is a failure.
pub const PATIENCE: Duration = Duration::from_secs(20);

pub fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// The values a path takes, as they come.
pub fn watch(ds: &DataServer, path: &str) -> (PathWatch, Receiver<PathEvent>) {
    let (tx, rx) = unbounded();
    let w = ds
        .watch_path(DottedPath::parse(path).unwrap(), None, move |e| {
            let _ = tx.send(e.clone());
        })
        .unwrap();
    (w, rx)
}

/// Waits until the watched path holds `want`; panics (naming it) if it does not in time.
pub fn until(rx: &Receiver<PathEvent>, what: &str, want: &Value) {
    let mut seen = Vec::new();
    loop {
        match rx.recv_timeout(PATIENCE) {
            Ok(e) if e.kind != Kind::Deleted && e.value.as_ref() == Some(want) => return,
            Ok(e) => seen.push(e.value),
            Err(_) => panic!("{what} never became {want:?}; saw {seen:?}"),
        }
    }
}
