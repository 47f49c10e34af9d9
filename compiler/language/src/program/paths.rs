//! The paths an expression reads ([`Bound::paths`]): its own and those of the `let`s it
//! names, each once, in order of first appearance.

use super::*;

impl Bound {
    /// Wraps an expression, collecting its paths: its own and those of the `let`s it reads,
    /// in order of first appearance, each `let` once (one that reads few paths has them
    /// listed already; the others are walked without recursion, so the cost is linear in
    /// the `let`s reached).
    pub fn new(expr: Expr) -> Bound {
        let paths = expr_paths(&expr);
        Bound { expr, paths }
    }
}

/// Every path `e` reads, through its `let`s too, each once, in order of first appearance
/// ([`Bound::paths`]), in one walk: a `let` is taken apart where it first appears.
fn expr_paths(e: &Expr) -> Vec<Path> {
    let mut set = PathSet::new(usize::MAX);
    e.walk(&mut |x| match &x.node {
        Node::Path(p) => {
            set.path(p);
        }
        Node::Let(l) => {
            set.read_let(&l.0);
        }
        _ => {}
    });
    // Most expressions read one path or none: no room kept for more.
    set.paths.shrink_to_fit();
    set.paths
}

/// Every path of `reads` and of the `let`s they name, each once, in order of appearance;
/// `None` when there are more than `limit`.
pub(super) fn collect_paths_upto(reads: &[Read], limit: usize) -> Option<Vec<Path>> {
    let mut set = PathSet::new(limit);
    set.reads(reads).then_some(set.paths)
}

/// Paths collected once each, in order, up to a limit; each `let` taken apart once.
struct PathSet<'e> {
    paths: Vec<Path>,
    seen_paths: Seen<&'e Path>,
    seen_lets: Seen<*const Let>,
    limit: usize,
}

impl<'e> PathSet<'e> {
    fn new(limit: usize) -> PathSet<'e> {
        PathSet {
            paths: Vec::new(),
            seen_paths: Seen::default(),
            seen_lets: Seen::default(),
            limit,
        }
    }

    /// Adds `p` unless it is there; false when that makes more than the limit.
    fn path(&mut self, p: &'e Path) -> bool {
        if self.seen_paths.insert(p) {
            if self.paths.len() == self.limit {
                return false;
            }
            self.paths.push(p.clone());
        }
        true
    }

    /// Adds the paths a `let` reads (listed, or through its reads), unless it was seen.
    fn read_let(&mut self, l: &'e Let) -> bool {
        if !self.seen_lets.insert(l as *const Let) {
            return true;
        }
        match &l.paths {
            Some(ps) => ps.iter().all(|p| self.path(p)),
            None => self.reads(&l.reads),
        }
    }

    /// Adds the paths of `reads`, walking the `let`s they name without recursion.
    fn reads(&mut self, reads: &'e [Read]) -> bool {
        let mut stack: Vec<(&[Read], usize)> = vec![(reads, 0)];
        while let Some((list, i)) = stack.pop() {
            let Some(r) = list.get(i) else { continue };
            stack.push((list, i + 1));
            match r {
                Read::Path(p) => {
                    if !self.path(p) {
                        return false;
                    }
                }
                Read::Let(l) => {
                    if !self.seen_lets.insert(Arc::as_ptr(&l.0)) {
                        continue;
                    }
                    match &l.0.paths {
                        Some(ps) => {
                            if !ps.iter().all(|p| self.path(p)) {
                                return false;
                            }
                        }
                        None => stack.push((&l.0.reads, 0)),
                    }
                }
            }
        }
        true
    }
}

/// A set that is a short list while small (most expressions read a path or two: no hashing,
/// no allocation until the second element) and a hash set past [`Seen::LIST`] elements.
pub(super) struct Seen<T> {
    list: Vec<T>,
    set: crate::passes::FastSet<T>,
}

impl<T> Default for Seen<T> {
    fn default() -> Seen<T> {
        Seen { list: Vec::new(), set: Default::default() }
    }
}

impl<T: Eq + std::hash::Hash + Copy> Seen<T> {
    const LIST: usize = 16;
    /// True when `x` was not in the set yet.
    pub(super) fn insert(&mut self, x: T) -> bool {
        if self.set.is_empty() {
            if self.list.contains(&x) {
                return false;
            }
            if self.list.len() < Self::LIST {
                self.list.push(x);
                return true;
            }
            self.set.extend(self.list.drain(..));
        }
        self.set.insert(x)
    }
}
