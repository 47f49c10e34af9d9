//! The Cranelift JIT: each IR function becomes native code. Numbers and booleans live in
//! registers with a presence flag beside them; strings go through runtime helpers.

use crate::Evaluate;
use crate::ir::{Arith, Builtin, Cmp, Expr, Function, IrError, Piece, Ty};
use crate::runtime::{self as rt, EvalCtx, Slot};
use cranelift_codegen::Context;
use cranelift_codegen::ir::condcodes::{FloatCC, IntCC};
use cranelift_codegen::ir::{
    AbiParam, BlockArg, FuncRef, InstBuilder, MemFlagsData, Signature, Type, Value, types,
};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{FuncId, Linkage, Module, default_libcall_names};
use std::collections::HashMap;
use std::sync::Arc;

/// Why compilation failed.
#[derive(Debug)]
pub enum JitError {
    /// The IR was ill-typed (a bug in lowering; the checker should have refused it).
    Ir(IrError),
    /// The host has no Cranelift backend, or Cranelift refused a setting.
    Target(String),
    /// Cranelift failed to compile or link a function.
    Codegen(String),
}

impl std::fmt::Display for JitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            JitError::Ir(e) => write!(f, "{e}"),
            JitError::Target(e) => write!(f, "no JIT for this machine: {e}"),
            JitError::Codegen(e) => write!(f, "code generation failed: {e}"),
        }
    }
}

impl std::error::Error for JitError {}

impl From<IrError> for JitError {
    fn from(e: IrError) -> Self {
        JitError::Ir(e)
    }
}

type RawFn = unsafe extern "C" fn(*const Slot, *mut Slot, *mut EvalCtx);

/// Natively compiled functions. Their code lives as long as the unit.
pub struct Unit {
    module: Option<JITModule>,
    functions: Vec<(RawFn, usize, Vec<Ty>)>,
    constants: Vec<Arc<str>>,
}

// SAFETY: the module is only touched again by `Drop` (which has `&mut self`); the compiled
// functions are plain code that keeps no state of its own (all state is in the `EvalCtx`
// and slots each caller passes), so calling them from several threads is sound.
unsafe impl Send for Unit {}
// SAFETY: as above.
unsafe impl Sync for Unit {}

impl Drop for Unit {
    fn drop(&mut self) {
        self.functions.clear();
        if let Some(m) = self.module.take() {
            // SAFETY: the only pointers into the module's code were in `self.functions`,
            // which is private and cleared above; nothing can call into it any more.
            unsafe { m.free_memory() };
        }
    }
}

impl Evaluate for Unit {
    fn call(&self, f: usize, inputs: &[Slot], outputs: &mut [Slot], ctx: &mut EvalCtx) {
        let (code, n_in, outs) = &self.functions[f];
        assert_eq!(inputs.len(), *n_in, "input slots of function {f}");
        assert_eq!(outputs.len(), outs.len(), "output slots of function {f}");
        // SAFETY: the code was compiled for exactly `n_in` inputs and `outs.len()` outputs
        // (checked above), reads only those, and gets a live `EvalCtx`.
        unsafe { code(inputs.as_ptr(), outputs.as_mut_ptr(), ctx) }
    }

    fn constants(&self) -> &[Arc<str>] {
        &self.constants
    }

    fn output_types(&self, f: usize) -> &[Ty] {
        &self.functions[f].2
    }

    fn len(&self) -> usize {
        self.functions.len()
    }
}

struct Helpers {
    ids: HashMap<&'static str, FuncId>,
}

const SLOT: i32 = std::mem::size_of::<Slot>() as i32;
const PRESENT: i32 = std::mem::offset_of!(Slot, present) as i32;

