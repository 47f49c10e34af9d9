//! World-model values into input slots, and results back into values.

use mocu_jit::{EvalCtx, Out, Slot, Ty};
use mocu_value::Value;

/// A world-model value as an input of type `ty`; anything that does not fit is absent
/// (a string where a number is needed reads as absent: the "no data" look, not a crash).
pub fn to_slot(v: Option<&Value>, ty: Ty, ctx: &mut EvalCtx) -> Slot {
    let Some(v) = v else { return Slot::ABSENT };
    match ty {
        Ty::Num => v.as_f64().map_or(Slot::ABSENT, Slot::num),
        Ty::Bool => v.as_bool().map_or(Slot::ABSENT, Slot::bool),
        Ty::Str => match v {
            Value::Str(s) => Slot::str(ctx, s.clone()),
            Value::Int(_) | Value::Float(_) | Value::Bool(_) | Value::Guid(_) => {
                Slot::str(ctx, v.to_string().into())
            }
            _ => Slot::ABSENT,
        },
        Ty::Color => match v {
            Value::Int(c) => Slot::color(*c as u32),
            Value::Str(s) => parse_hex(s).map_or(Slot::ABSENT, Slot::color),
            _ => Slot::ABSENT,
        },
    }
}

fn parse_hex(s: &str) -> Option<u32> {
    let h = s.strip_prefix('#')?;
    let v = u32::from_str_radix(h, 16).ok()?;
    match h.len() {
        6 => Some((v << 8) | 0xff),
        8 => Some(v),
        _ => None,
    }
}

/// A result as a world-model value; `None` for absent. Colours are ints `0xRRGGBBAA`.
pub fn to_value(o: Out) -> Option<Value> {
    match o {
        Out::Num(x) => Some(Value::Float(x)),
        Out::Bool(b) => Some(Value::Bool(b)),
        Out::Str(s) => Some(Value::Str(s)),
        Out::Color(c) => Some(Value::Int(c as i64)),
        Out::Absent => None,
    }
}
