//! Lowering: the checked program's typed expressions to the JIT's IR. Every path becomes an
//! input slot; the list of slots is the expression's subscription set. A `let` becomes a
//! local of the function, lowered once however many times it is read (an untyped one once
//! per type it is read as; a widget argument that its siblings name, once per function too);
//! so what is lowered is as large as the checked program, which is as large as the source.
//!
//! Shared by the live layout (`mocu-layout`) and the widget renderer (`mocu-widgets`, which
//! compiles component bodies), so that neither reaches into the other. [`convert`] turns
//! world-model values into input slots and results back into values, the one rule both use.
//!
//! Architecture invariant: compiler side: knows nothing of the DataServer, threads or I/O.

#![forbid(unsafe_code)]

pub mod convert;
mod data;

pub use data::data_params;

use mocu_jit as jit;
use mocu_language::program::{
    Arg, Expr, FormatPart, FormatSpec, Let, LetRef, Node, Path, PathBase,
};
use mocu_language::types::{Type, TypeKind};
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

/// Where a path starts.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Base {
    Root,
    /// A template variable: the instance's object.
    Var(String),
    /// `self` in a menu: the object the menu was opened on.
    SelfObject,
    /// `selected` in an action: the object whose GUID is in `root.operator.selected`.
    Selected,
}

/// Where an input slot's value comes from.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Source {
    /// A property reached by object names from a base.
    Path { base: Base, objects: Vec<String>, property: String },
    /// A binding's implicit value (`axis`, `delta`).
    Input(String),
    /// A component parameter (`value`, `range.min`, `w`, …) when drawing.
    Param(String),
    /// The position of a template instance.
    Index,
    /// The value of a `let` that several functions read: computed once, by a function of
    /// its own (the layout makes it a node of its graph, see [`Lowerer::sharing`]), and read
    /// here as `ty`. Named by the `let`'s number and digest (see `LetRef`'s `PartialEq`).
    Let { id: u32, digest: u64 },
}

/// Why an expression could not be lowered (a construct the checker accepted but that has
/// no value here, e.g. an object used as a number). Reported, never a panic.
#[derive(Clone, Debug, PartialEq)]
pub struct LowerError(pub String);

impl std::fmt::Display for LowerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// What names mean while lowering.
pub enum Scope<'a> {
    /// A widget's arguments: `Param(x)` is the sibling argument `x`; `w`/`h` its size.
    Widget { args: &'a [Arg], at: &'a [mocu_language::program::Bound] },
    /// A component body: parameters and `w`/`h` are input slots the renderer fills.
    Component,
    /// Anything else (windows, watches, actions, bindings).
    Plain,
}

/// Lowers expressions of one function, collecting its input slots and its locals.
pub struct Lowerer<'a> {
    pub slots: Vec<(Source, jit::Ty)>,
    /// The function's locals ([`jit::Function::locals`]): the `let`s and sibling arguments
    /// its expressions read, each lowered once, each after those it reads.
    pub locals: Vec<jit::Expr>,
    /// Which local holds a `let` (by address; `held` keeps it alive) or an argument, read
    /// as a type.
    local_of: HashMap<(Local, jit::Ty), u32>,
    held: Vec<LetRef>,
    scope: Scope<'a>,
    /// Screen size, to turn `%` into pixels.
    screen: (f64, f64),
    depth: u32,
    /// The `let`s read through a [`Source::Let`] slot instead of as locals ([`Lowerer::sharing`]).
    shared: Option<Arc<HashSet<(u32, u64)>>>,
    /// Each `let` read through a [`Source::Let`] slot, and as what, once each: who compiles
    /// this function compiles theirs too.
    pub shared_reads: Vec<(LetRef, jit::Ty)>,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Local {
    Let(*const Let),
    Arg(String),
}

/// The JIT type of a checked type, if it has one on its own.
pub fn value_ty(t: &Type) -> Option<jit::Ty> {
    match t.kind {
        TypeKind::Number { .. } | TypeKind::Duration => Some(jit::Ty::Num),
        TypeKind::Bool => Some(jit::Ty::Bool),
        TypeKind::String => Some(jit::Ty::Str),
        TypeKind::Colour => Some(jit::Ty::Color),
        _ => None,
    }
}

