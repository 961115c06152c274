//! Spatial rigid bodies for dalembert: an implementation of the system seam
//! ([`dalembert_system::MultibodySystem`]) that every formulation and integrator runs unchanged.
//!
//! - Coordinates ([`frame`]): per body the centre of mass and Euler parameters (7 positions), the
//!   centre-of-mass velocity and the body-frame angular velocity (6 velocities); constant block
//!   diagonal mass; orientation advanced by the quaternion exponential and normalized after each
//!   explicit step ([`euler_parameters`]). The choice and its measured drift: `docs/spatial.md`.
//! - Joints ([`joints`]): spherical, revolute, universal, cylindrical, prismatic, fixed, distance,
//!   point on line, point in plane, parallel, perpendicular, from four primitives.
//! - Drivers ([`Driver`]): joint angle, joint displacement, body coordinate, following a
//!   [`dalembert_system::TimeFunction`].
//! - Forces ([`Force`]): gravity, point forces, torques, spring–dampers.
//!
//! ```
//! use dalembert_spatial::{Body, BodyRef, Joint, ModelBuilder};
//! use dalembert_system::{ConstraintSet, MultibodySystem};
//!
//! // A spherical pendulum: a 1 kg bob 1 m below a ball joint at the origin.
//! let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
//! let bob = b.body(dalembert_spatial::Body::new("bob", 1.0, [1e-3; 3]).at([0.0, 0.0, -1.0]));
//! b.joint(Joint::spherical("ball", BodyRef::Ground, bob, [0.0, 0.0, 0.0]));
//! let model = b.build().unwrap();
//! assert_eq!((model.layout().n_q(), model.layout().n_v(), ConstraintSet::num_equations(&model)), (7, 6, 3));
//! let (q, _) = model.initial_state();
//! let mut values = model.values();
//! model.evaluate(0.0, &q, &[], &mut values);
//! assert!(values.c.iter().all(|c| c.abs() < 1e-15));
//! ```

pub mod body;
pub mod contact_friction;
pub mod couplings;
pub mod drivers;
pub mod euler_parameters;
pub mod forces;
pub mod frame;
pub mod friction;
pub mod geometry;
pub mod joint_coordinates;
pub mod joint_values;
pub mod joints;
pub mod limits;
pub mod model;
pub mod reactions;

pub use body::Body;
pub use couplings::Coupling;
pub use drivers::{Driver, DriverTarget};
pub use forces::Force;
pub use joint_coordinates::JointCoordinates;
pub use joint_values::JointValueKind;
pub use joints::{Joint, JointKind};
pub use model::{Model, ModelBuilder};
pub use reactions::Reaction;

/// A body of the model, or the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BodyRef {
    /// The fixed global frame.
    Ground,
    /// The moving body at this index (as returned by [`ModelBuilder::body`]).
    Body(usize),
}
