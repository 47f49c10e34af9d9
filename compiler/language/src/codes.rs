//! The stable diagnostic codes. Each is documented with an example in docs/diagnostics.md and
//! has at least one test under tests/syntax/. Never renumber; retire codes instead.

pub const SYNTAX: &str = "E0101";
pub const STRAY_TEXT: &str = "E0102";
pub const UNCLOSED: &str = "E0103";
pub const UNCLOSED_TEXT: &str = "E0104";
pub const CONFUSABLE: &str = "E0105";
pub const TOO_DEEP: &str = "E0106";
pub const NOT_UTF8: &str = "E0107";

pub const FILE_NOT_FOUND: &str = "E0201";
pub const USE_CYCLE: &str = "E0202";
pub const DUPLICATE: &str = "E0203";
pub const UNKNOWN_NAME: &str = "E0204";
pub const UNKNOWN_COMPONENT: &str = "E0205";
pub const UNKNOWN_WINDOW: &str = "E0206";
pub const UNKNOWN_INPUT: &str = "E0207";
pub const UNKNOWN_PARAM: &str = "E0208";
pub const MISSING_ARG: &str = "E0209";
pub const BAD_PROFILE: &str = "E0210";
pub const BAD_BINDING: &str = "E0211";
pub const UNKNOWN_MODE: &str = "E0212";
pub const UNKNOWN_ANCHOR: &str = "E0213";
pub const BAD_DESIGN: &str = "E0214";
pub const BAD_FLOW: &str = "E0215";
pub const BEYOND_LIMIT: &str = "E0216";

pub const NOT_A_NUMBER: &str = "E0301";
pub const TYPE_MISMATCH: &str = "E0302";
pub const ARG_COUNT: &str = "E0303";
pub const NOT_BOOL: &str = "E0304";
pub const UNKNOWN_TYPE: &str = "E0305";
pub const MISPLACED_CALL: &str = "E0306";
pub const BAD_FORMAT: &str = "E0307";
pub const NOT_A_PATH: &str = "E0308";
pub const UNKNOWN_PRIMITIVE: &str = "E0309";
pub const BAD_DURATION: &str = "E0310";

pub const UNKNOWN_PROPERTY: &str = "E0401";
pub const UNIT_MISMATCH: &str = "E0402";
pub const OUT_OF_RANGE: &str = "E0403";
pub const READ_ONLY: &str = "E0404";
pub const BAD_SCHEMA: &str = "E0405";

pub const UNUSED_LET: &str = "W0001";
pub const OUTSIDE_WINDOW: &str = "W0002";
pub const CONSTANT_WATCH: &str = "W0003";
pub const ABSURD_DURATION: &str = "W0004";
pub const SCREEN_PX_IN_DESIGN: &str = "W0005";

/// Every code with a one-line description (SARIF rule text, docs check).
pub const ALL: &[(&str, &str)] = &[
    (SYNTAX, "syntax error"),
    (STRAY_TEXT, "text outside any item"),
    (UNCLOSED, "unclosed brace"),
    (UNCLOSED_TEXT, "unclosed string, interpolation or block comment"),
    (CONFUSABLE, "look-alike character or single quote"),
    (TOO_DEEP, "nesting too deep"),
    (NOT_UTF8, "file is not UTF-8"),
    (FILE_NOT_FOUND, "file not found"),
    (USE_CYCLE, "`use` cycle"),
    (DUPLICATE, "duplicate definition"),
    (UNKNOWN_NAME, "unknown name"),
    (UNKNOWN_COMPONENT, "unknown component"),
    (UNKNOWN_WINDOW, "unknown window"),
    (UNKNOWN_INPUT, "unknown input device, axis, button or key"),
    (UNKNOWN_PARAM, "unknown parameter or event"),
    (MISSING_ARG, "missing required argument"),
    (BAD_PROFILE, "invalid profile"),
    (BAD_BINDING, "binding option that does not fit its input, or `shift` without a shift input"),
    (UNKNOWN_MODE, "`mode` action naming no declared mode"),
    (UNKNOWN_ANCHOR, "unknown anchor name"),
    (BAD_DESIGN, "`design` outside the layout file, twice, or not a positive px size"),
    (BAD_FLOW, "`flow` with an unknown direction, a gap not in px, or nothing to place"),
    (BEYOND_LIMIT, "`rect`, `at`, `design` or text `size` beyond what the display allocates"),
    (NOT_A_NUMBER, "a non-number used as a number"),
    (TYPE_MISMATCH, "type mismatch"),
    (ARG_COUNT, "wrong number of arguments"),
    (NOT_BOOL, "condition is not boolean"),
    (UNKNOWN_TYPE, "unknown type name"),
    (MISPLACED_CALL, "method call outside `call`, or `call` without a method"),
    (BAD_FORMAT, "invalid format spec"),
    (NOT_A_PATH, "`set` target is not a property path"),
    (UNKNOWN_PRIMITIVE, "unknown drawing primitive or style"),
    (BAD_DURATION, "duration that is negative, zero where a period is needed, or not constant"),
    (UNKNOWN_PROPERTY, "unknown property or method (schema)"),
    (UNIT_MISMATCH, "unit mismatch"),
    (OUT_OF_RANGE, "constant outside the declared range"),
    (READ_ONLY, "`set` of a read-only property"),
    (BAD_SCHEMA, "invalid schema file"),
    (UNUSED_LET, "unused `let`"),
    (OUTSIDE_WINDOW, "widget wholly outside its window"),
    (CONSTANT_WATCH, "watch condition is constant"),
    (ABSURD_DURATION, "duration longer than a day"),
    (SCREEN_PX_IN_DESIGN, "position reads the screen's size in a layout with `design`"),
];

pub fn describe(code: &str) -> &'static str {
    ALL.iter().find(|(c, _)| *c == code).map_or("", |(_, d)| d)
}
