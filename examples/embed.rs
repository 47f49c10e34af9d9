//! Mocu as a library: a DataServer of your own, a layout compiled from its file, the widget
//! renderer and a headless display, one frame written to a PNG. No simulator, no window: the
//! program writes the world model itself, as a vehicle module would.
//!
//! ```sh
//! cargo run --example embed -- card.png        # renders examples/custom_component.mocu
//! ```

use mocu_dataserver::{DataServer, Guid, ObjectInfo, PropMeta, Value, ValueKind};
use mocu_display::{Clock, Display, DisplayOptions};
use mocu_layout::{Layout, LayoutConfig, NullSink};
use mocu_widgets::{Library, RendererConfig, WidgetRenderer};
use std::path::Path;
use std::sync::Arc;

const SIZE: (u32, u32) = (500, 140);

/// A vehicle as a protocol module publishes one: `root.vehicles.NAME.nav.speed` in m/s.
fn vehicle(ds: &DataServer, name: &str, speed: Option<f64>) -> Guid {
    let vs = ds.resolve(&["vehicles"]).unwrap_or_else(|| {
        ds.create_object(ds.root(), ObjectInfo::new("vehicles", "vehicles")).unwrap()
    });
    let v = ds.create_object(vs, ObjectInfo::new(name, "usv")).unwrap();
    let nav = ds.create_object(v, ObjectInfo::new("nav", "nav")).unwrap();
    if let Some(s) = speed {
        let meta = PropMeta::typed(ValueKind::Float).units("m/s");
        ds.create_property(nav, "speed", Value::Float(s), meta).unwrap();
    }
    nav
}

/// Renders `layout` with usv1 at `speed` m/s and usv2 without a speed; returns the frame.
fn render(layout: &Path, speed: f64) -> Result<tiny_skia::Pixmap, String> {
    // 1. Compile: the checked program (diagnostics rendered as `mocu check` does).
    let (bundle, _) = mocu_language::load_target(layout).map_err(|e| e.to_string())?;
    let program = &bundle.layouts[0].program;
    // 2. The world model, and what the layout reads.
    let ds = DataServer::default();
    vehicle(&ds, "usv1", Some(speed));
    vehicle(&ds, "usv2", None);
    // 3. The display's modules, then the layout: each finds the others through root.display.
    let (w, h) = SIZE;
    let mut display = Display::new(&ds, DisplayOptions::new(w, h).clock(Clock::manual()))
        .map_err(|e| e.to_string())?;
    let library = Library::compile(program, true).map_err(|e| e.to_string())?;
    let _renderer = WidgetRenderer::start(&ds, library, RendererConfig::default())
        .map_err(|e| e.to_string())?;
    let config = LayoutConfig { screen: (f64::from(w), f64::from(h)), ..LayoutConfig::default() };
    let layout =
        Layout::load(&ds, program, config, Arc::new(NullSink)).map_err(|e| e.to_string())?;
    // 4. A frame: the layout's values reach the widgets, the widgets paint, the display
    //    composites (twice: widgets published in the first frame paint in the second).
    for _ in 0..2 {
        layout.settle();
        ds.quiesce();
        display.frame();
    }
    Ok(display.read_frame())
}

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "card.png".into());
    let layout = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/custom_component.mocu");
    match render(&layout, 5.2) {
        Ok(frame) => {
            frame.save_png(&out).expect("writable");
            println!("wrote {out}");
        }
        Err(e) => {
            eprintln!("embed: {e}");
            std::process::exit(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/custom_component.mocu")
    }

    /// The share of the card at `x0..x1` × `y0..y1` (frame px) drawn in amber.
    fn amber(f: &tiny_skia::Pixmap, (x0, x1): (u32, u32), (y0, y1): (u32, u32)) -> usize {
        let mut n = 0;
        for y in y0..y1 {
            for x in x0..x1 {
                let c = f.pixel(x, y).unwrap().demultiply();
                n += usize::from(c.red() > 200 && c.green() > 120 && c.blue() < 60);
            }
        }
        n
    }

    #[test]
    fn an_embedding_program_renders_its_layout_with_its_own_world_model() {
        let slow = render(&layout(), 2.0).unwrap();
        let fast = render(&layout(), 9.0).unwrap();
        assert_eq!((slow.width(), slow.height()), SIZE);
        // usv1's card (the window at 20,20; the card 220 wide): amber only when fast.
        let card = ((20, 240), (20, 120));
        assert_eq!(amber(&slow, card.0, card.1), 0, "a slow usv1 is not amber");
        assert!(amber(&fast, card.0, card.1) > 200, "a fast usv1 is amber");
        // The frame is the same when rendered again (nothing but the world model drives it).
        assert_eq!(render(&layout(), 9.0).unwrap().data(), fast.data());
    }
}
