//! Warning W0002: a widget placed wholly outside its window, which would never be seen.
//! Only constant positions are judged; a window in % is measured on the profile's screen
//! size (1920×1080 by default). Runs on the typed program.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;

pub fn warn_outside_window(program: &Program, screen: (f64, f64), diags: &mut Diagnostics) {
    let scale = crate::placement::scale(program.design, screen);
    let layout = WindowSizes::of(&program.windows, screen, scale);
    layout.warn_widgets_outside(&program.widgets, screen, scale, diags);
    for t in &program.templates {
        // A template's widgets are in its own windows first, then the layout's.
        let mut sizes = WindowSizes::of(&t.windows, screen, scale);
        for (name, size) in &layout.0 {
            sizes.0.entry(name.clone()).or_insert(*size);
        }
        sizes.warn_widgets_outside(&t.widgets, screen, scale, diags);
    }
}

/// A constant length in screen px: design px times the scale, or % of `full`.
fn length(b: &Bound, full: f64, scale: f64) -> Option<f64> {
    let v = b.expr.constant()?.number()?;
    Some(if b.expr.ty.unit() == Some("%") { v / 100.0 * full } else { v * scale })
}

/// Each window's size in screen px where it is constant, by name (the first window of each
/// name, as a search would find): what W0002 needs of the windows, kept by `crate::lint`
/// while the program they came from is dropped.
#[derive(Default)]
pub struct WindowSizes(super::FastMap<String, Option<(f64, f64)>>);

impl WindowSizes {
    pub fn of(windows: &[Window], screen: (f64, f64), scale: f64) -> WindowSizes {
        let mut sizes = WindowSizes::default();
        for x in windows {
            sizes.0.entry(x.name.clone()).or_insert_with(|| {
                Some((
                    x.rect.get(2).and_then(|b| length(b, screen.0, scale))?,
                    x.rect.get(3).and_then(|b| length(b, screen.1, scale))?,
                ))
            });
        }
        sizes
    }

    /// W0002 for `widgets` placed in these windows.
    pub fn warn_widgets_outside(
        &self,
        widgets: &[Widget],
        screen: (f64, f64),
        scale: f64,
        diags: &mut Diagnostics,
    ) {
        for w in widgets {
            let Some(Some((ww, wh))) = self.0.get(w.window.as_str()).copied() else { continue };
            // `%` in a widget's `at` is of the screen, as at run time.
            let get = |i: usize, full: f64| w.at.get(i).and_then(|b| length(b, full, scale));
            let (Some(ox), Some(oy)) = (get(0, screen.0), get(1, screen.1)) else { continue };
            let (sw, sh) = (get(2, screen.0).unwrap_or(1.0), get(3, screen.1).unwrap_or(1.0));
            let x = crate::placement::place(w.anchor.h, ww, ox, sw);
            let y = crate::placement::place(w.anchor.v, wh, oy, sh);
            if x >= ww || y >= wh || x + sw <= 0.0 || y + sh <= 0.0 {
                let name = w.name.clone().unwrap_or_else(|| w.component.clone());
                diags
                .warning(
                    codes::OUTSIDE_WINDOW,
                    w.span,
                    format!(
                        "`{name}` at ({x}, {y}) is wholly outside the window `{}` ({ww} × {wh} px)",
                        w.window
                    ),
                )
                .help(if w.anchor.is_default() {
                    "positions are relative to the window's top-left corner".to_string()
                } else {
                    format!(
                        "`anchor {}` measures the position from that point of the window",
                        w.anchor.name()
                    )
                });
            }
        }
    }
}
