//! What the language knows without any `use`: built-in functions, drawing primitives and
//! their styles, native components, window properties and input names.

use crate::types::{Type, TypeKind};

/// How a built-in's result type follows from its arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Returns {
    /// A number with the unit of the first argument.
    SameUnit,
    /// A unitless number.
    Unitless,
    /// A number in the given unit.
    Unit(&'static str),
    String,
    Colour,
    Bool,
}

pub struct Function {
    pub name: &'static str,
    /// Parameter kinds: 'n' number, 's' string, 'a' any value.
    pub params: &'static str,
    pub returns: Returns,
    pub doc: &'static str,
}

/// The documented built-in functions (docs/language.md, "Built-in functions").
pub const FUNCTIONS: &[Function] = &[
    Function {
        name: "min",
        params: "nn",
        returns: Returns::SameUnit,
        doc: "the smaller of two numbers",
    },
    Function {
        name: "max",
        params: "nn",
        returns: Returns::SameUnit,
        doc: "the larger of two numbers",
    },
    Function { name: "abs", params: "n", returns: Returns::SameUnit, doc: "absolute value" },
    Function { name: "clamp", params: "nnn", returns: Returns::SameUnit, doc: "clamp(x, lo, hi)" },
    Function { name: "round", params: "n", returns: Returns::SameUnit, doc: "nearest integer" },
    Function {
        name: "floor",
        params: "n",
        returns: Returns::SameUnit,
        doc: "largest integer not above",
    },
    Function {
        name: "ceil",
        params: "n",
        returns: Returns::SameUnit,
        doc: "smallest integer not below",
    },
    Function { name: "sqrt", params: "n", returns: Returns::Unitless, doc: "square root" },
    Function { name: "sin", params: "n", returns: Returns::Unitless, doc: "sine of radians" },
    Function { name: "cos", params: "n", returns: Returns::Unitless, doc: "cosine of radians" },
    Function {
        name: "atan2",
        params: "nn",
        returns: Returns::Unit("rad"),
        doc: "atan2(y, x) in radians",
    },
    Function { name: "deg", params: "n", returns: Returns::Unit("deg"), doc: "radians to degrees" },
    Function { name: "rad", params: "n", returns: Returns::Unit("rad"), doc: "degrees to radians" },
    Function {
        name: "mod",
        params: "nn",
        returns: Returns::SameUnit,
        doc: "remainder, sign of the divisor",
    },
    Function {
        name: "lerp",
        params: "nnn",
        returns: Returns::SameUnit,
        doc: "lerp(a, b, t) = a + (b - a) * t",
    },
    Function {
        name: "deadzone",
        params: "nn",
        returns: Returns::SameUnit,
        doc: "deadzone(x, dz): 0 inside ±dz, rescaled outside",
    },
    Function {
        name: "format",
        params: "as",
        returns: Returns::String,
        doc: "format(x, \".1\"): a value as text with a format spec",
    },
    Function {
        name: "rgb",
        params: "nnn",
        returns: Returns::Colour,
        doc: "rgb(r, g, b), 0..255 each",
    },
    Function {
        name: "rgba",
        params: "nnnn",
        returns: Returns::Colour,
        doc: "rgba(r, g, b, a), a in 0..1",
    },
    Function {
        name: "present",
        params: "a",
        returns: Returns::Bool,
        doc: "true when the value is not absent",
    },
];

pub fn function(name: &str) -> Option<&'static Function> {
    FUNCTIONS.iter().find(|f| f.name == name)
}

/// A drawing primitive usable in a component body.
pub struct PrimitiveDef {
    pub name: &'static str,
    /// Positional arguments: 'n' number, 's' string, 'a' any (text).
    pub args: &'static str,
    /// Repeats the argument list (polyline: pairs of numbers, at least two).
    pub variadic: bool,
}

pub const PRIMITIVES: &[PrimitiveDef] = &[
    PrimitiveDef { name: "rect", args: "nnnn", variadic: false },
    PrimitiveDef { name: "rounded", args: "nnnnn", variadic: false },
    PrimitiveDef { name: "circle", args: "nnn", variadic: false },
    PrimitiveDef { name: "arc", args: "nnnnn", variadic: false },
    PrimitiveDef { name: "line", args: "nnnn", variadic: false },
    PrimitiveDef { name: "polyline", args: "nn", variadic: true },
    PrimitiveDef { name: "text", args: "nna", variadic: false },
    PrimitiveDef { name: "image", args: "nnnns", variadic: false },
];