impl<'a> Lowerer<'a> {
    pub fn new(scope: Scope<'a>, screen: (f64, f64)) -> Lowerer<'a> {
        Lowerer {
            slots: Vec::new(),
            locals: Vec::new(),
            local_of: HashMap::new(),
            held: Vec::new(),
            scope,
            screen,
            depth: 0,
            shared: None,
            shared_reads: Vec::new(),
        }
    }

    /// Reads the `let`s of `shared` (by number and digest) through [`Source::Let`] slots,
    /// recorded in [`Lowerer::shared_reads`], instead of lowering them as locals: a `let`
    /// that many functions read is then lowered and evaluated once, not once per function.
    /// Only for `let`s whose value reads nothing but paths from the root (no parameter,
    /// template variable, input, `self` or index): their value is the same for every reader.
    pub fn sharing(mut self, shared: Arc<HashSet<(u32, u64)>>) -> Lowerer<'a> {
        self.shared = Some(shared);
        self
    }

    fn shared_slot(&mut self, l: &LetRef, ty: jit::Ty) -> Option<jit::Expr> {
        let key = (l.id, l.digest);
        if !self.shared.as_ref().is_some_and(|s| s.contains(&key)) {
            return None;
        }
        let source = Source::Let { id: key.0, digest: key.1 };
        let before = self.slots.len();
        let e = self.slot(source, ty);
        if self.slots.len() > before {
            self.shared_reads.push((l.clone(), ty));
        }
        Some(e)
    }

    /// The screen size it was made for.
    pub fn screen(&self) -> (f64, f64) {
        self.screen
    }

    /// The function of `outputs` lowered by this lowerer, and its slots.
    pub fn finish(self, outputs: Vec<jit::Expr>) -> (jit::Function, Vec<(Source, jit::Ty)>) {
        let inputs = self.slots.iter().map(|s| s.1).collect();
        (jit::Function { inputs, locals: self.locals, outputs }, self.slots)
    }

    fn push_local(&mut self, key: Local, ty: jit::Ty, e: jit::Expr) -> jit::Expr {
        self.locals.push(e);
        let i = (self.locals.len() - 1) as u32;
        self.local_of.insert((key, ty), i);
        jit::Expr::Local(i, ty)
    }

    /// A `let` computed once per evaluation ([`Let::is_local`]): its local, lowered now if
    /// it is not yet, after every local `let` it reads (found without recursion, deepest
    /// first, and each lowered out of line at depth 0: a chain of 50,000 `let`s is lowered
    /// 50,000 times one level deep, not once 50,000 levels deep).
    fn let_local(&mut self, l: &LetRef) -> Result<jit::Expr, LowerError> {
        let ty = |l: &Let| value_ty(&l.value.ty).unwrap_or(jit::Ty::Num);
        if let Some(i) = self.local_of.get(&(Local::Let(Arc::as_ptr(&l.0)), ty(l))) {
            return Ok(jit::Expr::Local(*i, ty(l)));
        }
        for dep in self.unlowered_lets(l) {
            let t = ty(&dep);
            let saved = std::mem::replace(&mut self.depth, 0);
            let e = self.lower(&dep.value, t);
            self.depth = saved;
            let e = e?;
            self.push_local(Local::Let(Arc::as_ptr(&dep.0)), t, e);
            self.held.push(dep);
        }
        Ok(jit::Expr::Local(self.local_of[&(Local::Let(Arc::as_ptr(&l.0)), ty(l))], ty(l)))
    }

