//! Errors raised while building a model.

use thiserror::Error;

/// A model element was given invalid data. Every variant names the element at fault.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// A body's mass is negative or not finite.
    #[error("body '{body}': mass must be finite and non-negative, got {value}")]
    InvalidMass {
        /// Body name.
        body: String,
        /// Offending value.
        value: f64,
    },
    /// A body's moment of inertia is negative or not finite.
    #[error("body '{body}': moment of inertia must be finite and non-negative, got {value}")]
    InvalidInertia {
        /// Body name.
        body: String,
        /// Offending value.
        value: f64,
    },
    /// A geometric or physical parameter is not finite or out of its range.
    #[error("{element}: {what}")]
    InvalidParameter {
        /// The element (body, joint, force, driver) at fault, by name.
        element: String,
        /// What is wrong.
        what: String,
    },
    /// An element refers to a body index that does not exist.
    #[error("{element}: refers to body #{index}, but the model has {count} moving bodies")]
    UnknownBody {
        /// Element name.
        element: String,
        /// Body index referred to.
        index: usize,
        /// Number of moving bodies.
        count: usize,
    },
}
