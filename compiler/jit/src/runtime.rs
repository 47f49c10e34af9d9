//! What compiled code and the interpreter share at run time: the slot calling convention,
//! the evaluation context (strings), and the helper functions both call, so that both give
//! bit-identical results.

use crate::ir::{NumFormat, Ty};
use std::sync::Arc;

/// One value crossing the boundary of a compiled function.
///
/// `bits` holds an f64 (`Num`), 0/1 (`Bool`), a string handle into the [`EvalCtx`] (`Str`)
/// or `0xRRGGBBAA` (`Color`); it means nothing when `present` is 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Slot {
    pub bits: u64,
    pub present: u8,
}

impl Slot {
    pub const ABSENT: Slot = Slot { bits: 0, present: 0 };

    /// A number; non-finite numbers are absent (the IR's rule).
    pub fn num(x: f64) -> Slot {
        if x.is_finite() { Slot { bits: x.to_bits(), present: 1 } } else { Slot::ABSENT }
    }

    pub fn bool(b: bool) -> Slot {
        Slot { bits: b as u64, present: 1 }
    }

    pub fn color(rgba: u32) -> Slot {
        Slot { bits: rgba as u64, present: 1 }
    }

    pub fn str(ctx: &mut EvalCtx, s: Arc<str>) -> Slot {
        Slot { bits: ctx.intern(s), present: 1 }
    }

    pub fn is_present(self) -> bool {
        self.present != 0
    }

    /// Reads the slot as a value of type `ty`.
    pub fn decode(self, ty: Ty, ctx: &EvalCtx) -> Out {
        if !self.is_present() {
            return Out::Absent;
        }
        match ty {
            Ty::Num => Out::Num(f64::from_bits(self.bits)),
            Ty::Bool => Out::Bool(self.bits & 1 == 1),
            Ty::Str => Out::Str(ctx.string(self.bits).clone()),
            Ty::Color => Out::Color(self.bits as u32),
        }
    }
}

/// A decoded result.
#[derive(Clone, Debug, PartialEq)]
pub enum Out {
    Num(f64),
    Bool(bool),
    Str(Arc<str>),
    Color(u32),
    Absent,
}

/// Per-evaluation state: the string table (constants first, then strings made or loaded
/// during evaluation) and the buffer interpolated strings are built in.
pub struct EvalCtx {
    strings: Vec<Arc<str>>,
    constants: usize,
    buf: String,
}

impl EvalCtx {
    pub fn new(constants: &[Arc<str>]) -> EvalCtx {
        EvalCtx { strings: constants.to_vec(), constants: constants.len(), buf: String::new() }
    }

    /// Adds a string (an input, or a result) and returns its handle.
    pub fn intern(&mut self, s: Arc<str>) -> u64 {
        self.strings.push(s);
        (self.strings.len() - 1) as u64
    }

    pub fn string(&self, handle: u64) -> &Arc<str> {
        &self.strings[handle as usize]
    }

    /// Forgets the strings of earlier evaluations (keeps the constants).
    pub fn reset(&mut self) {
        self.strings.truncate(self.constants);
    }

    pub(crate) fn fmt_begin(&mut self) {
        self.buf.clear();
    }

    pub(crate) fn fmt_text(&mut self, h: u64) {
        if let Some(s) = self.strings.get(h as usize) {
            self.buf.push_str(s);
        }
    }

    pub(crate) fn fmt_num(&mut self, x: f64, spec: NumFormat) {
        spec.write(&mut self.buf, x);
    }

    pub(crate) fn fmt_bool(&mut self, b: bool) {
        self.buf.push_str(if b { "true" } else { "false" });
    }

    pub(crate) fn fmt_end(&mut self) -> u64 {
        let s: Arc<str> = Arc::from(self.buf.as_str());
        self.intern(s)
    }
}

// ----- numeric helpers: one definition, called by the interpreter and by compiled code ----

