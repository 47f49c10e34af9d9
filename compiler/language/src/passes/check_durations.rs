//! Durations the runtime cannot honour (E0310) or that are surely a slip (W0004). Called by
//! `check_types` on each watch's `for` and `repeat every` and each swap's duration, once the
//! expression is typed:
//! - `for -5s` (negative), `repeat every 0ms` or `repeat every -30s` (zero or negative), and a
//!   duration that is not a constant (the runtime takes timings when the layout loads) are
//!   errors;
//! - a duration over a day (`for 100000000min`) is a warning: no operator waits that long.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::Expr;
use crate::types::TypeKind;

/// Where a duration is used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Use {
    /// `when … for T`: may be zero.
    Hold,
    /// `repeat every T`: must be positive.
    Repeat,
    /// `swap a b over T`: may be zero.
    Swap,
}

/// The longest duration not reported as absurd: one day, in milliseconds.
pub const DAY_MS: f64 = 24.0 * 3600.0 * 1000.0;

/// Checks one typed duration expression; returns its value in ms when it is usable.
pub fn check_duration(e: &Expr, usage: Use, diags: &mut Diagnostics) -> Option<f64> {
    if matches!(e.ty.kind, TypeKind::Error) {
        return None;
    }
    let what = match usage {
        Use::Hold => "the hold time after `for`",
        Use::Repeat => "the repeat period after `repeat every`",
        Use::Swap => "a swap's duration",
    };
    let Some(ms) = e.constant().and_then(|c| c.number()) else {
        diags
            .error(codes::BAD_DURATION, e.span, format!("{what} must be a constant duration"))
            .label("not known until run time")
            .help("write a literal such as `5s`, `500ms` or `2min`, or a `let` of one");
        return None;
    };
    if !ms.is_finite() || ms < 0.0 || (usage == Use::Repeat && ms == 0.0) {
        // The fix, in the user's own number where there is one (`-30s` → `30s`).
        let positive = if ms.is_finite() && ms != 0.0 { literal(-ms) } else { "1s".into() };
        let (label, help) = match usage {
            Use::Repeat => (
                "must be more than zero",
                format!("a repeat period is positive: `repeat every {positive}`"),
            ),
            _ => (
                "must not be negative",
                format!(
                    "a duration counts forward from now: write `for {positive}`, or `for 0s` for none"
                ),
            ),
        };
        diags
            .error(
                codes::BAD_DURATION,
                e.span,
                format!("{what} of {} cannot be honoured", show(ms)),
            )
            .label(label)
            .help(help);
        return None;
    }
    if ms > DAY_MS {
        diags
            .warning(
                codes::ABSURD_DURATION,
                e.span,
                format!("{what} of {} is longer than a day", show(ms)),
            )
            .label("over 24 h")
            .help("durations are in ms, s or min; check the number and the unit");
    }
    Some(ms)
}

/// `ms` as the language writes it: `30s`, `500ms`, `2min`.
fn literal(ms: f64) -> String {
    if ms >= 60_000.0 && ms % 60_000.0 == 0.0 {
        format!("{}min", ms / 60_000.0)
    } else if ms >= 1000.0 && ms % 1000.0 == 0.0 {
        format!("{}s", ms / 1000.0)
    } else {
        format!("{ms}ms")
    }
}

fn show(ms: f64) -> String {
    if ms.abs() >= 60_000.0 {
        format!("{} min", ms / 60_000.0)
    } else if ms.abs() >= 1000.0 {
        format!("{} s", ms / 1000.0)
    } else {
        format!("{ms} ms")
    }
}
