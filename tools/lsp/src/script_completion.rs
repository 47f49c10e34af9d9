//! Completion inside a script action's body (`#js: { … }`, `#rhai: { … }`): the script's own
//! language, so none of the layout's words; the DataServer API the engines give a script
//! (docs/scripting.md, "The API") and the variables an action's script has.

use lsp_types::{CompletionItem, CompletionItemKind};
use mocu_language::script_text;

/// The API: (JavaScript member, Rhai function, what it does).
const API: &[(&str, &str, &str)] = &[
    (
        "read",
        "read",
        "read(path): the value at a path (`vehicles.usv1.nav.speed`); absent: undefined / ()",
    ),
    ("write", "write", "write(path, value): writes a property; a refused write is an exception"),
    (
        "subscribe",
        "subscribe",
        "subscribe(path, f): f(value) now and on each change; follows discovery",
    ),
    (
        "call",
        "call_method",
        "call(path, args, f): calls a method; f(status, detail) with its outcome",
    ),
    ("create", "create", "create(parent, name, kind): creates an object; returns its path"),
    ("after", "after", "after(ms, f): f() once, after ms of the DataServer's clock"),
];

/// The variables an action's script has.
const VARIABLES: &[(&str, &str)] = &[
    ("self", "the path of a menu's object, or of a `for each` instance"),
    ("selected", "the path of the selected object"),
    ("input", "a binding's shaped value"),
];

/// The engine of the script body `offset` is in, if it is in one.
pub fn engine_at(text: &str, offset: usize) -> Option<&str> {
    let bytes = text.as_bytes();
    let mut i = 0;
    while let Some(k) = text[i..].find('#') {
        let hash = i + k;
        if hash >= offset {
            return None;
        }
        match script_text::body_open(bytes, hash) {
            Some(open) => {
                // An unclosed body runs to the end of the text, cursor at the end included.
                let end = script_text::body_end(bytes, open).unwrap_or(bytes.len() + 1);
                if open < offset && offset < end {
                    return Some(script_text::prefix(text, hash));
                }
                i = end.min(bytes.len());
            }
            None => i = hash + 1,
        }
    }
    None
}

/// The completions at `offset` of a `engine` script whose text before it is `before`.
pub fn complete(engine: &str, before: &str) -> Vec<CompletionItem> {
    let item = |label: &str, kind, detail: &str| CompletionItem {
        label: label.to_string(),
        kind: Some(kind),
        detail: Some(detail.to_string()),
        ..CompletionItem::default()
    };
    let word = before.trim_end_matches(|c: char| c.is_ascii_alphanumeric() || c == '_');
    let rhai = engine == "rhai";
    if (!rhai && word.ends_with("mocu.")) || (rhai && word.ends_with("mocu::")) {
        return API
            .iter()
            .map(|(js, rh, doc)| item(if rhai { rh } else { js }, CompletionItemKind::METHOD, doc))
            .collect();
    }
    let mut out = vec![item("mocu", CompletionItemKind::MODULE, "the DataServer API")];
    out.extend(VARIABLES.iter().map(|(n, d)| item(n, CompletionItemKind::VARIABLE, d)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn labels(text: &str) -> Vec<String> {
        let at = text.find('|').expect("a cursor");
        let text = text.replace('|', "");
        let engine = engine_at(&text, at).expect("in a script");
        complete(engine, &text[..at]).into_iter().map(|c| c.label).collect()
    }

    #[test]
    fn in_a_script_body_completion_offers_the_api_of_its_engine_not_the_layouts_words() {
        let js = "bind keyboard { key n -> #js: { const s = \"}\"; mocu.| } }";
        assert_eq!(labels(js), ["read", "write", "subscribe", "call", "create", "after"]);
        let rhai = "bind keyboard { key n -> #rhai: { mocu::w| } }";
        assert!(labels(rhai).contains(&"call_method".to_string()));
        let start = "menu for type \"usv\" { item \"A\" -> #js: { | } }";
        assert_eq!(labels(start), ["mocu", "self", "selected", "input"]);
    }

    #[test]
    fn outside_script_bodies_and_on_colours_there_is_no_script() {
        let t = "let c = #ff0000\nbind keyboard { key n -> #js: { x() } }\nlet d = 1";
        assert_eq!(engine_at(t, t.find("#ff").unwrap() + 3), None);
        assert_eq!(engine_at(t, t.find("x()").unwrap()), Some("js"));
        assert_eq!(engine_at(t, t.find("let d").unwrap()), None);
    }
}
