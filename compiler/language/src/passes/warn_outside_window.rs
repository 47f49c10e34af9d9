//! Warning W0002: a widget placed wholly outside its window, which would never be seen.
//! Only constant positions are judged; a window in % is measured on the profile's screen
//! size (1920×1080 by default). Runs on the typed program.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;

pub fn warn_outside_window(program: &Program, screen: (f64, f64), diags: &mut Diagnostics) {
    check(&program.windows, &program.widgets, screen, diags);
    for t in &program.templates {
        let mut windows = t.windows.clone();
        windows.extend(program.windows.iter().cloned());
        check(&windows, &t.widgets, screen, diags);
    }
}

fn length(b: &Bound, full: f64) -> Option<f64> {
    let v = b.expr.constant()?.number()?;
    Some(if b.expr.ty.unit() == Some("%") { v / 100.0 * full } else { v })
}

fn check(windows: &[Window], widgets: &[Widget], screen: (f64, f64), diags: &mut Diagnostics) {
    // By name, the first of each (as a search would find): searching the list for every
    // widget made 100,000-line layouts quadratic.
    let mut by_name: std::collections::HashMap<&str, &Window> = Default::default();
    for x in windows {
        by_name.entry(x.name.as_str()).or_insert(x);
    }
    for w in widgets {
        let Some(win) = by_name.get(w.window.as_str()).copied() else { continue };
        let (Some(ww), Some(wh)) = (
            win.rect.get(2).and_then(|b| length(b, screen.0)),
            win.rect.get(3).and_then(|b| length(b, screen.1)),
        ) else {
            continue;
        };
        let get = |i: usize, full: f64| w.at.get(i).and_then(|b| length(b, full));
        let (Some(x), Some(y)) = (get(0, ww), get(1, wh)) else { continue };
        let (sw, sh) = (get(2, ww).unwrap_or(1.0), get(3, wh).unwrap_or(1.0));
        if x >= ww || y >= wh || x + sw <= 0.0 || y + sh <= 0.0 {
            let name = w.name.clone().unwrap_or_else(|| w.component.clone());
            diags
                .warning(
                    codes::OUTSIDE_WINDOW,
                    w.span,
                    format!(
                        "`{name}` at ({x}, {y}) is wholly outside the window `{}` ({ww} × {wh} px)",
                        win.name
                    ),
                )
                .help("positions are relative to the window's top-left corner");
        }
    }
}
