//! The payload format (docs/distribution.md): JSON, UTF-8, one document per sample.
//!
//! JSON because every tool reads it (Python's `json`, `jq`, a browser) and a vehicle's
//! properties are small: a float property's sample is ~60 bytes. Values carry their kind, so
//! a reader never guesses an int from a float: `{"kind":"float","value":3.5}`. Non-finite
//! floats are the strings `"NaN"`, `"inf"`, `"-inf"`; bytes are lowercase hex; a guid is
//! the publishing site's number for the object; lists and sets hold typed values.

use mocu_dataserver::{
    CallOutcome, Guid, MethodSpec, ObjectInfo, ParamSpec, PropMeta, PropName, Value, ValueKind,
};
use serde_json::{Map, Value as J, json};
use std::sync::Arc;

/// A malformed payload: counted and dropped by the receiver, never fatal.
#[derive(Debug, PartialEq)]
pub struct Malformed(pub String);

fn bad(what: impl Into<String>) -> Malformed {
    Malformed(what.into())
}

pub fn value(v: &Value) -> J {
    json!({"kind": v.kind().name(), "value": bare(v)})
}

fn bare(v: &Value) -> J {
    match v {
        Value::Int(i) => json!(i),
        Value::Float(x) if x.is_nan() => json!("NaN"),
        Value::Float(x) if x.is_infinite() => json!(if *x > 0.0 { "inf" } else { "-inf" }),
        Value::Float(x) => json!(x),
        Value::Bool(b) => json!(b),
        Value::Str(s) => json!(&**s),
        Value::Guid(g) => json!(g.get()),
        Value::Bytes(b) => J::String(b.iter().map(|x| format!("{x:02x}")).collect()),
        Value::List(xs) | Value::Set(xs) => J::Array(xs.iter().map(value).collect()),
    }
}

pub fn value_from(j: &J) -> Result<Value, Malformed> {
    let kind = j.get("kind").and_then(J::as_str).ok_or_else(|| bad("a value without `kind`"))?;
    let kind = ValueKind::parse(kind).ok_or_else(|| bad(format!("unknown kind `{kind}`")))?;
    let v = j.get("value").ok_or_else(|| bad("a value without `value`"))?;
    let wrong = || bad(format!("not a {kind}: {v}"));
    Ok(match kind {
        ValueKind::Int => Value::Int(v.as_i64().ok_or_else(wrong)?),
        ValueKind::Float => Value::Float(match v {
            J::String(s) if s == "NaN" => f64::NAN,
            J::String(s) if s == "inf" => f64::INFINITY,
            J::String(s) if s == "-inf" => f64::NEG_INFINITY,
            _ => v.as_f64().ok_or_else(wrong)?,
        }),
        ValueKind::Bool => Value::Bool(v.as_bool().ok_or_else(wrong)?),
        ValueKind::String => Value::str(v.as_str().ok_or_else(wrong)?),
        ValueKind::Guid => Value::Guid(v.as_u64().and_then(Guid::new).ok_or_else(wrong)?),
        ValueKind::Bytes => {
            let s = v.as_str().ok_or_else(wrong)?;
            let b = (0..s.len() / 2)
                .map(|i| s.get(2 * i..2 * i + 2).and_then(|h| u8::from_str_radix(h, 16).ok()))
                .collect::<Option<Vec<u8>>>()
                .filter(|_| s.len() % 2 == 0)
                .ok_or_else(wrong)?;
            Value::Bytes(b.into())
        }
        ValueKind::List | ValueKind::Set => {
            let items = v.as_array().ok_or_else(wrong)?;
            let items = items.iter().map(value_from).collect::<Result<Vec<_>, _>>()?;
            if kind == ValueKind::Set { Value::set(items) } else { Value::list(items) }
        }
    })
}

pub fn values(vs: &[Value]) -> J {
    J::Array(vs.iter().map(value).collect())
}

pub fn values_from(j: Option<&J>) -> Result<Vec<Value>, Malformed> {
    match j {
        None => Ok(Vec::new()),
        Some(J::Array(xs)) => xs.iter().map(value_from).collect(),
        Some(other) => Err(bad(format!("not a list of values: {other}"))),
    }
}

pub fn meta(m: &PropMeta) -> J {
    let mut o = Map::new();
    if let Some(k) = m.kind {
        o.insert("kind".into(), json!(k.name()));
    }
    let text = |o: &mut Map<String, J>, k: &str, v: &Option<Arc<str>>| {
        if let Some(v) = v {
            o.insert(k.into(), json!(&**v));
        }
    };
    text(&mut o, "units", &m.units);
    text(&mut o, "representation", &m.representation);
    text(&mut o, "description", &m.description);
    if let Some((lo, hi)) = m.range {
        o.insert("range".into(), json!([lo, hi]));
    }
    if let Some(hz) = m.rate_hz {
        o.insert("rate_hz".into(), json!(hz));
    }
    J::Object(o)
}

