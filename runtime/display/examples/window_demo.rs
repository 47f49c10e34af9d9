//! Opens a winit window, composites a map, a camera inset and a HUD on the GPU, swaps the
//! camera and the map half-way through, and writes a screenshot.
//!
//! ```text
//! xvfb-run -a -s "-screen 0 1280x800x24" cargo run -p mocu-display --example window_demo -- \
//!     --frames 90 --screenshot /tmp/window_demo.png
//! ```
//! Without `--frames` it runs until the window is closed (drawing only on change).

use mocu_dataserver::{DataServer, Value};
use mocu_display::demo::{self, palette};
use mocu_display::*;
use std::time::Duration;

fn main() {
    let mut frames = None;
    let mut shot = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--frames" => frames = args.next().and_then(|n| n.parse().ok()),
            "--screenshot" => shot = args.next().map(std::path::PathBuf::from),
            other => {
                eprintln!("unknown argument {other}");
                std::process::exit(2);
            }
        }
    }
    let ds = DataServer::default();
    let (w, h) = (1024u32, 640u32);
    let opts = WindowOptions {
        title: "Mocu — window demo".into(),
        display: DisplayOptions::new(w, h),
        frames,
        screenshot: shot.clone(),
        stop: None,
    };
    let ds2 = ds.clone();
    let result = run_window(&ds, opts, move |d| {
        let ds = ds2;
        let disp = d.display_object();
        let map =
            publish_window(&ds, disp, "map", "map", 0, Rect::new(0.0, 0.0, w as f32, h as f32))
                .unwrap();
        let cam =
            publish_window(&ds, disp, "video", "video", 5, Rect::new(744.0, 420.0, 260.0, 200.0))
                .unwrap();
        let hud = publish_window(
            &ds,
            disp,
            "hud",
            "widgets",
            10,
            Rect::new(0.0, 0.0, w as f32, h as f32),
        )
        .unwrap();
        ds.set(hud, "opacity", Value::Float(0.92)).unwrap();
        claim_window(&ds, map, |c, _| {
            let s = c.size();
            demo::sea_chart(c, Point::new(s.w * 0.3, s.h * 0.6), 35.0)
        })
        .unwrap();
        claim_window(&ds, cam, |c, _| demo::camera_view(c, "DRIVE CAM", Color::rgb(80, 96, 130)))
            .unwrap();
        let speed = std::sync::Arc::new(parking_lot::Mutex::new(12.0f32));
        let sp = speed.clone();
        claim_window(&ds, hud, move |c, a| {
            demo::panel(c, Rect::new(16.0, 16.0, 220.0, 220.0), "PROPULSION");
            demo::gauge(c, Point::new(126.0, 132.0), 86.0, *sp.lock(), 0.0, 40.0, "SPD", "kn");
            demo::panel(c, Rect::new(788.0, 16.0, 220.0, 70.0), "HEADING");
            c.draw_text(
                "HDG 035°",
                Point::new(898.0, 58.0),
                &TextStyle::new(24.0, palette::TEXT).align(Align::Center).bold(),
            );
            c.draw_text(
                &format!("frame {}", a.frame),
                Point::new(16.0, 620.0),
                &TextStyle::new(12.0, palette::DIM).baseline(Baseline::Bottom),
            );
        })
        .unwrap();
        // Telemetry: the speed gauge moves; half-way the camera and the map swap.
        let ds3 = ds.clone();
        std::thread::spawn(move || {
            for i in 0..400 {
                std::thread::sleep(Duration::from_millis(33));
                *speed.lock() = 12.0 + (i as f32 * 0.15).sin() * 8.0 + i as f32 * 0.05;
                let _ = invalidate_rect(&ds3, hud, Rect::new(36.0, 42.0, 180.0, 190.0));
                if i == 20 {
                    ds3.call(
                        disp,
                        "swap",
                        vec![Value::str("video"), Value::str("map"), Value::Int(400)],
                        None,
                        |o| eprintln!("swap: {o}"),
                    );
                }
            }
        });
    });
    match result {
        Ok(c) => {
            eprintln!("window_demo: {c:?}");
            if let Some(p) = shot {
                eprintln!("window_demo: screenshot in {}", p.display());
            }
        }
        Err(e) => {
            eprintln!("window_demo: {e}");
            std::process::exit(1);
        }
    }
}