    /// The local `let`s that `l` reads (through any `let`), `l` last, not yet lowered, each
    /// after those it reads. Iterative depth-first search.
    fn unlowered_lets(&self, l: &LetRef) -> Vec<LetRef> {
        // A shared `let` is read through its slot: neither it nor what it reads is lowered here.
        let lowered = |x: &Let| {
            let t = value_ty(&x.value.ty).unwrap_or(jit::Ty::Num);
            self.local_of.contains_key(&(Local::Let(x as *const Let), t))
                || self.shared.as_ref().is_some_and(|s| s.contains(&(x.id, x.digest)))
        };
        let mut order = Vec::new();
        let mut seen: HashSet<*const Let> = HashSet::new();
        seen.insert(Arc::as_ptr(&l.0));
        let mut stack: Vec<(LetRef, usize)> = vec![(l.clone(), 0)];
        while let Some((cur, i)) = stack.pop() {
            let next = cur.reads[i..].iter().position(|r| {
                matches!(r, mocu_language::program::Read::Let(d)
                    if !seen.contains(&Arc::as_ptr(&d.0)) && !lowered(d))
            });
            match next {
                Some(k) => {
                    let mocu_language::program::Read::Let(d) = &cur.reads[i + k] else {
                        unreachable!("position found a let")
                    };
                    let d = d.clone();
                    seen.insert(Arc::as_ptr(&d.0));
                    stack.push((cur, i + k + 1));
                    stack.push((d, 0));
                }
                None => {
                    if cur.is_local() {
                        order.push(cur);
                    }
                }
            }
        }
        order
    }

    fn slot(&mut self, source: Source, ty: jit::Ty) -> jit::Expr {
        let i = match self.slots.iter().position(|(s, t)| *s == source && *t == ty) {
            Some(i) => i,
            None => {
                self.slots.push((source, ty));
                self.slots.len() - 1
            }
        };
        jit::Expr::Input(i as u32, ty)
    }

    /// Lowers a rectangle coordinate: `%` of the screen's width (`horizontal`) or height.
    pub fn coordinate(&mut self, e: &Expr, horizontal: bool) -> Result<jit::Expr, LowerError> {
        let v = self.lower(e, jit::Ty::Num)?;
        if e.ty.unit() == Some("%") {
            let dim = if horizontal { self.screen.0 } else { self.screen.1 };
            return Ok(jit::Expr::Arith(
                jit::Arith::Mul,
                Box::new(v),
                Box::new(jit::Expr::Num(dim / 100.0)),
            ));
        }
        Ok(v)
    }

    /// Lowers `e` as a value of type `want` where its own type does not decide (dynamic
    /// paths take the type their use needs).
    pub fn lower(&mut self, e: &Expr, want: jit::Ty) -> Result<jit::Expr, LowerError> {
        self.depth += 1;
        if self.depth as usize > mocu_language::passes::check_depth::MAX_DEPTH {
            // `mocu check` reports this first (E0106, passes/check_depth.rs).
            return Err(LowerError("arguments refer to each other too deeply (a cycle?)".into()));
        }
        let r = self.lower_inner(e, want);
        self.depth -= 1;
        r
    }

