//! The expression IR: what the JIT and the reference interpreter both execute.
//!
//! # Semantics (docs/language.md, "Evaluation")
//! - Four value types: `Num` (f64), `Bool`, `Str`, `Color` (RGBA8 packed as `0xRRGGBBAA`).
//!   Every value may be **absent**.
//! - A present number is always finite: any operation whose result is NaN or ±∞ (division
//!   by zero, `sqrt(-1)`, overflow to infinity) gives *absent*, never a silent NaN or zero.
//!   World-model integers are read as f64 (exact up to 2^53; beyond that they round).
//! - Operators and functions are strict: an absent operand gives an absent result — except
//!   `and`/`or` (Kleene logic: `false and absent` is `false`, `true or absent` is `true`),
//!   `a ?? b` (the first present), `present(a)` (always present), and `if`, whose absent
//!   condition gives absent but whose unselected branch does not matter.
//! - An interpolated string with an absent part is absent (write `"{x}" ?? "--"`).
//! - `min`/`max` pick by `<` (so `min(-0, 0)` is the first operand), `round` rounds half
//!   away from zero, `mod` takes the sign of the divisor.
//! - A function's locals (a layout's `let`s) are computed once per call, in order, before
//!   its outputs; [`Expr::Local`] reads one. Evaluation has no side effects, so this is the
//!   value the local's expression would have where it is read.
//!
//! # Limits
//! Both backends, and [`Expr::check`], recurse over the tree. [`Function::check`] measures
//! every expression's depth first, without recursing, and refuses one deeper than
//! [`MAX_DEPTH`] with an [`IrError`], so that no IR, however it was built, overflows the
//! stack. Dropping an expression does not recurse either.

use std::sync::Arc;

/// The deepest expression tree the backends accept (see "Limits"). `mocu-lower` refuses
/// source expressions nested deeper than 256 levels, and lowering makes at most three IR
/// levels of one (an interpolation: `Format`, `Coalesce`, `Format`); a caller that builds
/// IR directly gets an [`IrError`] past this. At this depth a debug build of either
/// backend stays well within a 2 MiB thread stack.
pub const MAX_DEPTH: usize = 768;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Ty {
    Num,
    Bool,
    Str,
    Color,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arith {
    Add,
    Sub,
    Mul,
    Div,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cmp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builtin {
    Min,
    Max,
    Abs,
    Clamp,
    Round,
    Floor,
    Ceil,
    Sqrt,
    Sin,
    Cos,
    Atan2,
    Deg,
    Rad,
    Mod,
    Lerp,
    Deadzone,
    Rgb,
    Rgba,
}

impl Builtin {
    pub fn arity(self) -> usize {
        use Builtin::*;
        match self {
            Abs | Round | Floor | Ceil | Sqrt | Sin | Cos | Deg | Rad => 1,
            Min | Max | Atan2 | Mod | Deadzone => 2,
            Clamp | Lerp | Rgb => 3,
            Rgba => 4,
        }
    }

    pub fn by_name(name: &str) -> Option<Builtin> {
        use Builtin::*;
        Some(match name {
            "min" => Min,
            "max" => Max,
            "abs" => Abs,
            "clamp" => Clamp,
            "round" => Round,
            "floor" => Floor,
            "ceil" => Ceil,
            "sqrt" => Sqrt,
            "sin" => Sin,
            "cos" => Cos,
            "atan2" => Atan2,
            "deg" => Deg,
            "rad" => Rad,
            "mod" => Mod,
            "lerp" => Lerp,
            "deadzone" => Deadzone,
            "rgb" => Rgb,
            "rgba" => Rgba,
            _ => return None,
        })
    }

    pub fn result(self) -> Ty {
        match self {
            Builtin::Rgb | Builtin::Rgba => Ty::Color,
            _ => Ty::Num,
        }
    }
}

/// How a number is written in a string: `{x:03.1}`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NumFormat {
    pub zero: bool,
    pub width: Option<u8>,
    pub precision: Option<u8>,
}

impl NumFormat {
    pub(crate) fn pack(self) -> i64 {
        (self.zero as i64)
            | (self.width.map_or(0, |w| w as i64 + 1) << 8)
            | (self.precision.map_or(0, |p| p as i64 + 1) << 16)
    }

    pub(crate) fn unpack(v: i64) -> NumFormat {
        let w = (v >> 8) & 0xff;
        let p = (v >> 16) & 0xff;
        NumFormat {
            zero: v & 1 == 1,
            width: (w > 0).then(|| (w - 1) as u8),
            precision: (p > 0).then(|| (p - 1) as u8),
        }
    }

    pub fn write(self, out: &mut String, x: f64) {
        use std::fmt::Write;
        let w = self.width.unwrap_or(0) as usize;
        let _ = match (self.precision, self.zero) {
            (Some(p), true) => write!(out, "{x:0w$.p$}", p = p as usize),
            (Some(p), false) => write!(out, "{x:w$.p$}", p = p as usize),
            (None, true) => write!(out, "{x:0w$}"),
            (None, false) => write!(out, "{x:w$}"),
        };
    }
}

/// One part of an interpolated string.
#[derive(Clone, Debug, PartialEq)]
pub enum Piece {
    Text(Arc<str>),
    Num(Expr, NumFormat),
    Str(Expr),
    Bool(Expr),
}

/// An expression. Build it well-typed (see [`Expr::check`]); both backends assume so.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    Num(f64),
    Bool(bool),
    Str(Arc<str>),
    Color(u32),
    Absent(Ty),
    /// Input slot `slot`, already converted to `ty` by whoever filled the slots.
    Input(u32, Ty),
    /// Local `i` of the function (computed once per call, before the outputs; a local may
    /// read only the locals before it).
    Local(u32, Ty),
    Neg(Box<Expr>),
    Not(Box<Expr>),
    Arith(Arith, Box<Expr>, Box<Expr>),
    /// `<` … `>=` on numbers; `==`/`!=` on any two values of one type.
    Cmp(Cmp, Box<Expr>, Box<Expr>),
    And(Box<Expr>, Box<Expr>),
    Or(Box<Expr>, Box<Expr>),
    If(Box<Expr>, Box<Expr>, Box<Expr>),
    Coalesce(Box<Expr>, Box<Expr>),
    Present(Box<Expr>),
    Call(Builtin, Vec<Expr>),
    Format(Vec<Piece>),
}

