//! Reference mechanisms and their independently derived solutions, shared by the tests and
//! benchmarks of every dalembert crate. Not published; nothing here is part of the library's API.
//!
//! Every builder returns a [`Mechanism`]: the model and a consistent initial state.

pub mod anchors;
pub mod chain_scene;
pub mod closed_form;
pub mod fuzz;
pub mod generator;
pub mod jet;
pub mod mechanisms;
pub mod n_four_bar;
pub mod spatial;

pub use mechanisms::Mechanism;
