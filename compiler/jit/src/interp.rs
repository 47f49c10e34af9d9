//! The reference interpreter: the IR's semantics in plain Rust, for differential tests
//! against the JIT and as a fallback where no JIT is available.

use crate::Evaluate;
use crate::ir::{Arith, Builtin, Cmp, Expr, Function, IrError, Piece, Ty};
use crate::runtime::{self as rt, EvalCtx, Slot};
use std::sync::Arc;

/// Checked functions, evaluated by walking the tree.
pub struct Interpreter {
    functions: Vec<Function>,
    outputs: Vec<Vec<Ty>>,
}

impl Interpreter {
    pub fn new(functions: &[Function]) -> Result<Interpreter, IrError> {
        let outputs = functions.iter().map(Function::check).collect::<Result<_, _>>()?;
        Ok(Interpreter { functions: functions.to_vec(), outputs })
    }
}

impl Evaluate for Interpreter {
    fn call(&self, f: usize, inputs: &[Slot], outputs: &mut [Slot], ctx: &mut EvalCtx) {
        let func = &self.functions[f];
        assert_eq!(inputs.len(), func.inputs.len(), "input slots of function {f}");
        let mut locals = Vec::with_capacity(func.locals.len());
        for e in &func.locals {
            let v = eval(e, inputs, &locals, ctx);
            locals.push(v);
        }
        for (o, e) in outputs.iter_mut().zip(&func.outputs) {
            *o = eval(e, inputs, &locals, ctx);
        }
    }

    fn constants(&self) -> &[Arc<str>] {
        &[]
    }

    fn output_types(&self, f: usize) -> &[Ty] {
        &self.outputs[f]
    }

    fn len(&self) -> usize {
        self.functions.len()
    }
}

fn num(s: Slot) -> f64 {
    f64::from_bits(s.bits)
}

fn both(a: Slot, b: Slot, f: impl FnOnce(f64, f64) -> f64) -> Slot {
    if a.is_present() && b.is_present() { Slot::num(f(num(a), num(b))) } else { Slot::ABSENT }
}

fn flag(s: Slot) -> bool {
    s.bits & 1 == 1
}

/// Evaluates one expression (well-typed and within the depth bound, as checked by
/// `Interpreter::new`); `locals` are the values of the function's locals it may read.
pub fn eval(e: &Expr, inputs: &[Slot], locals: &[Slot], ctx: &mut EvalCtx) -> Slot {
    let eval = |e: &Expr, ctx: &mut EvalCtx| eval(e, inputs, locals, ctx);
    match e {
        Expr::Num(x) => Slot::num(*x),
        Expr::Bool(b) => Slot::bool(*b),
        Expr::Str(s) => Slot::str(ctx, s.clone()),
        Expr::Color(c) => Slot::color(*c),
        Expr::Absent(_) => Slot::ABSENT,
        Expr::Input(i, _) => inputs[*i as usize],
        Expr::Local(i, _) => locals[*i as usize],
        Expr::Neg(a) => {
            let a = eval(a, ctx);
            if a.is_present() { Slot::num(-num(a)) } else { Slot::ABSENT }
        }
        Expr::Not(a) => {
            let a = eval(a, ctx);
            if a.is_present() { Slot::bool(!flag(a)) } else { Slot::ABSENT }
        }
        Expr::Arith(op, a, b) => {
            let (a, b) = (eval(a, ctx), eval(b, ctx));
            both(a, b, |x, y| match op {
                Arith::Add => x + y,
                Arith::Sub => x - y,
                Arith::Mul => x * y,
                Arith::Div => x / y,
            })
        }
        Expr::Cmp(op, a, b) => {
            let ty = a.ty();
            let (a, b) = (eval(a, ctx), eval(b, ctx));
            if !(a.is_present() && b.is_present()) {
                return Slot::ABSENT;
            }
            let eq = match ty {
                Ty::Num => num(a) == num(b),
                Ty::Str => ctx.string(a.bits) == ctx.string(b.bits),
                Ty::Bool | Ty::Color => a.bits == b.bits,
            };
            Slot::bool(match op {
                Cmp::Eq => eq,
                Cmp::Ne => !eq,
                Cmp::Lt => num(a) < num(b),
                Cmp::Le => num(a) <= num(b),
                Cmp::Gt => num(a) > num(b),
                Cmp::Ge => num(a) >= num(b),
            })
        }
        Expr::And(a, b) => {
            let (a, b) = (eval(a, ctx), eval(b, ctx));
            let a_false = a.is_present() && !flag(a);
            let b_false = b.is_present() && !flag(b);
            if a_false || b_false {
                Slot::bool(false)
            } else if a.is_present() && b.is_present() {
                Slot::bool(true)
            } else {
                Slot::ABSENT
            }
        }
        Expr::Or(a, b) => {
            let (a, b) = (eval(a, ctx), eval(b, ctx));
            let a_true = a.is_present() && flag(a);
            let b_true = b.is_present() && flag(b);
            if a_true || b_true {
                Slot::bool(true)
            } else if a.is_present() && b.is_present() {
                Slot::bool(false)
            } else {
                Slot::ABSENT
            }
        }
        Expr::If(c, a, b) => {
            let c = eval(c, ctx);
            let (a, b) = (eval(a, ctx), eval(b, ctx));
            match (c.is_present(), flag(c)) {
                (false, _) => Slot::ABSENT,
                (true, true) => a,
                (true, false) => b,
            }
        }
        Expr::Coalesce(a, b) => {
            let (a, b) = (eval(a, ctx), eval(b, ctx));
            if a.is_present() { a } else { b }
        }
        Expr::Present(a) => Slot::bool(eval(a, ctx).is_present()),
        Expr::Call(f, args) => call(*f, args, inputs, locals, ctx),
        Expr::Format(pieces) => format(pieces, inputs, locals, ctx),
    }
}