    fn lower_inner(&mut self, e: &Expr, want: jit::Ty) -> Result<jit::Expr, LowerError> {
        let ty = value_ty(&e.ty).unwrap_or(want);
        let bx = Box::new;
        Ok(match &e.node {
            Node::Number(x) | Node::Duration(x) => jit::Expr::Num(*x),
            Node::Bool(b) => jit::Expr::Bool(*b),
            Node::Str(s) => jit::Expr::Str(Arc::from(s.as_str())),
            Node::Colour(c) => jit::Expr::Color(*c),
            Node::Path(p) => {
                let source = self.path_source(p)?;
                self.slot(source, ty)
            }
            Node::Let(l) if let Some(e) = self.shared_slot(l, ty) => e,
            Node::Let(l) if l.is_local() => self.let_local(l)?,
            // Its uses decide what it is read as: lowered where it is first read as `ty`
            // (its depth counts there, as `check_depth` counts it), then shared as a local.
            Node::Let(l) => {
                let key = (Local::Let(Arc::as_ptr(&l.0)), ty);
                if let Some(i) = self.local_of.get(&key) {
                    return Ok(jit::Expr::Local(*i, ty));
                }
                let e = self.lower(&l.value, ty)?;
                self.held.push(l.clone());
                self.push_local(key.0, ty, e)
            }
            Node::Param(name) => match &self.scope {
                Scope::Widget { args, .. } => match args.iter().find(|a| &a.name == name) {
                    Some(a) => {
                        // A sibling argument: lowered once per function and type, in place
                        // (its depth counts where it is read, as `check_depth` counts it).
                        let key = (Local::Arg(name.clone()), ty);
                        if let Some(i) = self.local_of.get(&key) {
                            return Ok(jit::Expr::Local(*i, ty));
                        }
                        let arg = a.value.expr.clone();
                        let e = self.lower(&arg, ty)?;
                        self.push_local(key.0, ty, e)
                    }
                    None => jit::Expr::Absent(ty),
                },
                Scope::Component => self.slot(Source::Param(name.clone()), ty),
                Scope::Plain => return Err(LowerError(format!("`{name}` has no value here"))),
            },
            Node::Size(n) => match &self.scope {
                Scope::Widget { at, .. } => {
                    let i = if n == "w" { 2 } else { 3 };
                    match at.get(i) {
                        Some(b) => {
                            let x = b.expr.clone();
                            self.lower(&x, jit::Ty::Num)?
                        }
                        None => jit::Expr::Absent(jit::Ty::Num),
                    }
                }
                _ => self.slot(Source::Param(n.clone()), jit::Ty::Num),
            },
            Node::Input(n) => self.slot(Source::Input(n.clone()), jit::Ty::Num),
            Node::Index => self.slot(Source::Index, jit::Ty::Num),
            Node::RangeEnd { range, max } => self.range_end(range, *max)?,
            Node::Range { .. } => return Err(LowerError("a range is not a single value".into())),
            Node::Unary { op, arg } => match op {
                mocu_language::ast::UnOp::Neg => jit::Expr::Neg(bx(self.lower(arg, jit::Ty::Num)?)),
                mocu_language::ast::UnOp::Not => {
                    jit::Expr::Not(bx(self.lower(arg, jit::Ty::Bool)?))
                }
            },
            Node::Binary { op, lhs, rhs } => self.binary(*op, lhs, rhs, ty)?,
            Node::If { cond, then, other } => jit::Expr::If(
                bx(self.lower(cond, jit::Ty::Bool)?),
                bx(self.lower(then, ty)?),
                bx(self.lower(other, ty)?),
            ),
            Node::Call { function, args } => self.call(function, args, ty)?,
            Node::Format(parts) => {
                let mut pieces = Vec::new();
                for p in parts {
                    pieces.push(match p {
                        FormatPart::Text(t) => jit::Piece::Text(Arc::from(t.as_str())),
                        // An absent part shows as `—`; the rest of the text stays.
                        FormatPart::Value { expr, spec } => {
                            let part = self.piece(expr, spec.as_ref().map(num_format))?;
                            jit::Piece::Str(jit::Expr::Coalesce(
                                Box::new(jit::Expr::Format(vec![part])),
                                Box::new(jit::Expr::Str(Arc::from(ABSENT_PART))),
                            ))
                        }
                    });
                }
                jit::Expr::Format(pieces)
            }
        })
    }

    fn piece(&mut self, e: &Expr, spec: Option<jit::NumFormat>) -> Result<jit::Piece, LowerError> {
        let ty =
            value_ty(&e.ty).unwrap_or(if spec.is_some() { jit::Ty::Num } else { jit::Ty::Str });
        Ok(match ty {
            jit::Ty::Num => jit::Piece::Num(self.lower(e, ty)?, spec.unwrap_or_default()),
            jit::Ty::Str => jit::Piece::Str(self.lower(e, ty)?),
            jit::Ty::Bool => jit::Piece::Bool(self.lower(e, ty)?),
            jit::Ty::Color => {
                return Err(LowerError("a colour cannot be written in a string".into()));
            }
        })
    }

