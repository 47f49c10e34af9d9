//! Sample painters: a sea chart, HUD gauges and a camera stand-in. They are what the
//! tests, the benchmark and the window demo draw; real content comes from the widget
//! renderer, the video module and the map module, which paint the same way.

use crate::canvas::{self, Align, Baseline, Brush, Canvas, LineCap, Stroke, TextStyle};
use crate::color::Color;
use crate::geom::{Point, Rect};
use crate::path::{Path, PathBuilder};
use std::f32::consts::PI;

/// The HUD palette: near-black panels, cyan lines, amber warnings, red alarms.
pub mod palette {
    use crate::color::Color;
    pub const PANEL: Color = Color::rgba(10, 16, 24, 200);
    pub const EDGE: Color = Color::rgb(0, 200, 230);
    pub const TEXT: Color = Color::rgb(225, 240, 245);
    pub const DIM: Color = Color::rgb(90, 120, 135);
    pub const GOOD: Color = Color::rgb(60, 230, 120);
    pub const WARN: Color = Color::rgb(255, 176, 0);
    pub const ALARM: Color = Color::rgb(255, 60, 60);
    pub const SEA_DEEP: Color = Color::rgb(6, 22, 40);
    pub const SEA: Color = Color::rgb(12, 44, 70);
    pub const LAND: Color = Color::rgb(38, 46, 34);
}
use palette::*;

/// A dial gauge: track, value arc, ticks, needle, value and label. `value` in
/// `min..=max`; the arc sweeps 270° from the lower left.
#[allow(clippy::too_many_arguments)]
pub fn gauge(
    c: &mut dyn Canvas,
    center: Point,
    radius: f32,
    value: f32,
    min: f32,
    max: f32,
    label: &str,
    units: &str,
) {
    let start = 0.75 * PI;
    let sweep = 1.5 * PI;
    let t = ((value - min) / (max - min)).clamp(0.0, 1.0);
    let color = if t > 0.85 {
        ALARM
    } else if t > 0.7 {
        WARN
    } else {
        EDGE
    };
    // The face (panel, rim, track and ticks) is the same frame after frame: a cached
    // picture, drawn once.
    let r_arc = radius * 0.8;
    let face = Rect::new(
        center.x - radius - 2.0,
        center.y - radius - 2.0,
        2.0 * radius + 4.0,
        2.0 * radius + 4.0,
    );
    canvas::picture(c, canvas::picture_key(("demo::gauge face", radius.to_bits())), face, |c| {
        c.fill_circle(center, radius, PANEL);
        c.stroke_circle(center, radius - 1.0, 1.5, EDGE.with_alpha(0.35));
        c.stroke_arc(center, r_arc, start, sweep, &Stroke::new(radius * 0.09), DIM.with_alpha(0.5));
        let mut ticks = PathBuilder::new();
        for i in 0..=20 {
            let a = start + sweep * i as f32 / 20.0;
            let (s, co) = a.sin_cos();
            let r0 = if i % 5 == 0 { radius * 0.6 } else { radius * 0.66 };
            ticks.move_to(Point::new(center.x + co * r0, center.y + s * r0));
            ticks.line_to(Point::new(center.x + co * radius * 0.71, center.y + s * radius * 0.71));
        }
        c.stroke_path(&ticks.finish(), &Stroke::new(1.5), &Brush::Solid(TEXT.with_alpha(0.8)));
    });
    // The value's arc lies outside the ticks (0.755 to 0.845 of the radius; the ticks end
    // at 0.71): drawing it after them changes no pixel.
    c.stroke_arc(
        center,
        r_arc,
        start,
        sweep * t,
        &Stroke::new(radius * 0.09).cap(LineCap::Round),
        color,
    );
    // The needle, drawn pointing right and rotated into place.
    c.save();
    c.translate(center.x, center.y);
    c.rotate(start + sweep * t);
    let needle = Path::polyline(
        &[
            Point::new(-radius * 0.12, -radius * 0.035),
            Point::new(radius * 0.74, 0.0),
            Point::new(-radius * 0.12, radius * 0.035),
        ],
        true,
    );
    c.fill_path(&needle, &Brush::Solid(color));
    c.restore();
    c.fill_circle(center, radius * 0.07, TEXT);
    let size = (radius * 0.3).max(8.0);
    c.draw_text(
        &format!("{value:.0}"),
        Point::new(center.x, center.y + radius * 0.42),
        &TextStyle::new(size, TEXT).align(Align::Center).baseline(Baseline::Middle).bold(),
    );
    c.draw_text(
        &format!("{label} {units}"),
        Point::new(center.x, center.y + radius * 0.72),
        &TextStyle::new(size * 0.5, DIM).align(Align::Center).baseline(Baseline::Middle),
    );
}