pub fn meta_from(j: &J) -> Result<PropMeta, Malformed> {
    let o = j.as_object().ok_or_else(|| bad("`meta` is not an object"))?;
    let text = |k: &str| o.get(k).and_then(J::as_str).map(Arc::from);
    let mut m = PropMeta {
        units: text("units"),
        representation: text("representation"),
        description: text("description"),
        ..PropMeta::default()
    };
    if let Some(k) = o.get("kind").and_then(J::as_str) {
        m.kind = Some(ValueKind::parse(k).ok_or_else(|| bad(format!("unknown kind `{k}`")))?);
    }
    if let Some(r) = o.get("range").and_then(J::as_array) {
        match (r.first().and_then(J::as_f64), r.get(1).and_then(J::as_f64)) {
            (Some(lo), Some(hi)) => m.range = Some((lo, hi)),
            _ => return Err(bad("`range` is not two numbers")),
        }
    }
    m.rate_hz = o.get("rate_hz").and_then(J::as_f64);
    Ok(m)
}

/// An object as it is published: `{"guid", "name", "type", "subtype", "methods"}`.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectRecord {
    pub guid: u64,
    pub info: ObjectInfo,
    pub methods: Vec<MethodSpec>,
}

fn params(ps: &[ParamSpec]) -> J {
    J::Array(
        ps.iter()
            .map(|p| {
                let mut o = Map::new();
                o.insert("name".into(), json!(&*p.name));
                if let Some(k) = p.kind {
                    o.insert("kind".into(), json!(k.name()));
                }
                if let Some(u) = &p.units {
                    o.insert("units".into(), json!(&**u));
                }
                J::Object(o)
            })
            .collect(),
    )
}

fn params_from(j: Option<&J>) -> Vec<ParamSpec> {
    let Some(J::Array(xs)) = j else { return Vec::new() };
    xs.iter()
        .map(|p| ParamSpec {
            name: p.get("name").and_then(J::as_str).unwrap_or("").into(),
            kind: p.get("kind").and_then(J::as_str).and_then(ValueKind::parse),
            units: p.get("units").and_then(J::as_str).map(Arc::from),
        })
        .collect()
}

pub fn object(r: &ObjectRecord) -> Vec<u8> {
    let methods: Vec<J> = r
        .methods
        .iter()
        .map(|m| {
            let mut o = Map::new();
            o.insert("name".into(), json!(m.name.as_str()));
            o.insert("params".into(), params(&m.params));
            o.insert("results".into(), params(&m.results));
            if let Some(d) = &m.description {
                o.insert("description".into(), json!(&**d));
            }
            J::Object(o)
        })
        .collect();
    let j = json!({
        "guid": r.guid,
        "name": &*r.info.name,
        "type": &*r.info.kind,
        "subtype": &*r.info.subtype,
        "methods": methods,
    });
    j.to_string().into_bytes()
}

fn parse(bytes: &[u8]) -> Result<J, Malformed> {
    serde_json::from_slice(bytes).map_err(|e| bad(format!("not JSON: {e}")))
}

pub fn object_from(bytes: &[u8]) -> Result<ObjectRecord, Malformed> {
    let j = parse(bytes)?;
    let s = |k: &str| j.get(k).and_then(J::as_str);
    let name = s("name").ok_or_else(|| bad("an object without `name`"))?;
    let info = ObjectInfo::new(name, s("type").unwrap_or("")).subtype(s("subtype").unwrap_or(""));
    let mut methods = Vec::new();
    if let Some(J::Array(ms)) = j.get("methods") {
        for m in ms {
            let Some(name) = m.get("name").and_then(J::as_str).filter(|n| !n.is_empty()) else {
                return Err(bad("a method without `name`"));
            };
            let mut spec = MethodSpec::new(name);
            spec.params = params_from(m.get("params"));
            spec.results = params_from(m.get("results"));
            spec.description = m.get("description").and_then(J::as_str).map(Arc::from);
            methods.push(spec);
        }
    }
    Ok(ObjectRecord { guid: j.get("guid").and_then(J::as_u64).unwrap_or(0), info, methods })
}

