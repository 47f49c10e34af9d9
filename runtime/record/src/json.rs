//! Values as JSON, written straight into a message buffer (docs/recording.md, the value
//! table): a value's JSON beside its kind, floats always with a fraction or exponent,
//! non-finite floats as strings, bytes as base64, and inside lists every element that is
//! not an int, float, bool or string as `{"kind": K, "value": V}`.

use mocu_value::Value;

/// Writes `s` as a JSON string.
pub(crate) fn string(out: &mut Vec<u8>, s: &str) {
    // Writing to a Vec cannot fail.
    let _ = serde_json::to_writer(&mut *out, s);
}

/// `a.b` as one JSON string (a property's path: its object's path and its name).
pub(crate) fn dotted(out: &mut Vec<u8>, a: &str, b: &str) {
    let plain = |s: &str| s.bytes().all(|c| c >= 0x20 && c != b'"' && c != b'\\');
    if plain(a) && plain(b) {
        out.push(b'"');
        out.extend_from_slice(a.as_bytes());
        out.push(b'.');
        out.extend_from_slice(b.as_bytes());
        out.push(b'"');
    } else {
        string(out, &format!("{a}.{b}"));
    }
}

pub(crate) fn int(out: &mut Vec<u8>, i: i64) {
    if i < 0 {
        out.push(b'-');
    }
    uint(out, i.unsigned_abs());
}

pub(crate) fn uint(out: &mut Vec<u8>, mut i: u64) {
    let mut digits = [0u8; 20];
    let mut n = digits.len();
    loop {
        n -= 1;
        digits[n] = b'0' + (i % 10) as u8;
        i /= 10;
        if i == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[n..]);
}

/// A float: finite ones as JSON numbers that keep a fraction (`1.0`, not `1`), the others
/// as `"NaN"`, `"inf"`, `"-inf"`.
pub(crate) fn float(out: &mut Vec<u8>, x: f64) {
    if x.is_nan() {
        out.extend_from_slice(b"\"NaN\"");
    } else if x.is_infinite() {
        out.extend_from_slice(if x > 0.0 { b"\"inf\"" as &[u8] } else { b"\"-inf\"" });
    } else {
        let _ = serde_json::to_writer(&mut *out, &x);
    }
}

/// A value as it is written beside its kind (`"value": …`).
pub(crate) fn value(out: &mut Vec<u8>, v: &Value) {
    match v {
        Value::Int(i) => int(out, *i),
        Value::Float(x) => float(out, *x),
        Value::Bool(b) => out.extend_from_slice(if *b { b"true" } else { b"false" }),
        Value::Str(s) => string(out, s),
        Value::Guid(g) => uint(out, g.get()),
        Value::Bytes(b) => {
            out.push(b'"');
            base64(out, b);
            out.push(b'"');
        }
        Value::List(items) | Value::Set(items) => {
            out.push(b'[');
            for (i, e) in items.iter().enumerate() {
                if i > 0 {
                    out.push(b',');
                }
                match e {
                    Value::Int(_) | Value::Float(_) | Value::Bool(_) | Value::Str(_) => {
                        value(out, e)
                    }
                    _ => typed(out, e),
                }
            }
            out.push(b']');
        }
    }
}

/// `{"kind": K, "value": V}`.
pub(crate) fn typed(out: &mut Vec<u8>, v: &Value) {
    out.extend_from_slice(b"{\"kind\":\"");
    out.extend_from_slice(v.kind().name().as_bytes());
    out.extend_from_slice(b"\",\"value\":");
    value(out, v);
    out.push(b'}');
}

/// A list of typed values: `[{"kind": …, "value": …}, …]`.
pub(crate) fn typed_list(out: &mut Vec<u8>, vs: &[Value]) {
    out.push(b'[');
    for (i, v) in vs.iter().enumerate() {
        if i > 0 {
            out.push(b',');
        }
        typed(out, v);
    }
    out.push(b']');
}

