//! Reading model files written in XML (URDF, MJCF): the document, its elements' attributes as
//! numbers and vectors, and errors that name the element and its line.
//!
//! A model file is untrusted input: the document may not declare a DTD (so no entity is ever
//! expanded), its size and node count are bounded, and every value is checked as it is read.

use super::error::{line_col, SceneError};
use nalgebra::Vector3;
use roxmltree::{Document, Node, ParsingOptions};

/// The largest model file read (bytes): far above any robot description (a Panda's URDF is
/// 30 kB), far below what would exhaust memory.
pub(crate) const MAX_BYTES: usize = 16 << 20;

/// The most XML nodes a model file may hold.
const MAX_NODES: u32 = 1_000_000;

/// Parses `text` (from `origin`) as XML: one line naming the line and the cause otherwise.
pub(crate) fn parse<'a>(text: &'a str, origin: &str) -> Result<Document<'a>, SceneError> {
    if text.len() > MAX_BYTES {
        return Err(SceneError::at(
            origin,
            text,
            None,
            format!("{} bytes is more than a model file may hold ({MAX_BYTES})", text.len()),
        ));
    }
    let options = ParsingOptions {
        allow_dtd: false,
        nodes_limit: MAX_NODES,
        ..Default::default()
    };
    Document::parse_with_options(text, options).map_err(|e| {
        let p = e.pos();
        let message = match e {
            roxmltree::Error::DtdDetected => {
                "the file declares a DTD: model files may not (their entities are never expanded)".to_string()
            }
            other => format!("malformed XML: {other}"),
        };
        SceneError {
            file: origin.to_string(),
            position: Some((p.row as usize, p.col as usize)),
            message,
        }
    })
}

/// The document being read, to place errors at an element's line.
#[derive(Clone, Copy)]
pub(crate) struct Source<'a> {
    pub text: &'a str,
    pub origin: &'a str,
}

impl<'a> Source<'a> {
    /// An error at `node`'s start tag: `origin:line:column: <what>`.
    pub fn err(&self, node: Node<'_, '_>, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.origin.to_string(),
            position: Some(line_col(self.text, node.range().start)),
            message: message.into(),
        }
    }

    /// The element's `<tag name="…">` as messages name it.
    pub fn describe(node: Node<'_, '_>) -> String {
        let tag = node.tag_name().name();
        match node.attribute("name") {
            Some(n) => format!("<{tag} name=\"{n}\">"),
            None => format!("<{tag}>"),
        }
    }

    /// The required attribute `key` of `node`.
    pub fn required(&self, node: Node<'a, '_>, key: &str) -> Result<&'a str, SceneError> {
        node.attribute(key)
            .ok_or_else(|| self.err(node, format!("{} needs the attribute '{key}'", Source::describe(node))))
    }

    /// The attribute `key` as one finite number, or `default` when it is absent.
    pub fn number(&self, node: Node<'_, '_>, key: &str, default: Option<f64>) -> Result<f64, SceneError> {
        match (node.attribute(key), default) {
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.err(node, format!("{} needs the attribute '{key}'", Source::describe(node)))),
            (Some(s), _) => {
                let [x] = self.numbers::<1>(node, key, s)?;
                Ok(x)
            }
        }
    }

    /// The attribute `key` as three finite numbers separated by spaces, or `default`.
    pub fn vector(&self, node: Node<'_, '_>, key: &str, default: [f64; 3]) -> Result<Vector3<f64>, SceneError> {
        match node.attribute(key) {
            None => Ok(Vector3::from(default)),
            Some(s) => self.numbers::<3>(node, key, s).map(Vector3::from),
        }
    }

    fn numbers<const N: usize>(&self, node: Node<'_, '_>, key: &str, s: &str) -> Result<[f64; N], SceneError> {
        let bad = |finite: &str| {
            let what = if N == 1 {
                format!("a {finite}number")
            } else {
                format!("{N} {finite}numbers")
            };
            self.err(
                node,
                format!("{} {key}=\"{s}\": expected {what}", Source::describe(node)),
            )
        };
        let parts: Vec<&str> = s.split_whitespace().collect();
        if parts.len() != N {
            return Err(bad(""));
        }
        let mut out = [0.0; N];
        for (o, p) in out.iter_mut().zip(parts) {
            *o = p.parse::<f64>().map_err(|_| bad(""))?;
            if !o.is_finite() {
                return Err(bad("finite "));
            }
        }
        Ok(out)
    }

    /// Refuses any child element of `node` not in `known` (nothing is silently dropped), naming it
    /// and its line; `ignored` children are allowed and skipped.
    pub fn only(&self, node: Node<'_, '_>, known: &[&str], ignored: &[&str]) -> Result<(), SceneError> {
        for c in node.children().filter(Node::is_element) {
            let tag = c.tag_name().name();
            if !known.contains(&tag) && !ignored.contains(&tag) {
                let expected: Vec<String> = known.iter().map(|k| format!("<{k}>")).collect();
                return Err(self.err(
                    c,
                    format!(
                        "unsupported element <{tag}> in {} (expected {})",
                        Source::describe(node),
                        expected.join(", ")
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The one child element `tag` of `node`, if any (two are refused).
    pub fn child(&self, node: Node<'a, 'a>, tag: &str) -> Result<Option<Node<'a, 'a>>, SceneError> {
        let mut found = node.children().filter(|c| c.has_tag_name(tag));
        let first = found.next();
        if let Some(second) = found.next() {
            return Err(self.err(second, format!("{} has a second <{tag}>", Source::describe(node))));
        }
        Ok(first)
    }
}