/// A property sample: `{"object": guid, "value": typed, "meta": {...}}`; `meta` only when
/// the property is new or its metadata changed (and in snapshots).
pub fn property(object: Guid, v: &Value, m: Option<&PropMeta>) -> Vec<u8> {
    let mut o = Map::new();
    o.insert("object".into(), json!(object.get()));
    o.insert("value".into(), value(v));
    if let Some(m) = m {
        o.insert("meta".into(), meta(m));
    }
    J::Object(o).to_string().into_bytes()
}

pub fn property_from(bytes: &[u8]) -> Result<(Value, Option<PropMeta>), Malformed> {
    let j = parse(bytes)?;
    let v = value_from(j.get("value").ok_or_else(|| bad("a property without `value`"))?)?;
    let m = j.get("meta").map(meta_from).transpose()?;
    Ok((v, m))
}

/// A stream message (a camera frame): a JSON line, then the bytes of its `bytes` arguments
/// back to back. The line is `{"args": [typed…]}` where a top-level `bytes` argument is
/// `{"kind":"bytes","len":N}` instead of hex, its N bytes following the newline in argument
/// order (a 640×480 frame is not made 2.5 MB of hex text). Compact JSON holds no raw
/// newline, so a reader splits at the first one (Python: `bytes.partition(b"\n")`).
pub fn stream(args: &[Value]) -> Vec<u8> {
    let blobs: usize = args.iter().map(|a| if let Value::Bytes(b) = a { b.len() } else { 0 }).sum();
    let head: Vec<J> = args
        .iter()
        .map(|a| match a {
            Value::Bytes(b) => json!({"kind": "bytes", "len": b.len()}),
            other => value(other),
        })
        .collect();
    let mut out = json!({ "args": head }).to_string().into_bytes();
    out.reserve_exact(1 + blobs);
    out.push(b'\n');
    for a in args {
        if let Value::Bytes(b) = a {
            out.extend_from_slice(b);
        }
    }
    out
}

pub fn stream_from(bytes: &[u8]) -> Result<Vec<Value>, Malformed> {
    let nl = bytes
        .iter()
        .position(|&b| b == b'\n')
        .ok_or_else(|| bad("a stream message without its newline"))?;
    let j = parse(&bytes[..nl])?;
    let args = j
        .get("args")
        .and_then(J::as_array)
        .ok_or_else(|| bad("a stream message without `args`"))?;
    let mut tail = &bytes[nl + 1..];
    let mut out = Vec::with_capacity(args.len());
    for a in args {
        let blob = a.get("kind").and_then(J::as_str) == Some("bytes") && a.get("value").is_none();
        if !blob {
            out.push(value_from(a)?);
            continue;
        }
        let n = a
            .get("len")
            .and_then(J::as_u64)
            .ok_or_else(|| bad("a bytes argument without `len`"))?;
        let n = usize::try_from(n).ok().filter(|n| *n <= tail.len());
        let n = n.ok_or_else(|| bad("a stream message shorter than its `len`s"))?;
        let (b, rest) = tail.split_at(n);
        out.push(Value::Bytes(b.into()));
        tail = rest;
    }
    if !tail.is_empty() {
        return Err(bad("a stream message longer than its `len`s"));
    }
    Ok(out)
}

/// A call's query payload: `{"args": [typed…], "timeout_ms": N, "operator": NAME,
/// "site": SITE}` (operator and site: the calling process's, for control arbitration).
pub fn call(args: &[Value], timeout_ms: u64, operator: &str, site: &str) -> Vec<u8> {
    json!({"args": values(args), "timeout_ms": timeout_ms, "operator": operator, "site": site})
        .to_string()
        .into_bytes()
}

pub struct CallRequest {
    pub args: Vec<Value>,
    pub timeout_ms: Option<u64>,
    pub operator: Option<String>,
    pub site: Option<String>,
}

pub fn call_from(bytes: &[u8]) -> Result<CallRequest, Malformed> {
    if bytes.is_empty() {
        return Ok(CallRequest { args: Vec::new(), timeout_ms: None, operator: None, site: None });
    }
    let j = parse(bytes)?;
    Ok(CallRequest {
        args: values_from(j.get("args"))?,
        timeout_ms: j.get("timeout_ms").and_then(J::as_u64),
        operator: j.get("operator").and_then(J::as_str).map(String::from),
        site: j.get("site").and_then(J::as_str).map(String::from),
    })
}

/// A call's outcome: `{"outcome": label, "results"|"reason": …}` (labels of
/// [`CallOutcome::label`]).
pub fn outcome(o: &CallOutcome) -> Vec<u8> {
    let j = match o {
        CallOutcome::Accepted(r) => json!({"outcome": o.label(), "results": values(r)}),
        CallOutcome::Refused(why) | CallOutcome::Failed(why) => {
            json!({"outcome": o.label(), "reason": why})
        }
        _ => json!({"outcome": o.label()}),
    };
    j.to_string().into_bytes()
}