/// A HUD panel: translucent dark box with a cyan edge and a title.
pub fn panel(c: &mut dyn Canvas, r: Rect, title: &str) {
    c.fill_rounded_rect(r, 8.0, &Brush::Solid(PANEL));
    c.stroke_rounded_rect(r.inset(0.5), 8.0, &Stroke::new(1.5), EDGE.with_alpha(0.6));
    if !title.is_empty() {
        c.draw_text(title, Point::new(r.x + 12.0, r.y + 8.0), &TextStyle::new(13.0, EDGE).bold());
    }
}

/// A sea chart: depth gradient, grid, an island, a dashed route and a vehicle.
pub fn sea_chart(c: &mut dyn Canvas, vehicle: Point, heading_deg: f32) {
    let s = c.size();
    let full = Rect::new(0.0, 0.0, s.w, s.h);
    c.fill_path(
        &Path::rect(full),
        &Brush::Linear {
            start: Point::new(0.0, 0.0),
            end: Point::new(0.0, s.h),
            stops: vec![(0.0, SEA), (1.0, SEA_DEEP)],
        },
    );
    let mut grid = PathBuilder::new();
    let step = 80.0;
    let mut x = 0.0;
    while x <= s.w {
        grid.move_to(Point::new(x, 0.0)).line_to(Point::new(x, s.h));
        x += step;
    }
    let mut y = 0.0;
    while y <= s.h {
        grid.move_to(Point::new(0.0, y)).line_to(Point::new(s.w, y));
        y += step;
    }
    c.stroke_path(&grid.finish(), &Stroke::new(1.0), &Brush::Solid(EDGE.with_alpha(0.12)));
    let island: Vec<Point> = (0..14)
        .map(|i| {
            let a = i as f32 / 14.0 * 2.0 * PI;
            let r = s.h * 0.22 * (1.0 + 0.25 * (3.0 * a).sin());
            Point::new(s.w * 0.68 + r * a.cos(), s.h * 0.38 + r * 0.7 * a.sin())
        })
        .collect();
    c.fill_path(&Path::polyline(&island, true), &Brush::Solid(LAND));
    c.stroke_path(
        &Path::polyline(&island, true),
        &Stroke::new(2.0),
        &Brush::Solid(Color::rgb(90, 110, 70)),
    );
    let route = Path::polyline(
        &[
            vehicle,
            Point::new(s.w * 0.35, s.h * 0.75),
            Point::new(s.w * 0.5, s.h * 0.8),
            Point::new(s.w * 0.9, s.h * 0.72),
        ],
        false,
    );
    c.stroke_path(&route, &Stroke::new(2.0).dash(&[10.0, 6.0], 0.0), &Brush::Solid(WARN));
    c.save();
    c.translate(vehicle.x, vehicle.y);
    c.rotate(heading_deg.to_radians());
    let boat = Path::polyline(
        &[
            Point::new(0.0, -14.0),
            Point::new(9.0, 10.0),
            Point::new(0.0, 5.0),
            Point::new(-9.0, 10.0),
        ],
        true,
    );
    c.fill_path(&boat, &Brush::Solid(GOOD));
    c.stroke_path(&boat, &Stroke::new(1.5), &Brush::Solid(Color::BLACK));
    c.restore();
    c.draw_text(
        "USV1",
        Point::new(vehicle.x + 16.0, vehicle.y - 8.0),
        &TextStyle::new(13.0, TEXT).bold(),
    );
}

