//! Shutdown is bounded: fig3 (the simulator, the display, the widget renderer, the map,
//! the video windows and the layout under the hot reloader) is loaded and torn down again
//! and again while writers keep every vehicle's position changing, so that callbacks are
//! running at the moment each module stops. A teardown that holds a lock a running
//! callback needs while it waits for that callback deadlocks; here it fails the test
//! (a bounded wait) instead of hanging it.

use mocu_dataserver::{DataServer, Guid, Kind, Value};
use mocu_display::{BackendChoice, Display, DisplayOptions};
use mocu_host::{ModuleHost, ModuleSpec, Registry};
use mocu_layout::{LayoutConfig, NullSink};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Long enough for a loaded machine to stop everything; a deadlock never does.
const HANG: Duration = Duration::from_secs(60);

const ROUNDS: usize = 12;

fn components(bundle: &mocu_language::Bundle) -> mocu_language::Program {
    let mut p = mocu_language::Program::default();
    for l in &bundle.layouts {
        for c in &l.program.components {
            if !p.components.iter().any(|x| x.name == c.name) {
                p.components.push(c.clone());
            }
        }
    }
    p
}

/// Everything `mocu run` starts for a layout.
struct Ocu {
    ds: DataServer,
    host: ModuleHost,
    display: Display,
    layout: mocu_hotreload::Reloader,
    renderer: mocu_widgets::WidgetRenderer,
    map: mocu_widgets::MapModule,
    video: mocu_video::VideoWindows,
}

fn start(path: &Path, bundle: &mocu_language::Bundle) -> Ocu {
    let ds = DataServer::default();
    let mut registry = Registry::new();
    mocu_sim::register(&mut registry);
    let mut host = ModuleHost::new(ds.clone(), registry);
    let mut sim = ModuleSpec::new("sim");
    sim.settings.insert("appear_every".into(), 0.0.into());
    host.start_all(&[sim]);
    let lib = mocu_widgets::Library::compile(&components(bundle), true).unwrap();
    let display =
        Display::new(&ds, DisplayOptions::new(640, 360).backend(BackendChoice::Cpu)).unwrap();
    let renderer =
        mocu_widgets::WidgetRenderer::start(&ds, lib, mocu_widgets::RendererConfig::default())
            .unwrap();
    let map = mocu_widgets::MapModule::start(&ds).unwrap();
    let video = mocu_video::VideoWindows::start(&ds).unwrap();
    let options = mocu_hotreload::ReloaderOptions {
        config: LayoutConfig { screen: (640.0, 360.0), ..LayoutConfig::default() },
        layout: None,
        on_components: None,
    };
    let layout =
        mocu_hotreload::Reloader::start(&ds, path, bundle, options, Arc::new(NullSink)).unwrap();
    layout.watch().unwrap();
    Ocu { ds, host, display, layout, renderer, map, video }
}

/// Writes every vehicle's position as fast as it can until told to stop.
fn hammer(ds: &DataServer, stop: &Arc<AtomicBool>) -> std::thread::JoinHandle<u64> {
    let (ds, stop) = (ds.clone(), stop.clone());
    let (going_tx, going) = crossbeam_channel::bounded(1);
    let writer = std::thread::spawn(move || {
        let mut n = 0u64;
        while n == 0 || !stop.load(Ordering::Relaxed) {
            if n == 1 {
                let _ = going_tx.send(());
            }
            let vehicles = ds.resolve(&["vehicles"]);
            for v in vehicles.and_then(|f| ds.children(f).ok()).unwrap_or_default() {
                if let Ok(Some(nav)) = ds.find_child(v, "nav") {
                    let _ = ds.set(nav, "x", Value::Float((n % 500) as f64));
                    let _ = ds.set(nav, "heading", Value::Float((n % 360) as f64));
                }
            }
            n += 1;
        }
        n
    });
    // Writing before anything stops.
    let _ = going.recv();
    writer
}

/// One round in a thread of its own: load, draw, tear down with the writers going.
/// Returns the subscriptions left and the writes made.
fn round(path: &'static Path, bundle: Arc<mocu_language::Bundle>) -> (usize, u64) {
    let ocu = start(path, &bundle);
    let Ocu { ds, mut host, mut display, layout, renderer, map, video } = ocu;
    // Both USVs on the map and in the strips before anything stops.
    let (seen_tx, seen) = crossbeam_channel::bounded(1);
    let watch = ds
        .watch_object(Guid::ROOT, &["vehicles", "usv2", "nav"], None, move |e| {
            if e.kind != Kind::Deleted {
                let _ = seen_tx.try_send(());
            }
        })
        .unwrap();
    seen.recv_timeout(HANG).expect("the simulator's second USV");
    drop(watch);
    ds.quiesce();
    display.frame();
    let stop = Arc::new(AtomicBool::new(false));
    let writers = [hammer(&ds, &stop), hammer(&ds, &stop)];
    // The order `mocu run` stops in, with the writers still going.
    drop(display);
    drop(layout);
    drop(renderer);
    drop(map);
    drop(video);
    stop.store(true, Ordering::Relaxed);
    let writes = writers.map(|w| w.join().unwrap()).iter().sum();
    host.stop_all();
    ds.quiesce();
    (ds.subscription_count(), writes)
}

#[test]
fn fig3_loads_and_unloads_again_and_again_without_a_stuck_teardown() {
    let path = Path::new("layouts/fig3-multi-usv.mocu");
    let (bundle, _) = mocu_language::load_target(path).unwrap_or_else(|e| panic!("{e}"));
    let bundle = Arc::new(bundle);
    for n in 0..ROUNDS {
        let (tx, rx) = crossbeam_channel::bounded(1);
        let b = bundle.clone();
        std::thread::spawn(move || {
            let _ = tx.send(round(Path::new("layouts/fig3-multi-usv.mocu"), b));
        });
        let (left, writes) = match rx.recv_timeout(HANG) {
            Ok(r) => r,
            Err(crossbeam_channel::RecvTimeoutError::Disconnected) => {
                panic!("round {n}: the round failed (see its panic above)")
            }
            Err(_) => panic!("round {n}: the teardown is stuck (a deadlock)"),
        };
        assert!(writes > 0, "round {n}: the writers ran");
        assert_eq!(left, 0, "round {n}: every subscription ended");
    }
}