pub fn outcome_from(bytes: &[u8]) -> Result<CallOutcome, Malformed> {
    let j = parse(bytes)?;
    let reason = || j.get("reason").and_then(J::as_str).unwrap_or("").to_string();
    Ok(match j.get("outcome").and_then(J::as_str) {
        Some("accepted") => CallOutcome::Accepted(values_from(j.get("results"))?),
        Some("refused") => CallOutcome::Refused(reason()),
        Some("failed") => CallOutcome::Failed(reason()),
        Some("no_such_method") => CallOutcome::NoSuchMethod,
        Some("no_such_object") => CallOutcome::NoSuchObject,
        Some("timed_out") => CallOutcome::TimedOut,
        other => return Err(bad(format!("unknown outcome {other:?}"))),
    })
}

/// The names of `specs`, for comparing method lists cheaply.
pub fn method_names(specs: &[MethodSpec]) -> Vec<PropName> {
    specs.iter().map(|m| m.name).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_of_value_reads_back_equal() {
        let vs = [
            Value::Int(-3),
            Value::Float(2.5),
            Value::Float(f64::NAN),
            Value::Float(f64::NEG_INFINITY),
            Value::Bool(true),
            Value::str("a \"b\""),
            Value::Guid(Guid::new(42).unwrap()),
            Value::Bytes(vec![0, 255, 16].into()),
            Value::list([Value::Int(1), Value::str("x"), Value::list([Value::Bool(false)])]),
            Value::set([Value::Int(2), Value::Int(1)]),
        ];
        for v in vs {
            let back = value_from(&value(&v)).unwrap();
            assert!(back.total_cmp(&v).is_eq() && back.kind() == v.kind(), "{v:?} -> {back:?}");
        }
    }

    #[test]
    fn every_outcome_reads_back_equal() {
        for o in [
            CallOutcome::Accepted(vec![Value::Int(1)]),
            CallOutcome::Refused("engine off".into()),
            CallOutcome::Failed("link lost".into()),
            CallOutcome::NoSuchMethod,
            CallOutcome::NoSuchObject,
            CallOutcome::TimedOut,
        ] {
            assert_eq!(outcome_from(&outcome(&o)), Ok(o));
        }
    }

    #[test]
    fn metadata_and_objects_read_back_equal() {
        let m = PropMeta::typed(ValueKind::Float).units("m/s").range(0.0, 20.0).rate(10.0);
        let bytes = property(Guid::new(7).unwrap(), &Value::Float(1.0), Some(&m));
        assert_eq!(property_from(&bytes), Ok((Value::Float(1.0), Some(m))));
        let r = ObjectRecord {
            guid: 9,
            info: ObjectInfo::new("usv1", "usv").subtype("catamaran"),
            methods: vec![MethodSpec::new("arm").param(ParamSpec::new("on", ValueKind::Bool))],
        };
        assert_eq!(object_from(&object(&r)), Ok(r));
    }

    #[test]
    fn a_stream_message_reads_back_equal_its_bytes_raw_after_the_line() {
        let frame: Vec<u8> = (0..=255u8).cycle().take(640 * 3).collect();
        let args = vec![
            Value::Bytes(frame.clone().into()),
            Value::Int(640),
            Value::str("rgb8\nnot a line break"),
            Value::Bytes(vec![b'\n', 0].into()),
        ];
        let bytes = stream(&args);
        assert_eq!(stream_from(&bytes), Ok(args));
        // The frame travels as itself, not as hex.
        assert!(bytes.len() < frame.len() + 200, "{} bytes", bytes.len());
        for bad in [
            &b"{\"args\":[]}"[..],
            b"{\"args\":[{\"kind\":\"bytes\",\"len\":9}]}\nabc",
            b"{\"args\":[]}\nx",
            b"\xff\n",
        ] {
            assert!(stream_from(bad).is_err(), "{}", String::from_utf8_lossy(bad));
        }
    }

    #[test]
    fn malformed_payloads_are_errors_not_panics() {
        for b in [&b"not json"[..], b"{}", b"{\"value\":{\"kind\":\"int\",\"value\":1.5}}", b"[1]"]
        {
            assert!(property_from(b).is_err(), "{}", String::from_utf8_lossy(b));
        }
        assert!(object_from(b"{\"methods\":[{}]}").is_err());
        assert!(outcome_from(b"{\"outcome\":\"maybe\"}").is_err());
    }
}