/// A camera stand-in: horizon, sky and water gradients, a crosshair.
pub fn camera_view(c: &mut dyn Canvas, label: &str, tint: Color) {
    let s = c.size();
    let horizon = s.h * 0.45;
    c.fill_path(
        &Path::rect(Rect::new(0.0, 0.0, s.w, horizon)),
        &Brush::Linear {
            start: Point::new(0.0, 0.0),
            end: Point::new(0.0, horizon),
            stops: vec![(0.0, Color::rgb(30, 40, 70)), (1.0, tint)],
        },
    );
    c.fill_path(
        &Path::rect(Rect::new(0.0, horizon, s.w, s.h - horizon)),
        &Brush::Linear {
            start: Point::new(0.0, horizon),
            end: Point::new(0.0, s.h),
            stops: vec![(0.0, Color::rgb(20, 60, 80)), (1.0, Color::rgb(5, 15, 25))],
        },
    );
    let cx = s.w / 2.0;
    let cy = s.h / 2.0;
    let k = s.h.min(s.w) * 0.06;
    let mut cross = PathBuilder::new();
    cross.move_to(Point::new(cx - 2.0 * k, cy)).line_to(Point::new(cx - k / 2.0, cy));
    cross.move_to(Point::new(cx + k / 2.0, cy)).line_to(Point::new(cx + 2.0 * k, cy));
    cross.move_to(Point::new(cx, cy - 2.0 * k)).line_to(Point::new(cx, cy - k / 2.0));
    cross.move_to(Point::new(cx, cy + k / 2.0)).line_to(Point::new(cx, cy + 2.0 * k));
    c.stroke_path(&cross.finish(), &Stroke::new(2.0), &Brush::Solid(GOOD));
    c.draw_text(
        label,
        Point::new(10.0, 8.0),
        &TextStyle::new((s.h * 0.06).clamp(10.0, 20.0), TEXT).bold(),
    );
}

/// The board the benchmark draws: `gauges` dials in a grid and `texts` text runs.
pub fn gauge_board(c: &mut dyn Canvas, values: &[f32], texts: usize) {
    let s = c.size();
    let cols = 5;
    let r = (s.w / cols as f32 / 2.0 - 16.0).min(90.0);
    for (i, v) in values.iter().enumerate() {
        let center = gauge_center(i, s.w);
        if !c.damage().intersects(&Rect::new(center.x - r, center.y - r, 2.0 * r, 2.0 * r)) {
            continue;
        }
        gauge(c, center, r, *v, 0.0, 100.0, "SPD", "kn");
    }
    for i in 0..texts {
        let x = 20.0 + (i % 8) as f32 * (s.w - 40.0) / 8.0;
        let y = s.h * 0.7 + (i / 8) as f32 * 13.0;
        let at = Rect::new(x, y, 200.0, 13.0);
        if !c.damage().intersects(&at) {
            continue;
        }
        c.draw_text(
            &format!("TRK {i:03} {:>5.1} kn", (i as f32 * 1.7) % 40.0),
            Point::new(x, y),
            &TextStyle::new(11.0, if i % 9 == 0 { WARN } else { TEXT }),
        );
    }
}

/// Where gauge `i` of [`gauge_board`] sits.
pub fn gauge_center(i: usize, width: f32) -> Point {
    let cols = 5;
    let cell = width / cols as f32;
    Point::new(cell * (i % cols) as f32 + cell / 2.0, 110.0 + (i / cols) as f32 * 190.0)
}