/// An IR type error: a bug in whoever lowered to IR (the checker should have caught it).
#[derive(Clone, Debug, PartialEq)]
pub struct IrError(pub String);

impl std::fmt::Display for IrError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ill-typed IR: {}", self.0)
    }
}

impl std::error::Error for IrError {}

impl Expr {
    /// The type of the expression, checking its operands; `inputs` gives each slot's type.
    /// An expression with locals is checked with its function ([`Function::check`]).
    pub fn check(&self, inputs: &[Ty]) -> Result<Ty, IrError> {
        self.check_depth()?;
        self.check_in(inputs, &[])
    }

    /// Refuses an expression deeper than [`MAX_DEPTH`], without recursing.
    pub fn check_depth(&self) -> Result<(), IrError> {
        let mut stack = vec![(self, 1usize)];
        while let Some((e, d)) = stack.pop() {
            if d > MAX_DEPTH {
                return Err(IrError(format!(
                    "the expression is nested more than {MAX_DEPTH} levels deep"
                )));
            }
            e.children(&mut |c| stack.push((c, d + 1)));
        }
        Ok(())
    }

    /// [`Expr::check`] once the depth is known to be within bounds; `locals` gives the type
    /// of each local the expression may read. Walks the tree with a stack of its own (its
    /// operands' types first, then the node's), so a deep tree costs heap, not stack.
    fn check_in(&self, inputs: &[Ty], locals: &[Ty]) -> Result<Ty, IrError> {
        let mut todo = vec![(self, false)];
        let mut types: Vec<Ty> = Vec::new();
        let mut kids = Vec::new();
        while let Some((e, operands_done)) = todo.pop() {
            if !operands_done {
                todo.push((e, true));
                e.children(&mut |c| kids.push(c));
                todo.extend(kids.drain(..).rev().map(|c| (c, false)));
                continue;
            }
            let mut n = 0;
            e.children(&mut |_| n += 1);
            let operands = types.split_off(types.len() - n);
            types.push(e.node_type(&operands, inputs, locals)?);
        }
        Ok(types[0])
    }

