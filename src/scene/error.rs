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
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.position {
            Some((l, c)) => write!(f, "{}:{l}:{c}: {}", self.file, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
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