/// A value as plain JSON (the `--log` form: `/events` fields).
pub(crate) fn plain(out: &mut Vec<u8>, v: &Value) {
    match v {
        Value::Float(x) if !x.is_finite() => float(out, *x),
        Value::Bytes(_) => value(out, v),
        Value::List(items) | Value::Set(items) => {
            out.push(b'[');
            for (i, e) in items.iter().enumerate() {
                if i > 0 {
                    out.push(b',');
                }
                plain(out, e);
            }
            out.push(b']');
        }
        _ => value(out, v),
    }
}

const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// Standard, padded base64 (what JSON Schema's `contentEncoding: base64` and Foxglove read).
pub(crate) fn base64(out: &mut Vec<u8>, data: &[u8]) {
    out.reserve(data.len().div_ceil(3) * 4);
    let mut chunks = data.chunks_exact(3);
    for c in &mut chunks {
        let n = (u32::from(c[0]) << 16) | (u32::from(c[1]) << 8) | u32::from(c[2]);
        out.extend_from_slice(&[
            ALPHABET[(n >> 18) as usize & 63],
            ALPHABET[(n >> 12) as usize & 63],
            ALPHABET[(n >> 6) as usize & 63],
            ALPHABET[n as usize & 63],
        ]);
    }
    match *chunks.remainder() {
        [a] => {
            let n = u32::from(a) << 16;
            out.extend_from_slice(&[
                ALPHABET[(n >> 18) as usize & 63],
                ALPHABET[(n >> 12) as usize & 63],
                b'=',
                b'=',
            ]);
        }
        [a, b] => {
            let n = (u32::from(a) << 16) | (u32::from(b) << 8);
            out.extend_from_slice(&[
                ALPHABET[(n >> 18) as usize & 63],
                ALPHABET[(n >> 12) as usize & 63],
                ALPHABET[(n >> 6) as usize & 63],
                b'=',
            ]);
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(f: impl FnOnce(&mut Vec<u8>)) -> String {
        let mut out = Vec::new();
        f(&mut out);
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn base64_matches_the_standard_alphabet_with_padding() {
        assert_eq!(text(|o| base64(o, b"")), "");
        assert_eq!(text(|o| base64(o, b"f")), "Zg==");
        assert_eq!(text(|o| base64(o, b"fo")), "Zm8=");
        assert_eq!(text(|o| base64(o, b"foo")), "Zm9v");
        assert_eq!(text(|o| base64(o, b"foobar")), "Zm9vYmFy");
        assert_eq!(text(|o| base64(o, &[0xff, 0xfe, 0x00, 0x01])), "//4AAQ==");
    }

    #[test]
    fn integers_and_dotted_paths_are_written_without_allocating_as_json_reads_them() {
        assert_eq!(text(|o| int(o, i64::MIN)), i64::MIN.to_string());
        assert_eq!(text(|o| int(o, 0)), "0");
        assert_eq!(text(|o| uint(o, u64::MAX)), u64::MAX.to_string());
        assert_eq!(text(|o| dotted(o, "root.a", "speed")), r#""root.a.speed""#);
        assert_eq!(text(|o| dotted(o, "root.\"q\"", "x")), r#""root.\"q\".x""#);
    }

    #[test]
    fn floats_keep_a_fraction_and_non_finite_ones_are_strings() {
        assert_eq!(text(|o| value(o, &Value::Float(1.0))), "1.0");
        assert_eq!(text(|o| value(o, &Value::Int(1))), "1");
        assert_eq!(text(|o| value(o, &Value::Float(f64::NAN))), "\"NaN\"");
        assert_eq!(text(|o| value(o, &Value::Float(f64::NEG_INFINITY))), "\"-inf\"");
    }

    #[test]
    fn list_elements_other_than_scalars_carry_their_kind() {
        let g = mocu_value::Guid::new(7).unwrap();
        let v = Value::list([Value::Int(1), Value::str("a"), Value::Guid(g)]);
        assert_eq!(
            text(|o| typed(o, &v)),
            r#"{"kind":"list","value":[1,"a",{"kind":"guid","value":7}]}"#
        );
    }
}