    /// The type of this node given its operands' types (in `children` order).
    fn node_type(&self, ops: &[Ty], inputs: &[Ty], locals: &[Ty]) -> Result<Ty, IrError> {
        let want = |i: usize, t: Ty| -> Result<(), IrError> {
            if ops[i] == t { Ok(()) } else { Err(self.mistyped(i, t, ops[i])) }
        };
        Ok(match self {
            Expr::Num(_) => Ty::Num,
            Expr::Bool(_) => Ty::Bool,
            Expr::Str(_) => Ty::Str,
            Expr::Color(_) => Ty::Color,
            Expr::Absent(t) => *t,
            Expr::Input(i, t) => match inputs.get(*i as usize) {
                Some(s) if s == t => *t,
                _ => return Err(IrError(format!("input {i} is not a {t:?}"))),
            },
            Expr::Local(i, t) => match locals.get(*i as usize) {
                Some(s) if s == t => *t,
                _ => return Err(IrError(format!("local {i} is not a {t:?} defined before"))),
            },
            Expr::Neg(_) | Expr::Arith(..) => {
                (0..ops.len()).try_for_each(|i| want(i, Ty::Num))?;
                Ty::Num
            }
            Expr::Not(_) | Expr::And(..) | Expr::Or(..) => {
                (0..ops.len()).try_for_each(|i| want(i, Ty::Bool))?;
                Ty::Bool
            }
            Expr::Cmp(op, ..) => {
                want(1, ops[0])?;
                if !matches!(op, Cmp::Eq | Cmp::Ne) && ops[0] != Ty::Num {
                    return Err(IrError(format!("{op:?} on {:?}", ops[0])));
                }
                Ty::Bool
            }
            Expr::If(..) => {
                want(0, Ty::Bool)?;
                want(2, ops[1])?;
                ops[1]
            }
            Expr::Coalesce(..) => {
                want(1, ops[0])?;
                ops[0]
            }
            Expr::Present(_) => Ty::Bool,
            Expr::Call(f, _) => {
                if ops.len() != f.arity() {
                    return Err(IrError(format!("{f:?} takes {} arguments", f.arity())));
                }
                (0..ops.len()).try_for_each(|i| want(i, Ty::Num))?;
                f.result()
            }
            Expr::Format(pieces) => {
                let mut i = 0;
                for p in pieces {
                    let t = match p {
                        Piece::Text(_) => continue,
                        Piece::Num(..) => Ty::Num,
                        Piece::Str(_) => Ty::Str,
                        Piece::Bool(_) => Ty::Bool,
                    };
                    want(i, t)?;
                    i += 1;
                }
                Ty::Str
            }
        })
    }

    /// Operand `i` has type `got` where this node needs `want` (named, not printed: the
    /// operand may be arbitrarily deep).
    #[cold]
    fn mistyped(&self, i: usize, want: Ty, got: Ty) -> IrError {
        let name = match self {
            Expr::Neg(_) => "Neg".to_string(),
            Expr::Not(_) => "Not".into(),
            Expr::Arith(op, ..) => format!("{op:?}"),
            Expr::Cmp(op, ..) => format!("{op:?}"),
            Expr::And(..) => "And".into(),
            Expr::Or(..) => "Or".into(),
            Expr::If(..) => "If".into(),
            Expr::Coalesce(..) => "Coalesce".into(),
            Expr::Call(f, _) => format!("{f:?}"),
            Expr::Format(_) => "Format".into(),
            _ => "a leaf".into(),
        };
        IrError(format!("expected {want:?}, got {got:?} as operand {i} of {name}"))
    }

    /// The type of a well-typed expression (see [`Expr::check`]).
    pub fn ty(&self) -> Ty {
        match self {
            Expr::Num(_) | Expr::Neg(_) | Expr::Arith(..) => Ty::Num,
            Expr::Bool(_)
            | Expr::Not(_)
            | Expr::Cmp(..)
            | Expr::And(..)
            | Expr::Or(..)
            | Expr::Present(_) => Ty::Bool,
            Expr::Str(_) | Expr::Format(_) => Ty::Str,
            Expr::Color(_) => Ty::Color,
            Expr::Absent(t) | Expr::Input(_, t) | Expr::Local(_, t) => *t,
            Expr::If(_, a, _) | Expr::Coalesce(a, _) => a.ty(),
            Expr::Call(f, _) => f.result(),
        }
    }