// `call` and `format` are out of line so that `eval`'s frame, one per level of a deep
// expression, stays small.
#[inline(never)]
fn call(f: Builtin, args: &[Expr], inputs: &[Slot], locals: &[Slot], ctx: &mut EvalCtx) -> Slot {
    let eval = |e: &Expr, ctx: &mut EvalCtx| eval(e, inputs, locals, ctx);
    let v: Vec<Slot> = args.iter().map(|a| eval(a, ctx)).collect();
    if !v.iter().all(|s| s.is_present()) {
        return Slot::ABSENT;
    }
    let x: Vec<f64> = v.iter().map(|s| num(*s)).collect();
    let min = |a: f64, b: f64| if a < b { a } else { b };
    let max = |a: f64, b: f64| if a > b { a } else { b };
    Slot::num(match f {
        Builtin::Min => min(x[0], x[1]),
        Builtin::Max => max(x[0], x[1]),
        Builtin::Abs => x[0].abs(),
        Builtin::Clamp => min(max(x[0], x[1]), x[2]),
        Builtin::Round => rt::round(x[0]),
        Builtin::Floor => rt::floor(x[0]),
        Builtin::Ceil => rt::ceil(x[0]),
        Builtin::Sqrt => x[0].sqrt(),
        Builtin::Sin => rt::sin(x[0]),
        Builtin::Cos => rt::cos(x[0]),
        Builtin::Atan2 => rt::atan2(x[0], x[1]),
        Builtin::Deg => x[0] * rt::DEG_PER_RAD,
        Builtin::Rad => x[0] * rt::RAD_PER_DEG,
        Builtin::Mod => rt::modulo(x[0], x[1]),
        Builtin::Lerp => x[0] + (x[1] - x[0]) * x[2],
        Builtin::Deadzone => rt::deadzone(x[0], x[1]),
        Builtin::Rgb => return Slot::color(rt::rgba(x[0], x[1], x[2], 1.0) as u32),
        Builtin::Rgba => return Slot::color(rt::rgba(x[0], x[1], x[2], x[3]) as u32),
    })
}

#[inline(never)]
fn format(pieces: &[Piece], inputs: &[Slot], locals: &[Slot], ctx: &mut EvalCtx) -> Slot {
    let eval = |e: &Expr, ctx: &mut EvalCtx| eval(e, inputs, locals, ctx);
    let vals: Vec<Slot> = pieces
        .iter()
        .map(|p| match p {
            Piece::Text(_) => Slot::bool(true),
            Piece::Num(e, _) | Piece::Str(e) | Piece::Bool(e) => eval(e, ctx),
        })
        .collect();
    if !vals.iter().all(|s| s.is_present()) {
        return Slot::ABSENT;
    }
    let mut out = String::new();
    for (p, v) in pieces.iter().zip(vals) {
        match p {
            Piece::Text(t) => out.push_str(t),
            Piece::Num(_, spec) => spec.write(&mut out, num(v)),
            Piece::Str(_) => out.push_str(ctx.string(v.bits)),
            Piece::Bool(_) => out.push_str(if flag(v) { "true" } else { "false" }),
        }
    }
    Slot::str(ctx, out.into())
}