/// Compiles functions into one unit (one code allocation, freed together).
pub fn compile(functions: &[Function]) -> Result<Unit, JitError> {
    let output_types: Vec<Vec<Ty>> =
        functions.iter().map(Function::check).collect::<Result<_, _>>()?;
    let mut flags = settings::builder();
    let target = |e: &dyn std::fmt::Display| JitError::Target(e.to_string());
    flags.set("opt_level", "speed").map_err(|e| target(&e))?;
    flags.set("use_colocated_libcalls", "false").map_err(|e| target(&e))?;
    flags.set("is_pic", "false").map_err(|e| target(&e))?;
    // Cranelift's IR verifier about doubles compile time (1,000 gauges: ~150 → ~75 ms on
    // the layout bench). Our IR is checked before translation (`Function::check`) and the
    // differential tests run in debug builds, where the verifier stays on.
    let verify = if cfg!(debug_assertions) { "true" } else { "false" };
    flags.set("enable_verifier", verify).map_err(|e| target(&e))?;
    let isa = cranelift_native::builder()
        .map_err(|e| target(&e))?
        .finish(settings::Flags::new(flags))
        .map_err(|e| target(&e))?;
    let mut jb = JITBuilder::with_isa(isa, default_libcall_names());
    for (name, ptr) in helper_symbols() {
        jb.symbol(name, ptr);
    }
    let mut module = JITModule::new(jb);
    let helpers = declare_helpers(&mut module)?;
    let ptr = module.target_config().pointer_type();
    let mut sig = module.make_signature();
    for _ in 0..3 {
        sig.params.push(AbiParam::new(ptr));
    }
    let mut ctx = module.make_context();
    let mut fctx = FunctionBuilderContext::new();
    let mut constants = Vec::new();
    let mut ids = Vec::with_capacity(functions.len());
    for (i, f) in functions.iter().enumerate() {
        let id = module
            .declare_function(&format!("mocu_fn_{i}"), Linkage::Local, &sig)
            .map_err(|e| JitError::Codegen(e.to_string()))?;
        ctx.func.signature = sig.clone();
        translate_function(&mut module, &helpers, &mut ctx, &mut fctx, f, &mut constants);
        module.define_function(id, &mut ctx).map_err(|e| JitError::Codegen(format!("{e:?}")))?;
        module.clear_context(&mut ctx);
        ids.push(id);
    }
    module.finalize_definitions().map_err(|e| JitError::Codegen(e.to_string()))?;
    let compiled = ids
        .into_iter()
        .zip(functions)
        .zip(output_types)
        .map(|((id, f), outs)| {
            let p = module.get_finalized_function(id);
            // SAFETY: `p` is the entry of a function just compiled with the signature
            // (ptr, ptr, ptr) -> () in the platform's C calling convention, which is `RawFn`.
            let code: RawFn = unsafe { std::mem::transmute::<*const u8, RawFn>(p) };
            (code, f.inputs.len(), outs)
        })
        .collect();
    Ok(Unit { module: Some(module), functions: compiled, constants })
}

fn helper_symbols() -> Vec<(&'static str, *const u8)> {
    vec![
        ("mocu_round", rt::round as *const u8),
        ("mocu_sin", rt::sin as *const u8),
        ("mocu_cos", rt::cos as *const u8),
        ("mocu_atan2", rt::atan2 as *const u8),
        ("mocu_mod", rt::modulo as *const u8),
        ("mocu_deadzone", rt::deadzone as *const u8),
        ("mocu_rgba", rt::rgba as *const u8),
        ("mocu_str_eq", rt::str_eq as *const u8),
        ("mocu_fmt_begin", rt::fmt_begin as *const u8),
        ("mocu_fmt_text", rt::fmt_text as *const u8),
        ("mocu_fmt_num", rt::fmt_num as *const u8),
        ("mocu_fmt_bool", rt::fmt_bool as *const u8),
        ("mocu_fmt_end", rt::fmt_end as *const u8),
    ]
}