    fn range_end(&mut self, range: &Expr, max: bool) -> Result<jit::Expr, LowerError> {
        match &range.peel().node {
            Node::Range { lo, hi } => self.lower(if max { hi } else { lo }, jit::Ty::Num),
            Node::Binary { op: mocu_language::ast::BinOp::Range, lhs, rhs } => {
                self.lower(if max { rhs } else { lhs }, jit::Ty::Num)
            }
            Node::Param(name) => match &self.scope {
                Scope::Widget { args, .. } => match args.iter().find(|a| &a.name == name) {
                    Some(a) => {
                        let r = a.value.expr.clone();
                        self.range_end(&r, max)
                    }
                    None => Ok(jit::Expr::Absent(jit::Ty::Num)),
                },
                Scope::Component => {
                    let end = if max { "max" } else { "min" };
                    Ok(self.slot(Source::Param(format!("{name}.{end}")), jit::Ty::Num))
                }
                Scope::Plain => Err(LowerError(format!("`{name}` has no value here"))),
            },
            _ => Err(LowerError("`.min`/`.max` of something that is not a range".into())),
        }
    }

    fn binary(
        &mut self,
        op: mocu_language::ast::BinOp,
        l: &Expr,
        r: &Expr,
        ty: jit::Ty,
    ) -> Result<jit::Expr, LowerError> {
        use mocu_language::ast::BinOp as B;
        let bx = Box::new;
        let num = |s: &mut Self, e: &Expr| s.lower(e, jit::Ty::Num).map(Box::new);
        Ok(match op {
            B::Coalesce => jit::Expr::Coalesce(bx(self.lower(l, ty)?), bx(self.lower(r, ty)?)),
            B::Range => return Err(LowerError("a range is not a single value".into())),
            B::Or => {
                jit::Expr::Or(bx(self.lower(l, jit::Ty::Bool)?), bx(self.lower(r, jit::Ty::Bool)?))
            }
            B::And => {
                jit::Expr::And(bx(self.lower(l, jit::Ty::Bool)?), bx(self.lower(r, jit::Ty::Bool)?))
            }
            B::Eq | B::Ne => {
                let t = value_ty(&l.ty).or(value_ty(&r.ty)).unwrap_or(jit::Ty::Num);
                let cmp = if op == B::Eq { jit::Cmp::Eq } else { jit::Cmp::Ne };
                jit::Expr::Cmp(cmp, bx(self.lower(l, t)?), bx(self.lower(r, t)?))
            }
            B::Lt | B::Le | B::Gt | B::Ge => {
                let cmp = match op {
                    B::Lt => jit::Cmp::Lt,
                    B::Le => jit::Cmp::Le,
                    B::Gt => jit::Cmp::Gt,
                    _ => jit::Cmp::Ge,
                };
                jit::Expr::Cmp(cmp, num(self, l)?, num(self, r)?)
            }
            B::Add if ty == jit::Ty::Str => jit::Expr::Format(vec![
                jit::Piece::Str(self.lower(l, jit::Ty::Str)?),
                jit::Piece::Str(self.lower(r, jit::Ty::Str)?),
            ]),
            B::Add | B::Sub | B::Mul | B::Div => {
                let a = match op {
                    B::Add => jit::Arith::Add,
                    B::Sub => jit::Arith::Sub,
                    B::Mul => jit::Arith::Mul,
                    _ => jit::Arith::Div,
                };
                jit::Expr::Arith(a, num(self, l)?, num(self, r)?)
            }
        })
    }

    fn call(&mut self, f: &str, args: &[Expr], ty: jit::Ty) -> Result<jit::Expr, LowerError> {
        match f {
            "present" => {
                let a = args.first().ok_or_else(|| LowerError("present() needs a value".into()))?;
                let t = value_ty(&a.ty).unwrap_or(jit::Ty::Num);
                Ok(jit::Expr::Present(Box::new(self.lower(a, t)?)))
            }
            "format" => {
                let a = args.first().ok_or_else(|| LowerError("format() needs a value".into()))?;
                let spec = match args.get(1).map(|s| &s.node) {
                    Some(Node::Str(s)) => parse_spec(s).as_ref().map(num_format),
                    _ => None,
                };
                Ok(jit::Expr::Format(vec![self.piece(a, spec)?]))
            }
            name => {
                let b = jit::Builtin::by_name(name)
                    .ok_or_else(|| LowerError(format!("`{name}` is not a built-in function")))?;
                if args.len() != b.arity() {
                    return Err(LowerError(format!("`{name}` takes {} arguments", b.arity())));
                }
                let args =
                    args.iter().map(|a| self.lower(a, jit::Ty::Num)).collect::<Result<_, _>>()?;
                let _ = ty;
                Ok(jit::Expr::Call(b, args))
            }
        }
    }

