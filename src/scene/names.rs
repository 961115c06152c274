//! Names in a scene file, planar or spatial: the bodies (with the implicit `"ground"`) and every
//! element's span, for the one-line errors that name an unknown body or a name used twice.

use super::error::SceneError;
use std::collections::HashMap;
use std::ops::Range;

/// The file's name and text, for errors placed at a span, and the named inputs the scene's
/// functions declare (`{ input = "NAME" }`), in the order first met.
#[derive(Clone, Copy)]
pub(crate) struct Ctx<'a> {
    pub file: &'a str,
    pub text: &'a str,
    pub inputs: &'a std::cell::RefCell<Vec<String>>,
    /// The force elements of type `code`, in the file's order.
    pub code_forces: &'a std::cell::RefCell<Vec<String>>,
}

impl Ctx<'_> {
    pub fn err(&self, span: Option<Range<usize>>, msg: impl Into<String>) -> SceneError {
        SceneError::at(self.file, self.text, span, msg)
    }

    /// Registers code force `name`; its index among the scene's code forces.
    pub fn code_force(&self, name: &str) -> usize {
        let mut names = self.code_forces.borrow_mut();
        names.push(name.to_string());
        names.len() - 1
    }

    /// The scene's code forces, in the file's order.
    pub fn code_force_names(&self) -> Vec<String> {
        self.code_forces.borrow().clone()
    }

    /// The scene's named inputs, in the order first met.
    pub fn input_names(&self) -> Vec<String> {
        self.inputs.borrow().clone()
    }
}

/// Body names to references of type `B` (a planar or a spatial body reference) and element names
/// to their spans.
pub(crate) struct Names<B> {
    bodies: HashMap<String, B>,
    spans: HashMap<String, Range<usize>>,
}

impl<B: Copy> Names<B> {
    /// Only the ground, as `ground`.
    pub fn new(ground: B) -> Self {
        Names {
            bodies: HashMap::from([("ground".to_string(), ground)]),
            spans: HashMap::new(),
        }
    }

    /// Registers body `name` as `b` (its uniqueness checked by [`Names::unique`] first).
    pub fn add_body(&mut self, name: &str, b: B) {
        self.bodies.insert(name.to_string(), b);
    }

    /// The body called `name`, or the error naming `owner` and the bodies that exist.
    pub fn body(&self, ctx: &Ctx<'_>, name: &str, span: &Range<usize>, owner: &str) -> Result<B, SceneError> {
        self.bodies.get(name).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.bodies.keys().map(String::as_str).collect();
            known.sort_unstable();
            ctx.err(
                Some(span.clone()),
                format!("{owner}: unknown body '{name}' (bodies: {})", known.join(", ")),
            )
        })
    }

    /// Records element `name` (a `what`: body, joint, driver, force) at `span`: an error when the
    /// name is taken, or is `ground` for a body.
    pub fn unique(&mut self, ctx: &Ctx<'_>, name: &str, span: &Range<usize>, what: &str) -> Result<(), SceneError> {
        if name == "ground" && what == "body" {
            return Err(ctx.err(
                Some(span.clone()),
                "body 'ground': the name is reserved for the fixed frame",
            ));
        }
        if self.spans.insert(name.to_string(), span.clone()).is_some() {
            return Err(ctx.err(Some(span.clone()), format!("{what} '{name}': the name is used twice")));
        }
        Ok(())
    }

    /// The span of element `name`.
    pub fn span(&self, name: &str) -> Option<Range<usize>> {
        self.spans.get(name).cloned()
    }
}
