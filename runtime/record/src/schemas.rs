//! The channels' JSON Schemas (docs/recording.md): Mocu's own, and Foxglove's well-known
//! ones where they fit (compressed video and images, locations), so Foxglove shows them.

pub(crate) const OBJECT: (&str, &str) = (
    "mocu.ObjectChange",
    r#"{"title":"mocu.ObjectChange","type":"object","properties":{
"op":{"type":"string","enum":["created","changed","deleted"]},
"guid":{"type":"integer"},"parent":{"type":"integer"},"index":{"type":"integer"},
"path":{"type":"string"},"name":{"type":"string"},"type":{"type":"string"},
"subtype":{"type":"string"}},"required":["op","guid","path"]}"#,
);

const VALUE: &str =
    r#"{"description":"a value (docs/recording.md): number, string, bool, base64 bytes or array"}"#;

pub(crate) fn property() -> String {
    format!(
        r#"{{"title":"mocu.PropertyChange","type":"object","properties":{{
"op":{{"type":"string","enum":["created","set","deleted"]}},
"object":{{"type":"integer"}},"path":{{"type":"string"}},"name":{{"type":"string"}},
"kind":{{"type":"string","enum":["int","float","bool","string","guid","bytes","list","set"]}},
"value":{VALUE},"unit":{{"type":"string"}},
"meta":{{"type":"object","properties":{{"kind":{{"type":"string"}},"units":{{"type":"string"}},
"representation":{{"type":"string"}},"description":{{"type":"string"}},
"range":{{"type":"array","items":{{"type":"number"}}}},"rate_hz":{{"type":"number"}}}}}}}},
"required":["op","object","path","name"]}}"#
    )
}

const TYPED: &str = r#"{"type":"object","properties":{"kind":{"type":"string"},"value":{}}}"#;

pub(crate) fn call() -> String {
    format!(
        r#"{{"title":"mocu.Call","type":"object","properties":{{
"op":{{"type":"string","enum":["call","outcome"]}},"id":{{"type":"integer"}},
"object":{{"type":"integer"}},"path":{{"type":"string"}},"method":{{"type":"string"}},
"args":{{"type":"array","items":{TYPED}}},
"outcome":{{"type":"string","enum":["accepted","refused","failed","no_such_method","no_such_object","timed_out"]}},
"reason":{{"type":"string"}},"results":{{"type":"array","items":{TYPED}}}}},
"required":["op","id"]}}"#
    )
}

pub(crate) const EVENT: (&str, &str) = (
    "mocu.Event",
    r#"{"title":"mocu.Event","type":"object","properties":{
"source":{"type":"string"},"event":{"type":"string"},"fields":{"type":"object"}},
"required":["source","event","fields"]}"#,
);

pub(crate) const LAYOUT: (&str, &str) = (
    "mocu.LayoutEvent",
    r#"{"title":"mocu.LayoutEvent","type":"object","properties":{
"event":{"type":"string"},"layout":{"type":"string"},"fields":{"type":"object"}},
"required":["event","fields"]}"#,
);

pub(crate) fn snapshot() -> String {
    format!(
        r#"{{"title":"mocu.WorldSnapshot","type":"object","properties":{{
"seq":{{"type":"integer"}},
"objects":{{"type":"array","items":{{"type":"object","properties":{{
"guid":{{"type":"integer"}},"parent":{{"type":"integer"}},"index":{{"type":"integer"}},
"name":{{"type":"string"}},"type":{{"type":"string"}},"subtype":{{"type":"string"}},
"properties":{{"type":"array","items":{{"type":"object","properties":{{
"name":{{"type":"string"}},"kind":{{"type":"string"}},"value":{VALUE},"meta":{{"type":"object"}}}}}}}}}}}}}}}},
"required":["seq","objects"]}}"#
    )
}

const TIME: &str = r#"{"type":"object","title":"time","properties":{"sec":{"type":"integer","minimum":0},"nsec":{"type":"integer","minimum":0,"maximum":999999999}}}"#;

/// Foxglove's `foxglove_msgs/msg/CompressedVideo` and `…/CompressedImage` (`ros2msg`, CDR),
/// with Mocu's `unit` and `arrival_us` after Foxglove's fields.
pub(crate) const COMPRESSED_VIDEO: (&str, &str) =
    ("foxglove_msgs/msg/CompressedVideo", COMPRESSED_FIELDS);
pub(crate) const COMPRESSED_IMAGE: (&str, &str) =
    ("foxglove_msgs/msg/CompressedImage", COMPRESSED_FIELDS);
const COMPRESSED_FIELDS: &str = "\
builtin_interfaces/Time timestamp
string frame_id
uint8[] data
string format
int64 unit
int64 arrival_us

================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
";

/// Foxglove's `foxglove.LocationFix` (JSON Schema form).
pub(crate) fn location_fix() -> String {
    format!(
        r#"{{"title":"foxglove.LocationFix","description":"A navigation satellite fix for any Global Navigation Satellite System","type":"object","properties":{{
"timestamp":{TIME},"frame_id":{{"type":"string"}},
"latitude":{{"type":"number"}},"longitude":{{"type":"number"}},"altitude":{{"type":"number"}},
"position_covariance":{{"type":"array","items":{{"type":"number"}},"minItems":9,"maxItems":9}},
"position_covariance_type":{{"type":"integer"}}}}}}"#
    )
}

/// Foxglove's `foxglove_msgs/msg/RawImage` (`ros2msg`, its dependency after the
/// separator line as ROS 2 bags write it): a camera's pixels as they were sent.
pub(crate) const RAW_IMAGE: (&str, &str) = (
    "foxglove_msgs/msg/RawImage",
    "\
builtin_interfaces/Time timestamp
string frame_id
uint32 width
uint32 height
string encoding
uint32 step
uint8[] data

================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
",
);

#[cfg(test)]
mod tests {
    #[test]
    fn every_schema_is_json() {
        let all = [
            super::OBJECT.1.to_string(),
            super::property(),
            super::call(),
            super::EVENT.1.to_string(),
            super::LAYOUT.1.to_string(),
            super::snapshot(),
            super::location_fix(),
        ];
        for s in all {
            let v: serde_json::Value =
                serde_json::from_str(&s).unwrap_or_else(|e| panic!("{e}: {s}"));
            assert!(v.get("title").is_some());
        }
    }
}
