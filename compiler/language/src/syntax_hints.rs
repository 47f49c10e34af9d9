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
    ("millisecond", "ms"),
    ("millis", "ms"),
    ("msecs", "ms"),
    ("msec", "ms"),
    ("hours", "min"),
    ("hour", "min"),
    // The right unit, but apart from its number (`5 s`).
    ("ms", "ms"),
    ("s", "s"),
    ("min", "min"),
    ("degrees", "deg"),
    ("degree", "deg"),
    ("pixels", "px"),
    ("percent", "%"),
];

/// Words each item reads besides names and expressions, for "did you mean `when`?" when a
/// syntax error sits on a near miss of one.
const ITEM_WORDS: &[(&str, &[&str])] = &[
    ("watch", &["when", "for", "clear", "repeat", "every", "then"]),
    ("window", &["rect", "layer", "at", "on"]),
    ("in", &["at", "on"]),
    ("for", &["each", "in", "of", "type"]),
    ("menu", &["for", "type", "item"]),
    ("bind", &["button", "axis", "key", "wheel", "shift", "mode", "hold", "double", "release"]),
    ("use", &["as"]),
];

/// Key names people write for the keys the language calls otherwise.
const KEY_ALIASES: &[(&str, &str)] = &[
    ("spacebar", "space"),
    ("space_bar", "space"),
    ("esc", "escape"),
    ("return", "enter"),
    ("del", "delete"),
    ("ins", "insert"),
    ("bksp", "backspace"),
    ("pgup", "page_up"),
    ("pageup", "page_up"),
    ("pgdn", "page_down"),
    ("pagedown", "page_down"),
    ("arrow_up", "up"),
    ("arrow_down", "down"),
    ("arrow_left", "left"),
    ("arrow_right", "right"),
];

pub const UNITS: &str =
    "units are ms, s, min, px, deg and %, written right after the number (`5s`)";

/// The item keyword of the innermost block open at the end of `before` (`watch` for a watch
/// inside a `for each`), or `item` (the first word of the top-level item).
pub fn inner_item<'a>(item: &'a str, before: &'a str) -> &'a str {
    let Some(open) = opening_of(before) else { return item };
    let line = before[..open].rsplit('\n').next().unwrap_or("");
    let word = line.split_whitespace().next().unwrap_or("");
    if crate::parser::ITEM_KEYWORDS.contains(&word) { word } else { item }
}

/// A script action written without its braces (`#js: mocu.write(…)`) or without the `:` of
/// its prefix (`#js { … }`).
fn script_hint(prev: &str, found: &str, after: &str) -> Option<(Option<String>, String)> {
    fn prefix(w: &str) -> Option<&str> {
        w.strip_prefix('#').filter(|n| {
            n.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) && n.chars().all(is_word_char)
        })
    }
    if let Some(engine) = prev.strip_suffix(':').and_then(prefix)
        && !found.starts_with('{')
    {
        return Some((
            Some(format!("the body of a `#{engine}:` script goes in braces")),
            format!(
                "write `#{engine}: {{ … }}`: the script runs from its `{{` to the `}}` that balances it"
            ),
        ));
    }
    let engine = prefix(found)?;
    after[found.len()..].trim_start().starts_with('{').then(|| {
        (
            Some(format!("a script's prefix ends with `:`: `#{engine}:`")),
            format!("write `#{engine}: {{ … }}`"),
        )
    })
}

