//! Scene errors: one line naming the file, the place and the cause.

use std::fmt;
use std::path::Path;

/// An error in a scene file.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The file (or origin) name.
    pub file: String,
    /// 1-based line and column, when known.
    pub position: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    /// One line: control characters of names echoed from the file are escaped (`\n`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (file, message) = (one_line(&self.file), one_line(&self.message));
        match self.position {
            Some((l, c)) => write!(f, "{file}:{l}:{c}: {message}"),
            None => write!(f, "{file}: {message}"),
        }
    }
}

/// `s` with line breaks, tabs and other control characters escaped, so that a message quoting
/// user text stays on one line.
pub fn one_line(s: &str) -> std::borrow::Cow<'_, str> {
    if !s.chars().any(char::is_control) {
        return std::borrow::Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for ch in s.chars() {
        match ch {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&c.escape_unicode().to_string()),
            c => out.push(c),
        }
    }
    std::borrow::Cow::Owned(out)
}

impl std::error::Error for SceneError {}

/// 1-based line and column of byte offset `at` in `text`.
pub(crate) fn line_col(text: &str, at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let before = &text[..at];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |s| s.chars().count()) + 1;
    (line, col)
}

impl SceneError {
    pub(crate) fn io(path: &Path, e: std::io::Error) -> Self {
        SceneError {
            file: path.display().to_string(),
            position: None,
            message: format!("cannot read: {e}"),
        }
    }

    pub(crate) fn parse(file: &str, text: &str, e: &toml::de::Error) -> Self {
        SceneError {
            file: file.to_string(),
            position: e.span().map(|s| line_col(text, s.start)),
            message: e.message().trim().to_string(),
        }
    }

    pub(crate) fn at(file: &str, text: &str, span: Option<std::ops::Range<usize>>, message: impl Into<String>) -> Self {
        SceneError {
            file: file.to_string(),
            position: span.map(|s| line_col(text, s.start)),
            message: message.into(),
        }
    }
}
