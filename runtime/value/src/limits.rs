//! The bounds on what a layout may ask the display for, written once: `mocu check` refuses a
//! layout beyond them (E0216) and the runtime enforces the same numbers, so that what checks
//! clean never asks the display for more than it can allocate.

/// The largest position or size, in px (design px in a layout with `design`), that a window's
/// `rect`, a widget's `at` or a `design` may state.
pub const MAX_EXTENT: f64 = 32768.0;

/// The largest screen side, in px, the display allocates a frame for (an 8K screen is
/// 7680 × 4320).
pub const MAX_SCREEN_SIDE: u32 = 8192;

/// The most pixels one pixmap or per-pixel buffer of the display may hold (a whole screen of
/// the largest size: 256 MiB of RGBA). A bigger one is refused, never allocated.
pub const MAX_PIXMAP_PX: u64 = MAX_SCREEN_SIDE as u64 * MAX_SCREEN_SIDE as u64;

/// The largest text size, in px, the display shapes and rasterises (a glyph is a per-pixel
/// buffer of about its size squared); a text `size` beyond it is refused by `mocu check`.
pub const MAX_FONT_PX: f64 = 1000.0;

/// The smallest side of a `design W x H`: below it the design's scale (screen / design) would
/// grow every px beyond what a screen can show.
pub const MIN_DESIGN_SIDE: f64 = 64.0;

/// The largest scale from design px to screen px: the largest screen over the smallest design.
pub const MAX_DESIGN_SCALE: f64 = MAX_SCREEN_SIDE as f64 / MIN_DESIGN_SIDE;

/// The largest window position or size, in screen px, that the window manager computes with:
/// a checked layout stays within it at any scale, and sums of two stay far inside `i32`.
pub const MAX_WINDOW_PX: i32 = (MAX_EXTENT * MAX_DESIGN_SCALE) as i32;