fn declare_helpers(module: &mut JITModule) -> Result<Helpers, JitError> {
    let ptr = module.target_config().pointer_type();
    let cc = module.target_config().default_call_conv;
    // Narrow integers (our booleans, `i8`) are widened by the caller: rustc (LLVM) compiles
    // a `u8` parameter of an `extern "C"` function assuming its register holds it
    // zero-extended to 32 bits, and Cranelift leaves the upper bits as they are unless the
    // parameter says `uext`. Without it, a release build of `fmt_bool` read `false` from
    // the low byte and its length from the whole register, and wrote "fals".
    let param = |t: Type| if t.bits() < 32 { AbiParam::new(t).uext() } else { AbiParam::new(t) };
    let sig = |params: &[Type], ret: Option<Type>| -> Signature {
        let mut s = Signature::new(cc);
        s.params.extend(params.iter().map(|t| param(*t)));
        s.returns.extend(ret.map(param));
        s
    };
    let (f, i64_, i8_) = (types::F64, types::I64, types::I8);
    let table: Vec<(&'static str, Signature)> = vec![
        ("mocu_round", sig(&[f], Some(f))),
        ("mocu_sin", sig(&[f], Some(f))),
        ("mocu_cos", sig(&[f], Some(f))),
        ("mocu_atan2", sig(&[f, f], Some(f))),
        ("mocu_mod", sig(&[f, f], Some(f))),
        ("mocu_deadzone", sig(&[f, f], Some(f))),
        ("mocu_rgba", sig(&[f, f, f, f], Some(i64_))),
        ("mocu_str_eq", sig(&[ptr, i64_, i64_], Some(i8_))),
        ("mocu_fmt_begin", sig(&[ptr], None)),
        ("mocu_fmt_text", sig(&[ptr, i64_], None)),
        ("mocu_fmt_num", sig(&[ptr, f, i64_], None)),
        ("mocu_fmt_bool", sig(&[ptr, i8_], None)),
        ("mocu_fmt_end", sig(&[ptr], Some(i64_))),
    ];
    let mut ids = HashMap::new();
    for (name, s) in table {
        let id = module
            .declare_function(name, Linkage::Import, &s)
            .map_err(|e| JitError::Codegen(e.to_string()))?;
        ids.insert(name, id);
    }
    Ok(Helpers { ids })
}

fn translate_function(
    module: &mut JITModule,
    helpers: &Helpers,
    ctx: &mut Context,
    fctx: &mut FunctionBuilderContext,
    f: &Function,
    constants: &mut Vec<Arc<str>>,
) {
    let config = module.target_config();
    let mut b = FunctionBuilder::new(&mut ctx.func, fctx);
    let entry = b.create_block();
    b.append_block_params_for_function_params(entry);
    b.switch_to_block(entry);
    let params = b.block_params(entry).to_vec();
    let mut t = Translator {
        b,
        module,
        helpers,
        refs: HashMap::new(),
        inputs: params[0],
        ctx: params[2],
        constants,
        locals: Vec::with_capacity(f.locals.len()),
    };
    // Locals first, in order, each once: their values are SSA values every output may use
    // (straight-line code; the blocks `format` adds rejoin before the next expression).
    for e in &f.locals {
        let v = t.expr(e);
        t.locals.push(v);
    }
    for (i, e) in f.outputs.iter().enumerate() {
        let (v, p) = t.expr(e);
        let off = i as i32 * SLOT;
        let bits = match e.ty() {
            Ty::Num => v,
            Ty::Bool => t.b.ins().uextend(types::I64, v),
            Ty::Str | Ty::Color => v,
        };
        t.b.ins().store(MemFlagsData::trusted(), bits, params[1], off);
        t.b.ins().store(MemFlagsData::trusted(), p, params[1], off + PRESENT);
    }
    t.b.ins().return_(&[]);
    t.b.seal_all_blocks();
    t.b.finalize(config);
}

