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

use std::sync::Arc;

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
    pub fn check(&self, inputs: &[Ty]) -> Result<Ty, IrError> {
        let want = |e: &Expr, t: Ty| -> Result<(), IrError> {
            let got = e.check(inputs)?;
            if got == t {
                Ok(())
            } else {
                Err(IrError(format!("expected {t:?}, got {got:?} in {e:?}")))
            }
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
            Expr::Neg(a) => {
                want(a, Ty::Num)?;
                Ty::Num
            }
            Expr::Not(a) => {
                want(a, Ty::Bool)?;
                Ty::Bool
            }
            Expr::Arith(_, a, b) => {
                want(a, Ty::Num)?;
                want(b, Ty::Num)?;
                Ty::Num
            }
            Expr::Cmp(op, a, b) => {
                let t = a.check(inputs)?;
                want(b, t)?;
                if !matches!(op, Cmp::Eq | Cmp::Ne) && t != Ty::Num {
                    return Err(IrError(format!("{op:?} on {t:?}")));
                }
                Ty::Bool
            }
            Expr::And(a, b) | Expr::Or(a, b) => {
                want(a, Ty::Bool)?;
                want(b, Ty::Bool)?;
                Ty::Bool
            }
            Expr::If(c, a, b) => {
                want(c, Ty::Bool)?;
                let t = a.check(inputs)?;
                want(b, t)?;
                t
            }
            Expr::Coalesce(a, b) => {
                let t = a.check(inputs)?;
                want(b, t)?;
                t
            }
            Expr::Present(a) => {
                a.check(inputs)?;
                Ty::Bool
            }
            Expr::Call(f, args) => {
                if args.len() != f.arity() {
                    return Err(IrError(format!("{f:?} takes {} arguments", f.arity())));
                }
                for a in args {
                    want(a, Ty::Num)?;
                }
                f.result()
            }
            Expr::Format(pieces) => {
                for p in pieces {
                    match p {
                        Piece::Text(_) => {}
                        Piece::Num(e, _) => want(e, Ty::Num)?,
                        Piece::Str(e) => want(e, Ty::Str)?,
                        Piece::Bool(e) => want(e, Ty::Bool)?,
                    }
                }
                Ty::Str
            }
        })
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
            Expr::Absent(t) | Expr::Input(_, t) => *t,
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
        f(self);
        match self {
            Expr::Neg(a) | Expr::Not(a) | Expr::Present(a) => a.walk(f),
            Expr::Arith(_, a, b)
            | Expr::Cmp(_, a, b)
            | Expr::And(a, b)
            | Expr::Or(a, b)
            | Expr::Coalesce(a, b) => {
                a.walk(f);
                b.walk(f);
            }
            Expr::If(c, a, b) => {
                c.walk(f);
                a.walk(f);
                b.walk(f);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.walk(f)),
            Expr::Format(ps) => {
                for p in ps {
                    if let Piece::Num(e, _) | Piece::Str(e) | Piece::Bool(e) = p {
                        e.walk(f)
                    }
                }
            }
            _ => {}
        }
    }
}

/// A function: typed input slots in, one slot per output expression out. A widget's
/// expressions compile together as one function.
#[derive(Clone, Debug, PartialEq)]
pub struct Function {
    pub inputs: Vec<Ty>,
    pub outputs: Vec<Expr>,
}

impl Function {
    pub fn check(&self) -> Result<Vec<Ty>, IrError> {
        self.outputs.iter().map(|e| e.check(&self.inputs)).collect()
    }
}
