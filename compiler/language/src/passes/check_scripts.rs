//! Script actions (`#js: { … }`, `#rhai: { … }`): the engine its prefix names exists, and the
//! body parses in that engine's language (E0101 at the script's own line and column).
//!
//! The compiler knows no engine (it depends on nothing of the runtime): whoever embeds it
//! installs a [`ScriptChecker`] once ([`install_script_checker`]; the `mocu` binary installs
//! `mocu-script`'s registry), and the type pass calls [`check_script`] on every script action.
//! Without one, script bodies are not checked, and a checked program says so
//! ([`scripts_unchecked`]).

use crate::codes;
use crate::diagnostics::Diagnostics;
use crate::source::Span;
use std::sync::OnceLock;

/// What the compiler asks of the script engines.
pub trait ScriptChecker: Send + Sync {
    /// The prefixes known (`js`, `rhai`).
    fn engines(&self) -> Vec<String>;
    /// Parses `body` (the text between the braces) without running it: `Err` with the
    /// 1-based line and column of the syntax error within `body`, and the engine's message.
    fn check(&self, engine: &str, body: &str) -> Result<(), (u32, u32, String)>;
}

static CHECKER: OnceLock<Box<dyn ScriptChecker>> = OnceLock::new();

/// Installs the engines' checker for this process (the first one installed stays).
pub fn install_script_checker(checker: Box<dyn ScriptChecker>) {
    let _ = CHECKER.set(checker);
}

/// Whether script bodies go unchecked in this process (no checker installed).
pub fn scripts_unchecked() -> bool {
    CHECKER.get().is_none()
}

/// Checks one script action: `engine` (its span the `#name:` prefix) and `body` at `body_span`.
pub fn check_script(
    engine: &str,
    engine_span: Span,
    body: &str,
    body_span: Span,
    diags: &mut Diagnostics,
) {
    let Some(checker) = CHECKER.get() else { return };
    let known = checker.engines();
    if !known.iter().any(|k| k == engine) {
        let list: Vec<String> = known.iter().map(|k| format!("`#{k}:`")).collect();
        diags
            .error(
                codes::UNKNOWN_NAME,
                engine_span,
                format!("there is no script engine `#{engine}:`"),
            )
            .label("unknown engine")
            .suggest(engine, known.iter().map(String::as_str))
            .help
            .get_or_insert_with(|| format!("the engines are {}", list.join(" and ")));
        return;
    }
    if let Err((line, col, message)) = checker.check(engine, body) {
        let at = body_span.start + offset_of(body, line, col);
        diags
            .error(
                codes::SYNTAX,
                Span { start: at, end: at, ..body_span },
                format!("{engine} script: {message}"),
            )
            .label("here");
    }
}

/// The byte offset of a 1-based line and column (in characters) of `text`.
pub fn offset_of(text: &str, line: u32, col: u32) -> u32 {
    let line_start: usize =
        text.split_inclusive('\n').take(line.saturating_sub(1) as usize).map(str::len).sum();
    let rest = &text[line_start.min(text.len())..];
    let line_text = rest.split('\n').next().unwrap_or("");
    let within: usize =
        line_text.chars().take(col.saturating_sub(1) as usize).map(char::len_utf8).sum();
    (line_start.min(text.len()) + within) as u32
}

#[cfg(test)]
mod tests {
    use super::offset_of;

    #[test]
    fn a_line_and_column_is_found_in_the_body() {
        let t = "a\nbcd\né";
        assert_eq!(offset_of(t, 1, 1), 0);
        assert_eq!(offset_of(t, 2, 3), 4);
        assert_eq!(offset_of(t, 3, 2), 8);
        assert_eq!(offset_of(t, 9, 9), t.len() as u32);
    }
}