pub fn primitive(name: &str) -> Option<&'static PrimitiveDef> {
    PRIMITIVES.iter().find(|p| p.name == name)
}

/// Every style name (one spelling: `colour`, as in the type name; `color` is refused with a
/// did-you-mean).
pub const STYLES: &[&str] =
    &["fill", "stroke", "colour", "width", "size", "opacity", "align", "font", "visible"];

/// Styles a primitive accepts, with their types.
pub fn style_type(name: &str) -> Option<Type> {
    Some(match name {
        "fill" | "stroke" | "colour" => Type::COLOUR,
        "width" | "size" | "opacity" => Type::number(),
        "align" | "font" => Type::STRING,
        "visible" => Type::BOOL,
        _ => return None,
    })
}

/// A native component: drawn by Rust, not by primitives.
pub struct NativeDef {
    pub name: &'static str,
    /// (name, type, has a default)
    pub params: &'static [(&'static str, &'static str, bool)],
    pub events: &'static [&'static str],
    pub doc: &'static str,
}

pub const NATIVES: &[NativeDef] = &[
    NativeDef {
        name: "Video",
        params: &[("source", "object", false), ("fit", "string", true)],
        events: &["press"],
        doc: "a camera's live video",
    },
    NativeDef {
        name: "Map",
        params: &[("follow", "object", true), ("zoom", "number", true)],
        events: &["select"],
        doc: "a chart with every vehicle",
    },
    NativeDef {
        name: "VehicleList",
        params: &[("filter", "string", true)],
        events: &["select"],
        doc: "the discovered vehicles",
    },
    NativeDef {
        name: "BindingLegend",
        params: &[("device", "string", true)],
        events: &[],
        doc: "the layout's input bindings in use and what each does (from its `bind` blocks)",
    },
    NativeDef {
        name: "AlertLayer",
        params: &[],
        events: &[],
        doc: "alerts and failed commands (the runtime adds one on top unless a layout places it)",
    },
];

pub fn native(name: &str) -> Option<&'static NativeDef> {
    NATIVES.iter().find(|n| n.name == name)
}

/// Window properties besides `rect`, with their types.
pub fn window_prop_type(name: &str) -> Option<Type> {
    Some(match name {
        "layer" | "opacity" => Type::number(),
        "visible" => Type::BOOL,
        "type" => Type::STRING,
        "source" => Type::new(TypeKind::Object { object_type: None }).maybe_absent(true),
        _ => return None,
    })
}
pub const WINDOW_PROPS: &[&str] = &["layer", "opacity", "visible", "type", "source"];

/// A binding kind of a device and its input names.
pub type BindingKind = (&'static str, &'static [&'static str]);

/// Input devices, their binding kinds and input names. Keys are checked by [`is_key`].
pub const DEVICES: &[(&str, &[BindingKind])] = &[
    (
        "gamepad",
        &[
            ("axis", &["left_x", "left_y", "right_x", "right_y", "left_trigger", "right_trigger"]),
            (
                "button",
                &[
                    "south",
                    "east",
                    "north",
                    "west",
                    "left_bumper",
                    "right_bumper",
                    "left_trigger",
                    "right_trigger",
                    "select",
                    "start",
                    "mode",
                    "left_stick",
                    "right_stick",
                    "dpad_up",
                    "dpad_down",
                    "dpad_left",
                    "dpad_right",
                ],
            ),
        ],
    ),
    ("keyboard", &[("key", &[])]),
    ("mouse", &[("button", &["left", "right", "middle"]), ("wheel", &["vertical", "horizontal"])]),
];

pub const NAMED_KEYS: &[&str] = &[
    "space",
    "enter",
    "escape",
    "tab",
    "backspace",
    "delete",
    "insert",
    "home",
    "end",
    "page_up",
    "page_down",
    "up",
    "down",
    "left",
    "right",
    "shift",
    "ctrl",
    "alt",
];

pub fn is_key(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    (lower.len() == 1 && lower.chars().all(|c| c.is_ascii_alphanumeric()))
        || NAMED_KEYS.contains(&lower.as_str())
        || lower
            .strip_prefix('f')
            .and_then(|n| n.parse::<u8>().ok())
            .is_some_and(|n| (1..=12).contains(&n))
}

/// The implicit value a binding's actions can read: `axis` (−1..1) or `delta` (wheel steps).
pub fn binding_value(kind: &str) -> Option<&'static str> {
    match kind {
        "axis" => Some("axis"),
        "wheel" => Some("delta"),
        _ => None,
    }
}

pub const ALERT_LEVELS: &[&str] = &["info", "warning", "critical"];