/// A better (message, help) for a syntax error, when the mistake is recognised. `item` is
/// the keyword of the innermost item ([`inner_item`]), `before` the item's text up to the
/// error and `after` the rest of it.
pub fn hint(
    item: &str,
    before: &str,
    found: &str,
    message: &str,
    after: &str,
) -> Option<(Option<String>, String)> {
    let prev = before.split_whitespace().last().unwrap_or("");
    if let Some(h) = script_hint(prev, found, after) {
        return Some(h);
    }
    // `a: Label { … }` where a widget cannot go: in a window's body or a template's.
    let widget = found == ":" && is_word(prev)
        || is_word(found) && after[found.len()..].trim_start().starts_with(':');
    if widget && matches!(item, "window" | "for" | "watch" | "menu" | "bind") {
        let name = if found == ":" { prev } else { found };
        let component = after.trim_start_matches(|c: char| c == ':' || is_word_char(c));
        let component = component.trim_start_matches([':', ' ', '\t']);
        let component = first_word_of(component);
        let message = match opening_of(before) {
            None => format!("`{name}: {component}` is outside any `in` block"),
            Some(_) => format!("`{name}:` starts a widget, which cannot go in a `{item}`"),
        };
        return Some((
            Some(message),
            format!(
                "a widget goes inside `in WINDOW {{ … }}`: `in main {{ {name}: {component} {{ at X Y … }} }}`"
            ),
        ));
    }
    if item == "watch" && matches!(found, "for" | "clear" | "repeat") && before.contains("then") {
        return Some((
            Some(format!("`{found}` comes before `then` in a watch")),
            SHAPES[0].1.to_string(),
        ));
    }
    if found.starts_with('.') && before.ends_with("..") {
        let max = found.trim_start_matches('.');
        let min = before.trim_end_matches('.').split_whitespace().last().unwrap_or("MIN");
        let name = before.split_whitespace().rev().nth(1).filter(|w| is_word(w)).unwrap_or("");
        return Some((
            Some("a range's ends are joined by two dots `..`".into()),
            range_help(name, min, if max.is_empty() { "MAX" } else { max }),
        ));
    }
    if found.starts_with(',')
        && let Some(kw) =
            before.split_whitespace().rev().take(4).find(|w| *w == "at" || *w == "rect")
    {
        // The numbers as written, from the keyword to the first word that is no number.
        let from = before.rfind(kw).unwrap_or(0) + kw.len();
        let text = format!("{}{after}", &before[from..]);
        let numbers: Vec<&str> = text
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|w| !w.is_empty())
            .take_while(|w| w.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '.'))
            .take(4)
            .collect();
        return Some((
            Some(format!("`{kw}` takes numbers separated by spaces, not commas")),
            format!("write `{kw} {}`", numbers.join(" ")),
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
    if prev.parse::<f64>().is_ok()
        && (matches!(found, "to" | "-") || found.parse::<f64>().is_ok())
        && before.contains("range")
    {
        let max = if found.parse::<f64>().is_ok() { found } else { "MAX" };
        // The parameter's name when it stands right before the minimum (`range 0 40`).
        let name = before.split_whitespace().rev().nth(1).filter(|w| is_word(w)).unwrap_or("");
        return Some((
            Some(format!("`{found}` after `{prev}`: a range needs `..` between its ends")),
            range_help(name, prev, max),
        ));
    }
    if let Some(h) = near_miss(item, before, found, message) {
        return Some(h);
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

/// "did you mean `window`?" for a word at a syntax error that is one slip away from a word
/// the item reads there: the words pest expected (quoted in `message`), the item's own
/// words, and the item keywords when a new item could start.
fn near_miss(
    item: &str,
    before: &str,
    found: &str,
    message: &str,
) -> Option<(Option<String>, String)> {
    if !found.starts_with(|c: char| c.is_ascii_lowercase()) || !is_word(found) {
        return None;
    }
    let mut words: Vec<&str> = message.split('`').skip(1).step_by(2).collect();
    words.extend(ITEM_WORDS.iter().filter(|(k, _)| *k == item).flat_map(|(_, w)| w.iter()));
    // A word alone at the start of a line after a complete item: a misspelt item keyword.
    let line_start = before.trim_end_matches([' ', '\t']).ends_with('\n');
    let new_item = line_start && message.contains("the end of the item");
    if new_item {
        words.extend(crate::parser::ITEM_KEYWORDS);
    }
    let best = crate::diagnostics::did_you_mean(found, words)?;
    let message = if new_item {
        format!("`{found}` is not the start of an item")
    } else {
        format!("unexpected `{found}` in this `{item}`")
    };
    Some((Some(message), format!("did you mean `{best}`?")))
}

/// Help for an unknown keyboard key (E0207): the key it is a slip or another name for.
pub fn key_help(name: &str) -> String {
    let lower = name.to_ascii_lowercase();
    let alias = KEY_ALIASES.iter().find(|(a, _)| *a == lower).map(|(_, k)| k.to_string());
    match alias.or_else(|| {
        crate::diagnostics::did_you_mean(&lower, crate::builtins::NAMED_KEYS.iter().copied())
    }) {
        Some(k) => format!("did you mean `{k}`?"),
        None => {
            "keys are letters, digits, F1…F12 or a name such as `space`, `enter`, `escape`, `up`"
                .into()
        }
    }
}

/// How a range is written, for a range given as `0 to 40`, `0 - 40` or `0 40`; `name` is the
/// parameter's, or empty.
pub fn range_help(name: &str, min: &str, max: &str) -> String {
    let name = if name.is_empty() { String::new() } else { format!("{name} ") };
    format!("a range is written `{name}{min} .. {max}` (MIN `..` MAX)")
}

fn is_word_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The first word of `s` (letters, digits, `_`), or `Component` when there is none.
fn first_word_of(s: &str) -> &str {
    let end = s.find(|c: char| !is_word_char(c)).unwrap_or(s.len());
    if end == 0 { "Component" } else { &s[..end] }
}

fn is_word(w: &str) -> bool {
    w.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && w.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
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
        _ => crate::diagnostics::did_you_mean(word, crate::parser::ITEM_KEYWORDS.iter().copied())
            .map(|k| format!("did you mean `{k}`?")),
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
