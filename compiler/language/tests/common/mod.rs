//! Inputs shared by the fuzz tests (fuzz.rs) and the fast parser's differential test
//! (fast_parser.rs): the language's tokens, nesting generators and the corpus of real files.
#![allow(dead_code)]

pub const TOKENS: &[&str] = &[
    "use",
    "let",
    "window",
    "in",
    "component",
    "bind",
    "menu",
    "watch",
    "for",
    "each",
    "of",
    "type",
    "if",
    "then",
    "else",
    "when",
    "item",
    "enabled",
    "on",
    "at",
    "rect",
    "layer",
    "opacity",
    "visible",
    "source",
    "set",
    "call",
    "swap",
    "show",
    "hide",
    "alert",
    "warning",
    "true",
    "false",
    "self",
    "root",
    "and",
    "or",
    "not",
    "axis",
    "button",
    "key",
    "gamepad",
    "keyboard",
    "mouse",
    "left_y",
    "south",
    "circle",
    "text",
    "line",
    "polyline",
    "arc",
    "fill",
    "stroke",
    "size",
    "Dial",
    "Bar",
    "Button",
    "Video",
    "x",
    "y",
    "w",
    "h",
    "v",
    "usv",
    "nav",
    "speed",
    "value",
    "range",
    "index",
    "min",
    "max",
    "clamp",
    "deadzone",
    "format",
    "present",
    "{",
    "}",
    "(",
    ")",
    "[",
    "]",
    ",",
    ":",
    ".",
    "..",
    "=",
    "==",
    "!=",
    "<",
    "<=",
    ">",
    ">=",
    "+",
    "-",
    "*",
    "/",
    "!",
    "&&",
    "||",
    "??",
    "->",
    "?",
    "0",
    "1.5",
    "300ms",
    "5s",
    "100%",
    "10px",
    "45deg",
    "#ff0000",
    "#00ff0080",
    "\"s\"",
    "\"{x:.1}\"",
    "\"{\"",
    "\"a{b}c{d:03.0}\"",
    "\"",
    "//c\n",
    "/*",
    "*/",
    "\n",
    " ",
    "\t",
    "é",
    "°",
    "\"use\"",
    "stdlib/gauges.mocu",
    "\"stdlib/gauges.mocu\"",
    "\"lib.mocu\"",
    "#js: {",
    "#rhai: {",
    "`",
];

/// Openers and closers (or postfixes, with no closer) repeated `n` times.
pub const NESTERS: &[(&str, &str)] = &[
    ("(", ")"),
    ("[", "]"),
    ("{", "}"),
    ("-", ""),
    ("not ", ""),
    ("if true then ", " else 0"),
    ("", ".a"),
    ("", "[\"x\"]"),
    ("", "()"),
    ("", " + 1"),
    ("\"{", "}\""),
    ("f(", ")"),
    ("/*", ""),
    ("\"", ""),
    ("#js: {", "}"),
];

/// Every layout, stdlib file, syntax and format test and test data file: the seeds of the
/// mutation tests.
pub fn corpus() -> &'static [String] {
    static CORPUS: std::sync::OnceLock<Vec<String>> = std::sync::OnceLock::new();
    CORPUS.get_or_init(|| {
        let mut out = Vec::new();
        for dir in [
            "../../layouts",
            "../../stdlib",
            "tests/syntax",
            "tests/format",
            "../../tests",
            "../../runtime/widgets/tests",
        ] {
            walk(std::path::Path::new(dir), &mut out);
        }
        assert!(out.len() > 20, "the fuzz corpus is missing");
        out
    })
}

pub fn walk(dir: &std::path::Path, out: &mut Vec<String>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<_> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        if p.is_dir() {
            walk(&p, out);
        } else if p.extension().is_some_and(|e| e == "mocu") {
            let bytes = std::fs::read(&p).unwrap_or_default();
            out.push(String::from_utf8_lossy(&bytes).into_owned());
        }
    }
}

pub fn floor_boundary(s: &str, mut at: usize) -> usize {
    while !s.is_char_boundary(at) {
        at -= 1;
    }
    at
}
