//! Placing windows and widgets on screens of any size: the layout's declared design size
//! (`design 1280 x 720`) and anchors (`anchor bottom-right`).
//!
//! The rule, shared by the runtime (which compiles it into each window's and widget's
//! function) and the checker (W0002, W0005):
//!
//! - With `design W x H`, every px number of a `rect` or an `at` is a design px. The screen
//!   shows the design at the scale `s = min(screen_w / W, screen_h / H)` — uniform, so that
//!   nothing is stretched and the whole design fits — and components draw at that scale
//!   (text and lines grow with it). `%` stays a fraction of the screen. Without `design`,
//!   `s = 1`: px are screen px.
//! - An anchor names the point of the parent (the screen for a window, its window for a
//!   widget) that the position is measured from, and the same point of the item itself:
//!   `anchor bottom-right` with `at 16 8 200 40` puts the widget's bottom-right corner 16 px
//!   left of and 8 px above the window's. Along each axis, with parent length `P`, offset
//!   `o` and size `z` (both scaled by `s`): start `o`; centre `(P − z) / 2 + o`; end
//!   `P − o − z`. An item without a size (a `Label { at X Y }`) is anchored by its point.
//!
//! When the screen's shape differs from the design's, the spare room is between the items
//! anchored to opposite edges: edges stay attached, and nothing leaves the screen that was
//! on the design.

use mocu_value::limits::MAX_DESIGN_SCALE;
use serde::{Deserialize, Serialize};

/// Where, along one axis, a position is measured from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Edge {
    /// Left or top (the default).
    #[default]
    Start,
    Centre,
    /// Right or bottom.
    End,
}

/// `anchor NAME`: the horizontal and vertical edges.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Anchor {
    pub h: Edge,
    pub v: Edge,
}

/// The anchor names, in reading order.
pub const ANCHORS: &[&str] = &[
    "top-left",
    "top",
    "top-right",
    "left",
    "centre",
    "right",
    "bottom-left",
    "bottom",
    "bottom-right",
];

impl Anchor {
    /// The anchor named `name` (one of [`ANCHORS`]).
    pub fn parse(name: &str) -> Option<Anchor> {
        let i = ANCHORS.iter().position(|a| *a == name)?;
        let edge = |k: usize| [Edge::Start, Edge::Centre, Edge::End][k];
        Some(Anchor { h: edge(i % 3), v: edge(i / 3) })
    }

    pub fn is_default(&self) -> bool {
        *self == Anchor::default()
    }

    pub fn name(&self) -> &'static str {
        let k = |e: Edge| match e {
            Edge::Start => 0,
            Edge::Centre => 1,
            Edge::End => 2,
        };
        ANCHORS[k(self.v) * 3 + k(self.h)]
    }
}

/// `design W x H`: the screen size a layout's px are written for.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Design {
    pub width: f64,
    pub height: f64,
}

impl Design {
    /// The uniform scale from design px to screen px: the whole design fits the screen. At
    /// most [`MAX_DESIGN_SCALE`] (the largest screen over the smallest design `mocu check`
    /// allows, E0216): a tiny design never grows every px beyond any screen.
    pub fn scale(&self, screen: (f64, f64)) -> f64 {
        let s = (screen.0 / self.width).min(screen.1 / self.height);
        if s.is_finite() && s > 0.0 { s.min(MAX_DESIGN_SCALE) } else { 1.0 }
    }
}

/// The scale of an optional design on a screen (1 without one).
pub fn scale(design: Option<Design>, screen: (f64, f64)) -> f64 {
    design.map_or(1.0, |d| d.scale(screen))
}

/// One axis of a placed item, all in screen px: the start of the item in its parent, given
/// the parent's length, the item's scaled offset and scaled size (0 when it has none).
pub fn place(edge: Edge, parent: f64, offset: f64, size: f64) -> f64 {
    match edge {
        Edge::Start => offset,
        Edge::Centre => (parent - size) / 2.0 + offset,
        Edge::End => parent - offset - size,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mocu_value::limits::MIN_DESIGN_SIDE;

    #[test]
    fn every_anchor_name_round_trips_and_others_are_refused() {
        for n in ANCHORS {
            assert_eq!(Anchor::parse(n).map(|a| a.name()), Some(*n));
        }
        assert_eq!(Anchor::parse("center"), None);
        assert_eq!(Anchor::parse("top-left"), Some(Anchor::default()));
        assert_eq!(Anchor::parse("bottom-right"), Some(Anchor { h: Edge::End, v: Edge::End }));
        assert_eq!(Anchor::parse("top"), Some(Anchor { h: Edge::Centre, v: Edge::Start }));
    }

    #[test]
    fn the_design_scales_uniformly_by_the_smaller_ratio() {
        let d = Design { width: 1280.0, height: 720.0 };
        assert_eq!(d.scale((1920.0, 1080.0)), 1.5);
        assert_eq!(d.scale((3840.0, 2160.0)), 3.0);
        assert_eq!(d.scale((800.0, 480.0)), 0.625); // 800 / 1280 < 480 / 720
        assert_eq!(scale(None, (800.0, 480.0)), 1.0);
    }

    #[test]
    fn a_tiny_design_scales_no_more_than_the_limit() {
        let tiny = Design { width: 0.001, height: 0.001 };
        assert_eq!(tiny.scale((1280.0, 720.0)), MAX_DESIGN_SCALE);
        let smallest = Design { width: MIN_DESIGN_SIDE, height: MIN_DESIGN_SIDE };
        let largest = mocu_value::limits::MAX_SCREEN_SIDE as f64;
        assert_eq!(smallest.scale((largest, largest)), MAX_DESIGN_SCALE, "a checked design");
    }

    #[test]
    fn an_end_anchored_item_keeps_its_distance_to_the_far_edge() {
        assert_eq!(place(Edge::End, 1920.0, 16.0, 200.0), 1704.0);
        assert_eq!(place(Edge::Centre, 1920.0, 0.0, 400.0), 760.0);
        assert_eq!(place(Edge::Start, 1920.0, 16.0, 200.0), 16.0);
    }
}