struct Translator<'a> {
    b: FunctionBuilder<'a>,
    module: &'a mut JITModule,
    helpers: &'a Helpers,
    refs: HashMap<&'static str, FuncRef>,
    inputs: Value,
    ctx: Value,
    constants: &'a mut Vec<Arc<str>>,
    /// The values of the function's locals computed so far.
    locals: Vec<Pv>,
}

/// A value and its presence flag (an i8, 0 or 1).
type Pv = (Value, Value);

impl Translator<'_> {
    fn helper(&mut self, name: &'static str, args: &[Value]) -> Option<Value> {
        let fref = match self.refs.get(name) {
            Some(r) => *r,
            None => {
                let id = self.helpers.ids[name];
                let r = self.module.declare_func_in_func(id, self.b.func);
                self.refs.insert(name, r);
                r
            }
        };
        let call = self.b.ins().call(fref, args);
        self.b.inst_results(call).first().copied()
    }

    fn yes(&mut self) -> Value {
        self.b.ins().iconst(types::I8, 1)
    }

    fn zero(&mut self, ty: Ty) -> Value {
        match ty {
            Ty::Num => self.b.ins().f64const(0.0),
            Ty::Bool => self.b.ins().iconst(types::I8, 0),
            Ty::Str | Ty::Color => self.b.ins().iconst(types::I64, 0),
        }
    }

    /// A numeric result: present only if its operands were and it is finite.
    fn finite(&mut self, v: Value, present: Value) -> Pv {
        let a = self.b.ins().fabs(v);
        let inf = self.b.ins().f64const(f64::INFINITY);
        let ok = self.b.ins().fcmp(FloatCC::LessThan, a, inf);
        (v, self.b.ins().band(present, ok))
    }

    fn text(&mut self, s: &Arc<str>) -> Value {
        self.constants.push(s.clone());
        self.b.ins().iconst(types::I64, (self.constants.len() - 1) as i64)
    }

    fn expr(&mut self, e: &Expr) -> Pv {
        match e {
            Expr::Num(x) => {
                let v = self.b.ins().f64const(*x);
                let p = self.b.ins().iconst(types::I8, x.is_finite() as i64);
                (v, p)
            }
            Expr::Bool(x) => {
                let v = self.b.ins().iconst(types::I8, *x as i64);
                (v, self.yes())
            }
            Expr::Str(s) => {
                let v = self.text(s);
                (v, self.yes())
            }
            Expr::Color(c) => {
                let v = self.b.ins().iconst(types::I64, *c as i64);
                (v, self.yes())
            }
            Expr::Absent(t) => {
                let v = self.zero(*t);
                (v, self.b.ins().iconst(types::I8, 0))
            }
            Expr::Input(i, ty) => {
                let off = *i as i32 * SLOT;
                let flags = MemFlagsData::trusted();
                let v = match ty {
                    Ty::Num => self.b.ins().load(types::F64, flags, self.inputs, off),
                    Ty::Bool => self.b.ins().load(types::I8, flags, self.inputs, off),
                    Ty::Str | Ty::Color => self.b.ins().load(types::I64, flags, self.inputs, off),
                };
                let p = self.b.ins().load(types::I8, flags, self.inputs, off + PRESENT);
                (v, p)
            }
            Expr::Local(i, _) => self.locals[*i as usize],
            Expr::Neg(a) => {
                let (a, p) = self.expr(a);
                (self.b.ins().fneg(a), p)
            }
            Expr::Not(a) => {
                let (a, p) = self.expr(a);
                (self.b.ins().icmp_imm_u(IntCC::Equal, a, 0), p)
            }
            Expr::Arith(op, a, b) => {
                let (a, pa) = self.expr(a);
                let (b, pb) = self.expr(b);
                let p = self.b.ins().band(pa, pb);
                let v = match op {
                    Arith::Add => self.b.ins().fadd(a, b),
                    Arith::Sub => self.b.ins().fsub(a, b),
                    Arith::Mul => self.b.ins().fmul(a, b),
                    Arith::Div => self.b.ins().fdiv(a, b),
                };
                self.finite(v, p)
            }
            Expr::Cmp(op, a, b) => {
                let ty = a.ty();
                let (a, pa) = self.expr(a);
                let (b, pb) = self.expr(b);
                let p = self.b.ins().band(pa, pb);
                let v = match ty {
                    Ty::Num => {
                        let cc = match op {
                            Cmp::Lt => FloatCC::LessThan,
                            Cmp::Le => FloatCC::LessThanOrEqual,
                            Cmp::Gt => FloatCC::GreaterThan,
                            Cmp::Ge => FloatCC::GreaterThanOrEqual,
                            Cmp::Eq => FloatCC::Equal,
                            Cmp::Ne => FloatCC::NotEqual,
                        };
                        self.b.ins().fcmp(cc, a, b)
                    }
                    Ty::Str => {
                        let ctx = self.ctx;
                        let eq = self.helper("mocu_str_eq", &[ctx, a, b]).expect("returns i8");
                        if *op == Cmp::Ne { self.b.ins().bxor_imm_u(eq, 1) } else { eq }
                    }
                    Ty::Bool | Ty::Color => {
                        let cc = if *op == Cmp::Ne { IntCC::NotEqual } else { IntCC::Equal };
                        self.b.ins().icmp(cc, a, b)
                    }
                };
                (v, p)
            }
            Expr::And(a, b) => {
                let (a, pa) = self.expr(a);
                let (b, pb) = self.expr(b);
                let na = self.b.ins().bxor_imm_u(a, 1);
                let nb = self.b.ins().bxor_imm_u(b, 1);
                let a_false = self.b.ins().band(pa, na);
                let b_false = self.b.ins().band(pb, nb);
                let any_false = self.b.ins().bor(a_false, b_false);
                let both = self.b.ins().band(pa, pb);
                let p = self.b.ins().bor(any_false, both);
                let a_true = self.b.ins().band(pa, a);
                let b_true = self.b.ins().band(pb, b);
                (self.b.ins().band(a_true, b_true), p)
            }
            Expr::Or(a, b) => {
                let (a, pa) = self.expr(a);
                let (b, pb) = self.expr(b);
                let a_true = self.b.ins().band(pa, a);
                let b_true = self.b.ins().band(pb, b);
                let any_true = self.b.ins().bor(a_true, b_true);
                let both = self.b.ins().band(pa, pb);
                (any_true, self.b.ins().bor(any_true, both))
            }
            Expr::If(c, a, b) => {
                let (c, pc) = self.expr(c);
                let (a, pa) = self.expr(a);
                let (b, pb) = self.expr(b);
                let v = self.b.ins().select(c, a, b);
                let ps = self.b.ins().select(c, pa, pb);
                (v, self.b.ins().band(pc, ps))
            }
            Expr::Coalesce(a, b) => {
                let (a, pa) = self.expr(a);
                let (b, pb) = self.expr(b);
                let v = self.b.ins().select(pa, a, b);
                (v, self.b.ins().bor(pa, pb))
            }
            Expr::Present(a) => {
                let (_, pa) = self.expr(a);
                (pa, self.yes())
            }
            Expr::Call(f, args) => self.call(*f, args),
            Expr::Format(pieces) => self.format(pieces),
        }
    }

    fn call(&mut self, f: Builtin, args: &[Expr]) -> Pv {
        let mut vs = Vec::with_capacity(args.len());
        let mut p = self.yes();
        for a in args {
            let (v, pa) = self.expr(a);
            vs.push(v);
            p = self.b.ins().band(p, pa);
        }
        let v = match f {
            Builtin::Min => {
                let lt = self.b.ins().fcmp(FloatCC::LessThan, vs[0], vs[1]);
                self.b.ins().select(lt, vs[0], vs[1])
            }
            Builtin::Max => {
                let gt = self.b.ins().fcmp(FloatCC::GreaterThan, vs[0], vs[1]);
                self.b.ins().select(gt, vs[0], vs[1])
            }
            Builtin::Clamp => {
                let gt = self.b.ins().fcmp(FloatCC::GreaterThan, vs[0], vs[1]);
                let m = self.b.ins().select(gt, vs[0], vs[1]);
                let lt = self.b.ins().fcmp(FloatCC::LessThan, m, vs[2]);
                self.b.ins().select(lt, m, vs[2])
            }
            Builtin::Abs => self.b.ins().fabs(vs[0]),
            Builtin::Floor => self.b.ins().floor(vs[0]),
            Builtin::Ceil => self.b.ins().ceil(vs[0]),
            Builtin::Sqrt => self.b.ins().sqrt(vs[0]),
            Builtin::Round => self.helper("mocu_round", &vs).expect("f64"),
            Builtin::Sin => self.helper("mocu_sin", &vs).expect("f64"),
            Builtin::Cos => self.helper("mocu_cos", &vs).expect("f64"),
            Builtin::Atan2 => self.helper("mocu_atan2", &vs).expect("f64"),
            Builtin::Mod => self.helper("mocu_mod", &vs).expect("f64"),
            Builtin::Deadzone => self.helper("mocu_deadzone", &vs).expect("f64"),
            Builtin::Deg | Builtin::Rad => {
                let k = if f == Builtin::Deg { rt::DEG_PER_RAD } else { rt::RAD_PER_DEG };
                let k = self.b.ins().f64const(k);
                self.b.ins().fmul(vs[0], k)
            }
            Builtin::Lerp => {
                let d = self.b.ins().fsub(vs[1], vs[0]);
                let m = self.b.ins().fmul(d, vs[2]);
                self.b.ins().fadd(vs[0], m)
            }
            Builtin::Rgb | Builtin::Rgba => {
                if f == Builtin::Rgb {
                    let one = self.b.ins().f64const(1.0);
                    vs.push(one);
                }
                let c = self.helper("mocu_rgba", &vs).expect("i64");
                return (c, p);
            }
        };
        self.finite(v, p)
    }

    /// Pieces are evaluated first; the string is built only when all are present.
    fn format(&mut self, pieces: &[Piece]) -> Pv {
        let mut vals = Vec::with_capacity(pieces.len());
        let mut p = self.yes();
        for piece in pieces {
            match piece {
                Piece::Text(t) => vals.push(self.text(t)),
                Piece::Num(e, _) | Piece::Str(e) | Piece::Bool(e) => {
                    let (v, pv) = self.expr(e);
                    vals.push(v);
                    p = self.b.ins().band(p, pv);
                }
            }
        }
        let build = self.b.create_block();
        let done = self.b.create_block();
        let result = self.b.append_block_param(done, types::I64);
        let none = self.b.ins().iconst(types::I64, 0);
        self.b.ins().brif(p, build, &[], done, &[BlockArg::Value(none)]);
        self.b.switch_to_block(build);
        let ctx = self.ctx;
        self.helper("mocu_fmt_begin", &[ctx]);
        for (piece, v) in pieces.iter().zip(vals) {
            match piece {
                Piece::Text(_) | Piece::Str(_) => {
                    self.helper("mocu_fmt_text", &[ctx, v]);
                }
                Piece::Num(_, spec) => {
                    let s = self.b.ins().iconst(types::I64, spec.pack());
                    self.helper("mocu_fmt_num", &[ctx, v, s]);
                }
                Piece::Bool(_) => {
                    self.helper("mocu_fmt_bool", &[ctx, v]);
                }
            }
        }
        let h = self.helper("mocu_fmt_end", &[ctx]).expect("i64");
        self.b.ins().jump(done, &[BlockArg::Value(h)]);
        self.b.switch_to_block(done);
        (result, p)
    }
}
