//! Where a benchmark frame's time goes: times each part of `benches/frame.rs`'s scene on
//! the CPU canvas (median of N runs). `cargo run --release -p mocu-display --example
//! frame_probe`.

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
    // Compositing two full layers.
    let a = tiny_skia::Pixmap::new(1920, 1080).unwrap();
    let mut dst = tiny_skia::Pixmap::new(1920, 1080).unwrap();
    let src = vec![7u8; 1920 * 1080 * 4];
    println!("memcpy 8MB       {:7.3} ms", median(|| dst.data_mut().copy_from_slice(&src), n));
    let _ = a;
}
