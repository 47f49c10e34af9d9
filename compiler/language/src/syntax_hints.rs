//! Help for syntax errors that names the fix: what the item in hand expects, instead of pest's
//! "expected something else". Called by the parser with the item's first word, the token found
//! and pest's message; returns a better message and help where it knows the mistake.

/// The shape of each item, for "a watch reads …".
const SHAPES: &[(&str, &str)] = &[
    (
        "watch",
        "a watch reads `watch NAME { when CONDITION [for DURATION] [clear when CONDITION] [repeat every DURATION] then ACTIONS }`",
    ),
    ("window", "a window reads `window NAME { rect X Y W H  layer N  … }`"),
    ("in", "widgets go in `in WINDOW { NAME: Component { at X Y W H  param value … } }`"),
    (
        "component",
        "a component reads `component Name(param: type = default, on event) { primitives }`",
    ),
    ("bind", "a binding reads `bind DEVICE { button NAME [options] -> ACTIONS }`"),
    ("menu", "a menu reads `menu for type \"TYPE\" { item \"Label\" -> ACTIONS }`"),
    (
        "for",
        "a template reads `for each NAME in OBJECT [of type \"TYPE\"] { lets, windows, in blocks, watches }`",
    ),
    ("let", "a let reads `let NAME = EXPRESSION`"),
    ("use", "a use reads `use \"FILE.mocu\" [as NAME]`"),
];

/// Unit words people write after a number, and the suffix the language takes.
const UNIT_WORDS: &[(&str, &str)] = &[
    ("seconds", "s"),
    ("second", "s"),
    ("secs", "s"),
    ("sec", "s"),
    ("minutes", "min"),
    ("minute", "min"),
    ("mins", "min"),
    ("m", "min"),
    ("milliseconds", "ms"),
    ("millis", "ms"),
    ("degrees", "deg"),
    ("degree", "deg"),
    ("pixels", "px"),
    ("percent", "%"),
];

pub const UNITS: &str =
    "units are ms, s, min, px, deg and %, written right after the number (`5s`)";

/// A better (message, help) for a syntax error, when the mistake is recognised.
/// `before` is the item's text up to the error.
pub fn hint(
    item: &str,
    before: &str,
    found: &str,
    message: &str,
) -> Option<(Option<String>, String)> {
    let prev = before.split_whitespace().last().unwrap_or("");
    if found == "," && before.split_whitespace().rev().take(4).any(|w| w == "at" || w == "rect") {
        return Some((
            Some("`at` and `rect` take numbers separated by spaces, not commas".into()),
            "write `at 10 10 100 100`".into(),
        ));
    }
    if let Some((_, unit)) = UNIT_WORDS.iter().find(|(w, _)| *w == found)
        && prev.parse::<f64>().is_ok()
    {
        return Some((
            Some(format!("`{found}` is not a unit")),
            format!("write `{prev}{unit}`: {UNITS}"),
        ));
    }
    if let Some(split) = found.find(|c: char| !(c.is_ascii_digit() || c == '.'))
        && split > 0
        && found[split..].chars().all(|c| c.is_alphabetic())
    {
        let unit = &found[split..];
        let fix = UNIT_WORDS
            .iter()
            .find(|(w, _)| *w == unit)
            .map(|(_, u)| format!("write `{}{u}`: ", &found[..split]))
            .unwrap_or_default();
        return Some((
            Some(format!("`{found}` is not a number with a unit")),
            format!("{fix}{UNITS}"),
        ));
    }
    if matches!(found, "to" | "-") && prev.parse::<f64>().is_ok() && before.contains("range") {
        return Some((None, format!("a range is written `range {prev} .. MAX`")));
    }
    if item == "for" && matches!(found, "bind" | "menu" | "component" | "use" | "for") {
        return Some((
            Some(format!("`{found}` cannot go inside `for each`")),
            format!(
                "`{found}` is a top-level item: move it out of the `for each` (a template holds lets, windows, in blocks and watches)"
            ),
        ));
    }
    if found.starts_with(|c: char| c.is_ascii_uppercase()) && message.contains("end of the item") {
        return Some((Some(format!("`{found}` is outside any `in` block")), stray(found)?));
    }
    let no_then = !before.split_whitespace().any(|w| w == "then");
    if item == "watch"
        && no_then
        && (found.is_empty() || found == "}" || message.contains("something else"))
    {
        return Some((
            Some("this watch has no `then` and actions".into()),
            SHAPES[0].1.to_string(),
        ));
    }
    if message.contains("something else")
        && let Some((_, shape)) = SHAPES.iter().find(|(k, _)| *k == item)
    {
        let shown =
            if found.is_empty() { "the end of the item".into() } else { format!("`{found}`") };
        return Some((Some(format!("unexpected {shown} in this `{item}`")), shape.to_string()));
    }
    None
}

/// Help for text outside any item (E0102).
pub fn stray(word: &str) -> Option<String> {
    if word.starts_with(|c: char| c.is_ascii_uppercase()) {
        return Some(format!(
            "a widget goes inside `in WINDOW {{ … }}`: `in main {{ name: {word} {{ at X Y W H … }} }}`"
        ));
    }
    match word {
        "}" => Some("this `}` closes nothing: is there one `}` too many above it?".into()),
        "const" | "var" | "val" => Some("a constant is written `let NAME = VALUE`".into()),
        "function" | "fn" | "def" => {
            Some("reusable drawing is a `component`; values are `let`s".into())
        }
        _ => None,
    }
}

/// The offset of the `{` that a `}` right after `before` would close (strings and comments
/// skipped), if any.
pub fn opening_of(before: &str) -> Option<usize> {
    let b = before.as_bytes();
    let mut stack = Vec::new();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' && b[i] != b'\n' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'{' => stack.push(i),
            b'}' => {
                stack.pop();
            }
            _ => {}
        }
        i += 1;
    }
    stack.pop()
}
