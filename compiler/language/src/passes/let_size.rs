//! The guard on `let` inlining (E0106), used by `check_types`: a `let` is copied into every
//! use, so `let a1 = a0 + a0`, `let a2 = a1 + a1`, … doubles the checked program per line.
//! Every lowered expression counts its nodes with the `let`s it names put in place (each
//! `let`'s count is kept with its value, so counting is linear in the source); an expression
//! over [`MAX_EXPANDED`] nodes, or one whose copies of `let`s take the file past
//! [`MAX_TOTAL`] copied nodes, is reported where it is written and becomes `{error}`, and a
//! `let` use that would overflow is not copied. An expression that names a refused `let` is
//! refused silently (one mistake, one diagnostic). So no input can make `check` hang or
//! exhaust memory through `let`s; plain source, however long, is never refused here.

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::source::Span;

/// The most nodes one expression may have once the `let`s it names are put in place.
pub const MAX_EXPANDED: usize = 20_000;
/// The most nodes that copies of `let`s may add to a layout (and what it uses) in all.
pub const MAX_TOTAL: usize = 1_000_000;

/// Counts nodes of the expression being lowered and of the whole file.
#[derive(Debug, Default)]
pub struct SizeGuard {
    /// How deep `lower` is nested; 0 between expressions.
    depth: usize,
    /// Nodes of the expression being lowered so far, `let`s put in place.
    nodes: usize,
    /// Nodes added so far by copying `let`s into their uses.
    total: usize,
    total_reported: bool,
    /// The expression being lowered names a refused `let` (its own refusal is not reported).
    tainted: bool,
}

/// What `SizeGuard::leave` decided about the expression just lowered.
pub enum Verdict {
    /// A nested expression, or a root within the bounds (with its expanded size).
    Keep(usize),
    /// A root over a bound: reported; lower it as `{error}` (counts 1 node).
    Refuse,
}

impl SizeGuard {
    /// Entering `lower` for one node.
    pub fn enter(&mut self) {
        if self.depth == 0 {
            self.nodes = 0;
            self.tainted = false;
        }
        self.depth += 1;
        self.nodes += 1;
    }

    /// Leaving `lower`; `span` is the node's. At the outermost level, reports an expression
    /// over a bound.
    pub fn leave(&mut self, span: Span, diags: &mut Diagnostics) -> Verdict {
        self.depth -= 1;
        if self.depth > 0 {
            return Verdict::Keep(self.nodes);
        }
        let n = self.nodes;
        if n > MAX_EXPANDED && self.tainted {
            return Verdict::Refuse;
        }
        if n > MAX_EXPANDED {
            diags
                .error(
                    codes::TOO_DEEP,
                    span,
                    format!(
                        "this expression expands to {n} nodes once the `let`s it names are put in place (at most {MAX_EXPANDED})"
                    ),
                )
                .label("too large to check")
                .help("each use of a `let` copies its value: split the expression or use fewer repeated references to the same `let`s");
            return Verdict::Refuse;
        }
        if self.total > MAX_TOTAL && !self.total_reported {
            self.total_reported = true;
            diags
                .error(
                    codes::TOO_DEEP,
                    span,
                    format!(
                        "copies of `let`s put in place add more than {MAX_TOTAL} nodes to the layout by here"
                    ),
                )
                .label("too large to check")
                .help("each use of a `let` copies its value, and each `let` built on the one before copies it again: use fewer chained or repeated `let`s");
            self.nodes = MAX_EXPANDED + 1;
            return Verdict::Refuse;
        }
        Verdict::Keep(n)
    }

    /// A use of a `let` whose value has `size` nodes (over [`MAX_EXPANDED`]: refused): counts
    /// it, and says whether it may be copied (false: over a bound, which `leave` reports
    /// unless the `let` was refused already; the use becomes `{error}`).
    pub fn use_let(&mut self, size: usize) -> bool {
        let extra = size.saturating_sub(1);
        self.nodes = self.nodes.saturating_add(extra);
        if size > MAX_EXPANDED || (self.total > MAX_TOTAL && self.total_reported) {
            self.tainted = true;
        }
        let ok = self.nodes <= MAX_EXPANDED && self.total <= MAX_TOTAL;
        if ok {
            self.total = self.total.saturating_add(extra);
        }
        ok
    }

    /// Lowers a top-level `let` out of line: the expression being lowered is set aside.
    pub fn set_aside(&mut self) -> (usize, usize, bool) {
        let saved = (self.depth, self.nodes, self.tainted);
        self.depth = 0;
        saved
    }

    /// Expanded size of the root just lowered, then back to the expression set aside.
    pub fn restore(&mut self, saved: (usize, usize, bool)) -> usize {
        let n = self.nodes;
        (self.depth, self.nodes, self.tainted) = saved;
        n
    }

    /// Expanded size of the root just lowered (after `leave`).
    pub fn last(&self) -> usize {
        self.nodes
    }
}
