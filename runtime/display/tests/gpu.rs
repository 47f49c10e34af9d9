//! The wgpu compositor against the tiny-skia one on the same scenes. Needs a wgpu
//! adapter: Mesa llvmpipe through GL (`WGPU_BACKEND=gl`, nothing to install beyond the
//! Mesa EGL libraries) or lavapipe through Vulkan (`mesa-vulkan-drivers libvulkan1`).
//! Without one each test says so on stderr and returns.
#![cfg(feature = "gpu")]

mod common;
use common::*;
use mocu_dataserver::{Config, DataServer, Value};
use mocu_display::demo::{self, palette};
use mocu_display::*;

/// Per-channel tolerance between the CPU and GPU compositors: the GPU blends in float,
/// the CPU in 8-bit integer arithmetic rounded per step.
const GPU_TOL: u8 = 2;

fn scene(ds: &DataServer, d: &Display) {
    let map =
        publish_window(ds, d.display_object(), "map", "map", 0, Rect::new(0.0, 0.0, 640.0, 400.0))
            .unwrap();
    let hud = publish_window(
        ds,
        d.display_object(),
        "hud",
        "widgets",
        10,
        Rect::new(0.0, 0.0, 640.0, 400.0),
    )
    .unwrap();
    let cam = publish_window(
        ds,
        d.display_object(),
        "cam",
        "video",
        5,
        Rect::new(400.0, 230.0, 220.0, 150.0),
    )
    .unwrap();
    ds.set(hud, "opacity", Value::Float(0.85)).unwrap();
    ds.set(cam, "opacity", Value::Float(0.6)).unwrap();
    claim_window(ds, map, |c, _| demo::sea_chart(c, Point::new(200.0, 260.0), 40.0)).unwrap();
    claim_window(ds, cam, |c, _| demo::camera_view(c, "PAYLOAD", Color::rgb(90, 70, 60))).unwrap();
    claim_window(ds, hud, |c, _| {
        demo::panel(c, Rect::new(12.0, 12.0, 200.0, 200.0), "PROPULSION");
        demo::gauge(c, Point::new(112.0, 122.0), 80.0, 31.0, 0.0, 40.0, "SPD", "kn");
        c.draw_text(
            "HDG 040°",
            Point::new(534.0, 40.0),
            &TextStyle::new(22.0, palette::TEXT).align(Align::Center).bold(),
        );
    })
    .unwrap();
}

fn gpu_display(ds: &DataServer) -> Option<Display> {
    match Display::new(
        ds,
        DisplayOptions::new(640, 400).backend(BackendChoice::Gpu).clock(Clock::manual()),
    ) {
        Ok(d) => {
            eprintln!("gpu test: running on {}", d.backend_name());
            Some(d)
        }
        Err(e) => {
            eprintln!(
                "gpu test SKIPPED: {e}. Install mesa (GL: libegl1-mesa / libgl1-mesa-dri) or \
                 `mesa-vulkan-drivers libvulkan1`, or set WGPU_BACKEND=gl"
            );
            None
        }
    }
}

fn max_diff(a: &tiny_skia::Pixmap, b: &tiny_skia::Pixmap) -> (u8, usize) {
    let mut worst = 0;
    let mut over = 0;
    for (x, y) in a.data().chunks_exact(4).zip(b.data().chunks_exact(4)) {
        let d = x.iter().zip(y).map(|(p, q)| p.abs_diff(*q)).max().unwrap();
        worst = worst.max(d);
        if d > GPU_TOL {
            over += 1;
        }
    }
    (worst, over)
}

#[test]
fn the_gpu_compositor_matches_the_cpu_one() {
    let gds = DataServer::new(Config { workers: 2 });
    let Some(mut g) = gpu_display(&gds) else { return };
    let cds = DataServer::new(Config { workers: 2 });
    let mut c = Display::new(&cds, DisplayOptions::new(640, 400).clock(Clock::manual())).unwrap();
    scene(&gds, &g);
    scene(&cds, &c);
    frame(&gds, &mut g);
    frame(&cds, &mut c);
    let (gf, cf) = (g.read_frame(), c.read_frame());
    let (worst, over) = max_diff(&gf, &cf);
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    gf.save_png(dir.join("gpu_scene.png")).unwrap();
    assert_eq!(over, 0, "{over} pixels differ by more than {GPU_TOL} (worst {worst})");
    // Moving a window and changing opacity: recomposited on both, still equal.
    for ds in [&gds, &cds] {
        let cam = ds.resolve(&["display", "cam"]).unwrap();
        ds.set(cam, "x", Value::Float(20.0)).unwrap();
        ds.set(cam, "opacity", Value::Float(0.9)).unwrap();
    }
    let st = frame(&gds, &mut g);
    assert!(st.drawn && st.repainted.is_empty(), "{st:?}");
    frame(&cds, &mut c);
    let (worst, over) = max_diff(&g.read_frame(), &c.read_frame());
    assert_eq!(over, 0, "after a move: {over} pixels over tolerance (worst {worst})");
}

#[test]
fn a_partial_repaint_updates_the_gpu_layer_in_place() {
    let ds = DataServer::new(Config { workers: 2 });
    let Some(mut d) = gpu_display(&ds) else { return };
    scene(&ds, &d);
    frame(&ds, &mut d);
    let before = d.read_frame();
    let hud = ds.resolve(&["display", "hud"]).unwrap();
    invalidate_rect(&ds, hud, Rect::new(30.0, 30.0, 160.0, 160.0)).unwrap();
    let st = frame(&ds, &mut d);
    assert_eq!(st.partial.len(), 1, "{st:?}");
    // Same content repainted in part (only that region uploaded): the same picture.
    let (worst, over) = max_diff(&before, &d.read_frame());
    assert_eq!((worst, over), (0, 0));
}
