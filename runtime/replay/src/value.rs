//! Values as the recording writes them: JSON beside their kind (docs/recording.md, the
//! table of kinds). GUIDs stay the recording's; [`crate::World`] maps them.

use mocu_dataserver::{Guid, Value, ValueKind};
use serde_json::Value as Json;

/// A value of kind `kind` written as `json`.
pub fn decode(kind_name: &str, json: &Json) -> Option<Value> {
    Some(match (ValueKind::parse(kind_name)?, json) {
        (ValueKind::Int, j) => Value::Int(j.as_i64()?),
        (ValueKind::Float, Json::String(s)) => Value::Float(match s.as_str() {
            "NaN" => f64::NAN,
            "inf" => f64::INFINITY,
            "-inf" => f64::NEG_INFINITY,
            _ => return None,
        }),
        (ValueKind::Float, j) => Value::Float(j.as_f64()?),
        (ValueKind::Bool, j) => Value::Bool(j.as_bool()?),
        (ValueKind::String, j) => Value::str(j.as_str()?),
        (ValueKind::Guid, j) => Value::Guid(Guid::new(j.as_u64()?)?),
        (ValueKind::Bytes, j) => Value::Bytes(base64(j.as_str()?)?.into()),
        (ValueKind::List, Json::Array(a)) => Value::List(elements(a)?.into()),
        (ValueKind::Set, Json::Array(a)) => Value::Set(elements(a)?.into()),
        _ => return None,
    })
}

/// A typed value `{"kind": K, "value": V}` (arguments, list elements of other kinds).
pub fn decode_typed(json: &Json) -> Option<Value> {
    decode(json.get("kind")?.as_str()?, json.get("value")?)
}

fn elements(a: &[Json]) -> Option<Vec<Value>> {
    a.iter()
        .map(|e| match e {
            Json::Number(n) if n.is_i64() => n.as_i64().map(Value::Int),
            Json::Number(n) => n.as_f64().map(Value::Float),
            Json::Bool(b) => Some(Value::Bool(*b)),
            Json::String(s) => Some(Value::str(s)),
            other => decode_typed(other),
        })
        .collect()
}

/// Standard, padded base64.
pub(crate) fn base64(s: &str) -> Option<Vec<u8>> {
    let digit = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let bytes = s.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for group in bytes.chunks(4) {
        let mut n = 0u32;
        for (i, &c) in group.iter().enumerate() {
            n |= digit(c)? << (18 - 6 * i);
        }
        let take = match group.len() {
            4 => 3,
            3 => 2,
            2 => 1,
            _ => return None,
        };
        out.extend_from_slice(&n.to_be_bytes()[1..1 + take]);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn every_kind_of_the_table_decodes() {
        assert_eq!(decode("int", &json!(3)), Some(Value::Int(3)));
        assert_eq!(decode("float", &json!(3.5)), Some(Value::Float(3.5)));
        assert!(decode("float", &json!("NaN")).is_some_and(|v| v.as_f64().unwrap().is_nan()));
        assert_eq!(decode("float", &json!("-inf")), Some(Value::Float(f64::NEG_INFINITY)));
        assert_eq!(decode("bool", &json!(true)), Some(Value::Bool(true)));
        assert_eq!(decode("string", &json!("usv")), Some(Value::str("usv")));
        assert_eq!(decode("guid", &json!(12)), Some(Value::Guid(Guid::new(12).unwrap())));
        assert_eq!(decode("bytes", &json!("TW9jdQ==")), Some(Value::Bytes(b"Mocu"[..].into())));
        assert_eq!(decode("bytes", &json!("TW9j")), Some(Value::Bytes(b"Moc"[..].into())));
        let list = json!([1, 2.5, "a", {"kind": "guid", "value": 4}]);
        assert_eq!(
            decode("list", &list),
            Some(Value::List(
                vec![
                    Value::Int(1),
                    Value::Float(2.5),
                    Value::str("a"),
                    Value::Guid(Guid::new(4).unwrap())
                ]
                .into()
            ))
        );
    }

    #[test]
    fn a_value_that_does_not_fit_its_kind_is_refused() {
        assert_eq!(decode("int", &json!("3")), None);
        assert_eq!(decode("colour", &json!(3)), None);
        assert_eq!(decode("bytes", &json!("T!==")), None);
    }
}