    /// The number of nodes (to split large layouts into small functions).
    pub fn size(&self) -> usize {
        let mut n = 0;
        self.walk(&mut |_| n += 1);
        n
    }

    fn walk(&self, f: &mut dyn FnMut(&Expr)) {
        let mut stack = vec![self];
        while let Some(e) = stack.pop() {
            f(e);
            e.children(&mut |c| stack.push(c));
        }
    }

    /// Calls `f` on each direct operand (one level: nothing here recurses).
    fn children<'a>(&'a self, f: &mut dyn FnMut(&'a Expr)) {
        match self {
            Expr::Neg(a) | Expr::Not(a) | Expr::Present(a) => f(a),
            Expr::Arith(_, a, b)
            | Expr::Cmp(_, a, b)
            | Expr::And(a, b)
            | Expr::Or(a, b)
            | Expr::Coalesce(a, b) => {
                f(a);
                f(b);
            }
            Expr::If(c, a, b) => {
                f(c);
                f(a);
                f(b);
            }
            Expr::Call(_, args) => args.iter().for_each(f),
            Expr::Format(ps) => {
                for p in ps {
                    if let Piece::Num(e, _) | Piece::Str(e) | Piece::Bool(e) = p {
                        f(e)
                    }
                }
            }
            Expr::Num(_)
            | Expr::Bool(_)
            | Expr::Str(_)
            | Expr::Color(_)
            | Expr::Absent(_)
            | Expr::Input(..)
            | Expr::Local(..) => {}
        }
    }

    /// Moves the operands that have operands of their own to `out`, leaving leaves behind.
    fn take_children(&mut self, out: &mut Vec<Expr>) {
        let mut take = |e: &mut Expr| {
            if !e.is_leaf() {
                out.push(std::mem::replace(e, Expr::Absent(Ty::Num)));
            }
        };
        match self {
            Expr::Neg(a) | Expr::Not(a) | Expr::Present(a) => take(a),
            Expr::Arith(_, a, b)
            | Expr::Cmp(_, a, b)
            | Expr::And(a, b)
            | Expr::Or(a, b)
            | Expr::Coalesce(a, b) => {
                take(a);
                take(b);
            }
            Expr::If(c, a, b) => {
                take(c);
                take(a);
                take(b);
            }
            Expr::Call(_, args) => args.iter_mut().for_each(take),
            Expr::Format(ps) => {
                for p in ps {
                    if let Piece::Num(e, _) | Piece::Str(e) | Piece::Bool(e) = p {
                        take(e)
                    }
                }
            }
            _ => {}
        }
    }

    fn is_leaf(&self) -> bool {
        let mut leaf = true;
        self.children(&mut |_| leaf = false);
        leaf
    }
}

/// Dropping a deep tree would recurse once per level: operands with operands are moved to
/// a list and dropped from there instead.
impl Drop for Expr {
    fn drop(&mut self) {
        let mut pending = Vec::new();
        self.take_children(&mut pending);
        while let Some(mut e) = pending.pop() {
            e.take_children(&mut pending);
        }
    }
}

/// A function: typed input slots in, one slot per output expression out. A widget's
/// expressions compile together as one function. Its locals are computed first, in order,
/// once per call; each may read the inputs and the locals before it, and the outputs read
/// any of them ([`Expr::Local`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Function {
    pub inputs: Vec<Ty>,
    pub locals: Vec<Expr>,
    pub outputs: Vec<Expr>,
}

impl Function {
    /// A function without locals.
    pub fn new(inputs: Vec<Ty>, outputs: Vec<Expr>) -> Function {
        Function { inputs, locals: Vec::new(), outputs }
    }

    /// The output types, checking every expression (depth first, see "Limits").
    pub fn check(&self) -> Result<Vec<Ty>, IrError> {
        let locals = self.local_types()?;
        self.outputs
            .iter()
            .map(|e| {
                e.check_depth()?;
                e.check_in(&self.inputs, &locals)
            })
            .collect()
    }

    /// The type of each local, checking each against the inputs and the locals before it.
    pub fn local_types(&self) -> Result<Vec<Ty>, IrError> {
        let mut types = Vec::with_capacity(self.locals.len());
        for e in &self.locals {
            e.check_depth()?;
            let t = e.check_in(&self.inputs, &types)?;
            types.push(t);
        }
        Ok(types)
    }
}