    /// Where a path's value comes from: its base, then object names, then the property.
    pub fn path_source(&mut self, p: &Path) -> Result<Source, LowerError> {
        let (base, mut names) = self.path_names(p)?;
        let property = names.pop().ok_or_else(|| LowerError(format!("`{p}` names no property")))?;
        Ok(Source::Path { base, objects: names, property })
    }

    /// A path's base and all its names (an object path: a method target, a source).
    pub fn path_names(&mut self, p: &Path) -> Result<(Base, Vec<String>), LowerError> {
        match &p.base {
            PathBase::Root => Ok((Base::Root, p.segments.clone())),
            PathBase::SelfObject => Ok((Base::SelfObject, p.segments.clone())),
            PathBase::Var(v) => Ok((Base::Var(v.clone()), p.segments.clone())),
            PathBase::Selected => Ok((Base::Selected, p.segments.clone())),
            PathBase::Param(name) => {
                let Scope::Widget { args, .. } = &self.scope else {
                    return Err(LowerError(format!("`{name}` is not an object here")));
                };
                let Some(Node::Path(inner)) =
                    args.iter().find(|a| &a.name == name).map(|a| &a.value.expr.node)
                else {
                    return Err(LowerError(format!("`{name}` is not a path to an object")));
                };
                let inner = inner.clone();
                let (base, mut names) = self.path_names(&inner)?;
                names.extend(p.segments.iter().cloned());
                Ok((base, names))
            }
        }
    }
}

/// What an interpolation shows for a part whose value is absent.
pub const ABSENT_PART: &str = "—";

/// The widest a formatted number is padded to, in characters.
pub const MAX_WIDTH: u32 = 64;
/// The most digits written after the point (an f64 has 17 significant digits).
pub const MAX_PRECISION: u32 = 17;

/// A checked format spec (`{x:03.1}` or `format(x, "03.1")`) as the JIT's number format:
/// one rule for both, width clamped to [`MAX_WIDTH`], precision to [`MAX_PRECISION`].
pub fn num_format(s: &FormatSpec) -> jit::NumFormat {
    jit::NumFormat {
        zero: s.zero,
        width: s.width.filter(|w| *w > 0).map(|w| w.min(MAX_WIDTH) as u8),
        precision: s.precision.map(|p| p.min(MAX_PRECISION) as u8),
    }
}

/// `format()`'s spec string, parsed by the checker's one parser (`[0][width][.precision]`);
/// `None` when the checker refuses it.
pub fn parse_spec(s: &str) -> Option<FormatSpec> {
    mocu_language::passes::check_types::parse_spec(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolations_and_format_share_one_spec_rule() {
        let cases = [
            ("03.1", jit::NumFormat { zero: true, width: Some(3), precision: Some(1) }),
            (".2", jit::NumFormat { zero: false, width: None, precision: Some(2) }),
            ("200", jit::NumFormat { zero: false, width: Some(64), precision: None }),
            ("0300.30", jit::NumFormat { zero: true, width: Some(64), precision: Some(17) }),
            ("0", jit::NumFormat { zero: false, width: None, precision: None }),
        ];
        for (spec, want) in cases {
            let parsed = parse_spec(spec).unwrap_or_else(|| panic!("{spec} parses"));
            assert_eq!(num_format(&parsed), want, "{spec}");
        }
        assert_eq!(parse_spec("x1"), None, "what the checker refuses");
    }
}
