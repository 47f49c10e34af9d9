//! Warning W0003: a watch whose condition is constant (it reads no path), so it fires at
//! start-up or never. Runs on the typed program, after constant folding is possible.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::program::*;

pub fn warn_constant_watch(program: &Program, diags: &mut Diagnostics) {
    let templates = program.templates.iter().flat_map(|t| t.watches.iter());
    for w in program.watches.iter().chain(templates) {
        if let Some(c) = w.when.expr.constant().and_then(|c| c.bool()) {
            diags
                .warning(
                    codes::CONSTANT_WATCH,
                    w.when.expr.span,
                    format!("the condition of watch `{}` is always {c}", w.name),
                )
                .label("reads no property")
                .help(if c {
                    "it fires once at start-up; a watch should read the world model"
                } else {
                    "it never fires"
                });
        }
    }
}