pub(crate) const DEG_PER_RAD: f64 = 180.0 / std::f64::consts::PI;
pub(crate) const RAD_PER_DEG: f64 = std::f64::consts::PI / 180.0;

pub(crate) extern "C" fn round(x: f64) -> f64 {
    x.round()
}

pub(crate) extern "C" fn floor(x: f64) -> f64 {
    x.floor()
}

pub(crate) extern "C" fn ceil(x: f64) -> f64 {
    x.ceil()
}

pub(crate) extern "C" fn sin(x: f64) -> f64 {
    x.sin()
}

pub(crate) extern "C" fn cos(x: f64) -> f64 {
    x.cos()
}

pub(crate) extern "C" fn atan2(y: f64, x: f64) -> f64 {
    y.atan2(x)
}

/// Remainder with the sign of the divisor (`mod(-1, 360) = 359`).
pub(crate) extern "C" fn modulo(x: f64, y: f64) -> f64 {
    let r = x % y;
    if r != 0.0 && (r < 0.0) != (y < 0.0) { r + y } else { r }
}

/// 0 inside ±dz, rescaled to 0..1 outside (so a stick still reaches full scale).
pub(crate) extern "C" fn deadzone(x: f64, dz: f64) -> f64 {
    let a = x.abs();
    if a <= dz { 0.0 } else { x.signum() * ((a - dz) / (1.0 - dz)) }
}

fn channel(x: f64) -> u32 {
    x.clamp(0.0, 255.0).round() as u32
}

pub(crate) extern "C" fn rgba(r: f64, g: f64, b: f64, a: f64) -> i64 {
    ((channel(r) << 24) | (channel(g) << 16) | (channel(b) << 8) | channel(a * 255.0)) as i64
}

// ----- string helpers called by compiled code ------------------------------------------

/// # Safety
/// `ctx` must be the live `EvalCtx` passed to the compiled function.
pub(crate) unsafe extern "C" fn str_eq(ctx: *mut EvalCtx, a: u64, b: u64) -> u8 {
    // SAFETY: compiled code passes through the ctx pointer its caller gave it, which
    // `Unit::call` takes as `&mut EvalCtx` for the duration of the call.
    let ctx = unsafe { &*ctx };
    // Compiled code compares branch-free, so an absent operand's (meaningless) handle may
    // arrive here: it must not panic (a panic cannot unwind out of compiled code). The
    // result is then ignored, its presence flag being false.
    match (ctx.strings.get(a as usize), ctx.strings.get(b as usize)) {
        (Some(x), Some(y)) => (x == y) as u8,
        _ => 0,
    }
}

/// # Safety
/// As [`str_eq`].
pub(crate) unsafe extern "C" fn fmt_begin(ctx: *mut EvalCtx) {
    // SAFETY: see `str_eq`.
    unsafe { &mut *ctx }.fmt_begin()
}

/// # Safety
/// As [`str_eq`].
pub(crate) unsafe extern "C" fn fmt_text(ctx: *mut EvalCtx, h: u64) {
    // SAFETY: see `str_eq`.
    unsafe { &mut *ctx }.fmt_text(h)
}

/// # Safety
/// As [`str_eq`].
pub(crate) unsafe extern "C" fn fmt_num(ctx: *mut EvalCtx, x: f64, spec: i64) {
    // SAFETY: see `str_eq`.
    unsafe { &mut *ctx }.fmt_num(x, NumFormat::unpack(spec))
}

/// # Safety
/// As [`str_eq`].
pub(crate) unsafe extern "C" fn fmt_bool(ctx: *mut EvalCtx, b: u8) {
    // SAFETY: see `str_eq`.
    unsafe { &mut *ctx }.fmt_bool(b != 0)
}

/// # Safety
/// As [`str_eq`].
pub(crate) unsafe extern "C" fn fmt_end(ctx: *mut EvalCtx) -> u64 {
    // SAFETY: see `str_eq`.
    unsafe { &mut *ctx }.fmt_end()
}
