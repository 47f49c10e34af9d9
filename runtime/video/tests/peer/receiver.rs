//! A video receiver under test: the module started on a loopback port of its own.

use mocu_dataserver::{DataServer, Guid};
use mocu_host::{Module, ModuleContext};
use mocu_video::{ReceiverConfig, VideoReceiver};

/// A video receiver module on loopback (any free port) publishing camera `test`.
pub struct Running {
    pub ds: DataServer,
    pub module: VideoReceiver,
    pub camera: Guid,
    pub port: u16,
}

/// Starts one, detached from any host.
pub fn receiver() -> Running {
    let ds = DataServer::default();
    let ctx = ModuleContext::detached("video", ds.clone());
    let cfg = ReceiverConfig {
        address: "127.0.0.1:0".parse().unwrap(),
        camera: Some("test".into()),
        ..ReceiverConfig::default()
    };
    let mut module = VideoReceiver::new(cfg);
    module.start(&ctx).expect("receiver starts");
    let camera = ds.resolve(&["cameras", "test"]).expect("root.cameras.test");
    let port = ds.get(camera, "port").unwrap().as_i64().unwrap() as u16;
    Running { ds, module, camera, port }
}
