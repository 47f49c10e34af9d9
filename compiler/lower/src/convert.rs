//! World-model values into input slots, and results back into values: the one rule the
//! live layout and the widget renderer both use.

use mocu_jit::{EvalCtx, Out, Slot, Ty};
use mocu_value::Value;

/// A world-model value as an input of type `ty`; anything that does not fit is absent
/// (a string where a number is needed reads as absent: the "no data" look, not a crash).
/// A string input also takes numbers, booleans and GUIDs (as written by `Display`); a
/// colour input takes an int `0xRRGGBBAA` or a string `#RRGGBB` / `#RRGGBBAA`.
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn read(v: Value, ty: Ty) -> Out {
        let mut ctx = EvalCtx::new(&[]);
        let s = to_slot(Some(&v), ty, &mut ctx);
        s.decode(ty, &ctx)
    }

    #[test]
    fn colour_inputs_accept_ints_and_hex_strings() {
        let cases = [
            (Value::Int(0x11223344), Out::Color(0x11223344)),
            (Value::str("#a0b0c0"), Out::Color(0xa0b0c0ff)),
            (Value::str("#a0b0c080"), Out::Color(0xa0b0c080)),
            (Value::str("#abc"), Out::Absent),
            (Value::str("red"), Out::Absent),
            (Value::Float(1.0), Out::Absent),
        ];
        for (v, want) in cases {
            assert_eq!(read(v.clone(), Ty::Color), want, "{v:?}");
        }
    }

    #[test]
    fn string_inputs_accept_scalars_and_guids_as_text() {
        let g = mocu_value::Guid::ROOT;
        let cases = [
            (Value::str("usv"), Out::Str(Arc::from("usv"))),
            (Value::Int(3), Out::Str(Arc::from("3"))),
            (Value::Bool(true), Out::Str(Arc::from("true"))),
            (Value::Guid(g), Out::Str(Arc::from(g.to_string().as_str()))),
        ];
        for (v, want) in cases {
            assert_eq!(read(v.clone(), Ty::Str), want, "{v:?}");
        }
    }

    #[test]
    fn values_that_do_not_fit_read_as_absent() {
        assert_eq!(read(Value::str("fast"), Ty::Num), Out::Absent);
        assert_eq!(read(Value::str("yes"), Ty::Bool), Out::Absent);
        let mut ctx = EvalCtx::new(&[]);
        assert_eq!(to_slot(None, Ty::Num, &mut ctx), Slot::ABSENT);
    }

    #[test]
    fn results_round_trip_into_values() {
        assert_eq!(to_value(Out::Num(2.5)), Some(Value::Float(2.5)));
        assert_eq!(to_value(Out::Color(0xff0000ff)), Some(Value::Int(0xff0000ff)));
        assert_eq!(to_value(Out::Absent), None);
    }
}
