//! Where a script's text is, and what went wrong in it: every error names the file, line and
//! column of the script inside its layout or module file.

use std::fmt;
use std::sync::Arc;

/// A place in a file, 1-based.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub file: Arc<str>,
    pub line: u32,
    pub col: u32,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.col)
    }
}

/// A script's text and where its first character stands in its file: a whole file starts
/// at 1:1, the body of `on press #rhai: { … }` where its `{` is followed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Source {
    pub text: Arc<str>,
    pub origin: Location,
}

impl Source {
    /// A whole file.
    pub fn file(path: &str, text: &str) -> Source {
        Source { text: text.into(), origin: Location { file: path.into(), line: 1, col: 1 } }
    }

    /// A script embedded in another file, its first character at `line`:`col` there.
    pub fn embedded(path: &str, line: u32, col: u32, text: &str) -> Source {
        Source { text: text.into(), origin: Location { file: path.into(), line, col } }
    }

    /// The file position of `line`:`col` (1-based) of the script's own text. Positions the
    /// engine does not know (0) are taken as the script's start.
    pub fn locate(&self, line: u32, col: u32) -> Location {
        let o = &self.origin;
        let (line, col) = match (line, col) {
            (0, _) => (o.line, o.col),
            (1, c) => (o.line, o.col + c.max(1) - 1),
            (l, c) => (o.line + l - 1, c.max(1)),
        };
        Location { file: o.file.clone(), line, col }
    }
}

/// What kind of failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The text does not parse (`mocu check` reports these).
    Syntax,
    /// An exception or error raised while running.
    Runtime,
    /// Past its operation budget: the script is stopped.
    Runaway,
    /// Past its memory limit: the script is stopped.
    Memory,
}

impl ErrorKind {
    pub fn describe(self) -> &'static str {
        match self {
            ErrorKind::Syntax => "syntax error",
            ErrorKind::Runtime => "error",
            ErrorKind::Runaway => "stopped: over its operation budget",
            ErrorKind::Memory => "stopped: over its memory limit",
        }
    }

    /// Whether the script is stopped after it (its subscriptions and timers end).
    pub fn stops(self) -> bool {
        matches!(self, ErrorKind::Runaway | ErrorKind::Memory)
    }
}

/// A script's error, at its place in the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScriptError {
    pub kind: ErrorKind,
    pub at: Location,
    pub message: String,
}

impl fmt::Display for ScriptError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: script {}: {}", self.at, self.kind.describe(), self.message)
    }
}

impl std::error::Error for ScriptError {}

/// Why a DataServer operation asked by a script was refused (the script sees it as an
/// exception at the call).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ApiError {
    /// The path text is malformed.
    BadPath { path: String, reason: String },
    /// No object at the path now.
    NoObject { path: String },
    /// The DataServer refused (a type mismatch, a duplicate name, …).
    Refused { path: String, reason: String },
    /// The script was stopped; it can do nothing more.
    Stopped,
}

impl fmt::Display for ApiError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ApiError::BadPath { path, reason } => write!(f, "bad path `{path}`: {reason}"),
            ApiError::NoObject { path } => write!(f, "no object at `{path}`"),
            ApiError::Refused { path, reason } => write!(f, "`{path}`: {reason}"),
            ApiError::Stopped => f.write_str("the script was stopped"),
        }
    }
}

impl std::error::Error for ApiError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_embedded_scripts_first_line_is_offset_by_its_column_and_later_lines_only_by_line() {
        let s = Source::embedded("a.mocu", 10, 20, "x");
        assert_eq!(s.locate(1, 3).to_string(), "a.mocu:10:22");
        assert_eq!(s.locate(3, 5).to_string(), "a.mocu:12:5");
        assert_eq!(s.locate(0, 0).to_string(), "a.mocu:10:20");
    }
}
