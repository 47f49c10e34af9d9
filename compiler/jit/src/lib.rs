//! Mocu's expression back end: a small typed IR ([`ir`]), its reference interpreter
//! ([`interp`]) and a Cranelift JIT ([`jit`]) with identical semantics (see the `ir` module
//! docs), sharing one calling convention ([`runtime::Slot`]).
//!
//! Architecture invariant: this crate knows nothing of the DataServer, the syntax tree or
//! the display; it turns IR functions into callable code. `unsafe` lives only in `jit.rs`
//! and the runtime helpers compiled code calls, each block with a `// SAFETY:` line.

pub mod interp;
pub mod ir;
pub mod jit;
pub mod runtime;

pub use interp::Interpreter;
pub use ir::{Arith, Builtin, Cmp, Expr, Function, IrError, NumFormat, Piece, Ty};
pub use jit::{JitError, Unit, compile};
pub use runtime::{EvalCtx, Out, Slot};

use std::sync::Arc;

/// Something that evaluates compiled functions: the JIT's [`Unit`] or the [`Interpreter`].
pub trait Evaluate: Send + Sync {
    /// Evaluates function `f`: reads `inputs`, writes one slot per output.
    fn call(&self, f: usize, inputs: &[Slot], outputs: &mut [Slot], ctx: &mut EvalCtx);
    /// String constants the evaluation context must start with.
    fn constants(&self) -> &[Arc<str>];
    fn output_types(&self, f: usize) -> &[Ty];
    fn len(&self) -> usize;
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// A fresh evaluation context for this evaluator.
    fn context(&self) -> EvalCtx {
        EvalCtx::new(self.constants())
    }
}
