//! Where a benchmark frame's time goes: times each part of `benches/frame.rs`'s scene on
//! the CPU canvas (median of N runs). `cargo run --release -p mocu-display --example
//! frame_probe`. `-- scene N` only draws the benchmark's full frame N times (for
//! `valgrind --tool=callgrind`, whose counts do not depend on the machine's load).

use mocu_display::demo;
use mocu_display::*;
use std::time::Instant;

/// This thread's CPU time in ns (`CLOCK_THREAD_CPUTIME_ID`): on a machine shared with
/// compilers, wall time measures the neighbours.
fn cpu_ns() -> Option<u64> {
    cpu_time::ThreadTime::try_now().ok().map(|t| t.as_duration().as_nanos() as u64)
}

/// Median CPU milliseconds of `n` runs (wall milliseconds where CPU time is unknown).
fn median(mut f: impl FnMut(), n: usize) -> f64 {
    let mut t: Vec<f64> = (0..n)
        .map(|_| {
            let (c0, s) = (cpu_ns(), Instant::now());
            f();
            match (c0, cpu_ns()) {
                (Some(a), Some(b)) => (b - a) as f64 / 1e6,
                _ => s.elapsed().as_secs_f64() * 1e3,
            }
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[n / 2]
}

fn canvas() -> SkiaCanvas {
    let pm = tiny_skia::Pixmap::new(1920, 1080).unwrap();
    SkiaCanvas::new(pm, (0, 0), Size::new(1920.0, 1080.0))
}

fn main() {
    let n = 15;
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("scene") {
        scene_frames(args.get(2).and_then(|a| a.parse().ok()).unwrap_or(5));
        return;
    }
    scene_frames(31);
    composite_only(15);
    let values: Vec<f32> = (0..20).map(|i| i as f32 * 4.0).collect();
    let mut c = canvas();
    println!(
        "sea chart        {:7.3} ms",
        median(|| demo::sea_chart(&mut c, Point::new(600.0, 700.0), 30.0), n)
    );
    let mut c = canvas();
    println!("gauge board      {:7.3} ms", median(|| demo::gauge_board(&mut c, &values, 200), n));
    let mut c = canvas();
    println!("20 gauges        {:7.3} ms", median(|| demo::gauge_board(&mut c, &values, 0), n));
    let mut c = canvas();
    let p = Point::new(300.0, 300.0);
    println!(
        "1 gauge          {:7.3} ms",
        median(|| demo::gauge(&mut c, p, 90.0, 40.0, 0.0, 100.0, "SPD", "kn"), n)
    );
    println!(
        "  fill_circle    {:7.3} ms",
        median(|| c.fill_circle(p, 90.0, Color::rgba(10, 20, 30, 200)), n)
    );
    println!(
        "  stroke_circle  {:7.3} ms",
        median(|| c.stroke_circle(p, 89.0, 1.5, Color::rgba(10, 200, 30, 100)), n)
    );
    let st = Stroke::new(8.0);
    println!(
        "  stroke_arc     {:7.3} ms",
        median(|| c.stroke_arc(p, 72.0, 2.3, 4.7, &st, Color::rgba(100, 100, 100, 128)), n)
    );
    let st = Stroke::new(8.0).cap(LineCap::Round);
    println!(
        "  arc round cap  {:7.3} ms",
        median(|| c.stroke_arc(p, 72.0, 2.3, 2.0, &st, Color::rgb(200, 100, 0)), n)
    );
    let mut ticks = PathBuilder::new();
    for i in 0..=20 {
        let a = 2.3 + 4.7 * i as f32 / 20.0;
        let (s, co) = a.sin_cos();
        ticks.move_to(Point::new(p.x + co * 54.0, p.y + s * 54.0));
        ticks.line_to(Point::new(p.x + co * 64.0, p.y + s * 64.0));
    }
    let ticks = ticks.finish();
    println!(
        "  ticks          {:7.3} ms",
        median(|| c.stroke_path(&ticks, &Stroke::new(1.5), &Brush::Solid(Color::WHITE)), n)
    );
    let style = TextStyle::new(27.0, Color::WHITE).align(Align::Center).bold();
    println!(
        "  text 27px      {:7.3} ms",
        median(
            || {
                c.draw_text("40", p, &style);
            },
            n
        )
    );
    let style = TextStyle::new(12.0, Color::WHITE);
    println!(
        "  text 12px x10  {:7.3} ms",
        median(
            || for i in 0..10 {
                c.draw_text("Text run 12 px", Point::new(10.0, 20.0 * i as f32), &style);
            },
            n
        )
    );
    // Gauge parts not listed above.
    let needle = Path::polyline(
        &[Point::new(-10.8, -3.15), Point::new(66.6, 0.0), Point::new(-10.8, 3.15)],
        true,
    );
    println!(
        "  needle         {:7.3} ms",
        median(
            || {
                c.save();
                c.translate(p.x, p.y);
                c.rotate(3.0);
                c.fill_path(&needle, &Brush::Solid(Color::rgb(200, 100, 0)));
                c.restore();
            },
            n
        )
    );
    println!("  hub            {:7.3} ms", median(|| c.fill_circle(p, 6.3, Color::WHITE), n));
    // Chart parts.
    let mut c = canvas();
    let full = Rect::new(0.0, 0.0, 1920.0, 1080.0);
    let grad = Brush::Linear {
        start: Point::new(0.0, 0.0),
        end: Point::new(0.0, 1080.0),
        stops: vec![(0.0, Color::rgb(12, 44, 70)), (1.0, Color::rgb(6, 22, 40))],
    };
    println!("chart gradient   {:7.3} ms", median(|| c.fill_path(&Path::rect(full), &grad), n));
    let mut grid = PathBuilder::new();
    let mut x = 0.0;
    while x <= 1920.0 {
        grid.move_to(Point::new(x, 0.0)).line_to(Point::new(x, 1080.0));
        x += 80.0;
    }
    let mut y = 0.0;
    while y <= 1080.0 {
        grid.move_to(Point::new(0.0, y)).line_to(Point::new(1920.0, y));
        y += 80.0;
    }
    let grid = grid.finish();
    let gb = Brush::Solid(Color::rgba(0, 200, 230, 30));
    println!(
        "chart grid       {:7.3} ms",
        median(|| c.stroke_path(&grid, &Stroke::new(1.0), &gb), n)
    );
    let island: Vec<Point> = (0..14)
        .map(|i| {
            let a = i as f32 / 14.0 * 2.0 * std::f32::consts::PI;
            let r = 1080.0 * 0.22 * (1.0 + 0.25 * (3.0 * a).sin());
            Point::new(1920.0 * 0.68 + r * a.cos(), 1080.0 * 0.38 + r * 0.7 * a.sin())
        })
        .collect();
    let isl = Path::polyline(&island, true);
    let lb = Brush::Solid(Color::rgb(38, 46, 34));
    println!("chart island     {:7.3} ms", median(|| c.fill_path(&isl, &lb), n));
    println!(
        "chart isl stroke {:7.3} ms",
        median(|| c.stroke_path(&isl, &Stroke::new(2.0), &lb), n)
    );
    let route = Path::polyline(
        &[
            Point::new(600.0, 700.0),
            Point::new(672.0, 810.0),
            Point::new(960.0, 864.0),
            Point::new(1728.0, 777.0),
        ],
        false,
    );
    println!(
        "chart route      {:7.3} ms",
        median(|| c.stroke_path(&route, &Stroke::new(2.0).dash(&[10.0, 6.0], 0.0), &lb), n)
    );
    // Compositing two full layers.
    let a = tiny_skia::Pixmap::new(1920, 1080).unwrap();
    let mut dst = tiny_skia::Pixmap::new(1920, 1080).unwrap();
    let src = vec![7u8; 1920 * 1080 * 4];
    println!("memcpy 8MB       {:7.3} ms", median(|| dst.data_mut().copy_from_slice(&src), n));
    let _ = a;
}

/// The benchmark's scene (`benches/frame.rs`): a chart layer and a HUD layer.
fn scene_frames(n: usize) {
    use mocu_dataserver::{Config, DataServer, Value};
    let (w, h) = (1920u32, 1080u32);
    let ds = DataServer::new(Config { workers: 2 });
    let mut display = Display::new(&ds, DisplayOptions::new(w, h)).unwrap();
    let disp = display.display_object();
    let full = Rect::new(0.0, 0.0, w as f32, h as f32);
    let map = publish_window(&ds, disp, "map", "map", 0, full).unwrap();
    let hud = publish_window(&ds, disp, "hud", "widgets", 10, full).unwrap();
    ds.set(hud, "opacity", Value::Float(0.95)).unwrap();
    claim_window(&ds, map, |c, _| demo::sea_chart(c, Point::new(600.0, 700.0), 30.0)).unwrap();
    let values: Vec<f32> = (0..20).map(|i| i as f32 * 4.0).collect();
    claim_window(&ds, hud, move |c, _| demo::gauge_board(c, &values, 200)).unwrap();
    ds.quiesce();
    display.frame();
    let mut paint = Vec::new();
    let mut comp = Vec::new();
    let total = median(
        || {
            display.invalidate_all();
            let st = display.frame();
            paint.push(st.paint_time.as_secs_f64() * 1e3);
            comp.push(st.composite_time.as_secs_f64() * 1e3);
        },
        n,
    );
    paint.sort_by(f64::total_cmp);
    comp.sort_by(f64::total_cmp);
    println!(
        "full frame       {total:7.3} ms cpu (wall medians: paint {:.3} ms, composite {:.3} ms)",
        paint[n / 2],
        comp[n / 2]
    );
}

/// Compositing the scene's two layers alone.
fn composite_only(n: usize) {
    let size = Size::new(1920.0, 1080.0);
    let mut chart = SkiaCanvas::new(tiny_skia::Pixmap::new(1920, 1080).unwrap(), (0, 0), size);
    demo::sea_chart(&mut chart, Point::new(600.0, 700.0), 30.0);
    let chart = chart.into_pixmap();
    let mut hud = SkiaCanvas::new(tiny_skia::Pixmap::new(1920, 1080).unwrap(), (0, 0), size);
    let values: Vec<f32> = (0..20).map(|i| i as f32 * 4.0).collect();
    demo::gauge_board(&mut hud, &values, 200);
    let hud = hud.into_pixmap();
    let g = mocu_dataserver::Guid::ROOT;
    let view = |pixmap, opacity, opaque| LayerView {
        window: g,
        pixmap,
        tiles: None,
        opaque,
        x: 0,
        y: 0,
        opacity,
        changed: None,
    };
    let mut comp = CpuCompositor::new(1920, 1080, Color::BLACK).unwrap();
    let full = IRect::new(0, 0, 1920, 1080);
    let layers = [view(&chart, 1.0, true), view(&hud, 0.95, false)];
    println!("composite        {:7.3} ms", median(|| comp.composite(&layers, full), n));
    let layers = [view(&chart, 1.0, false), view(&hud, 0.95, false)];
    println!("  chart not opaque {:5.3} ms", median(|| comp.composite(&layers, full), n));
    let layers = [view(&chart, 1.0, true)];
    println!("  chart only     {:7.3} ms", median(|| comp.composite(&layers, full), n));
    let layers = [view(&hud, 0.95, false)];
    println!("  hud only       {:7.3} ms", median(|| comp.composite(&layers, full), n));
}
