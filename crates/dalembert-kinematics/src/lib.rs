//! Planar rigid-body kinematics for dalembert.
//!
//! This crate is the bottom of the modelling layer. It holds:
//!
//! * [`Body`] — mass, moment of inertia about the centre of mass, and the (optional) local offset of
//!   the centre of mass from the body's reference point;
//! * the system coordinate layout ([`BodyId`], [`BodyRef`], [`coordinates`]): every moving body owns
//!   three consecutive entries `q = [x, y, θ]` of the system vector; the ground is not in `q`;
//! * point kinematics ([`point`]): `r = R + A u`, `ṙ = Ṙ + A_θ u θ̇`, `r̈ = R̈ + A_θ u θ̈ − A u θ̇²`;
//! * the block-diagonal mass matrix ([`MassMatrix`]) including the translation–rotation coupling and
//!   quadratic-velocity force of a reference point away from the centre of mass;
//! * applied forces mapped to generalized forces by virtual work ([`forces`]), with potential energy;
//! * time functions with exact first and second derivatives ([`TimeFunction`](dalembert_system::TimeFunction), from the seam).
//!
//! Equations follow `docs/equations.md` §1 and `docs/coordinates.md`.

pub mod body;
pub mod coordinates;
pub mod forces;
pub mod mass;
pub mod point;
pub mod rotation;
pub mod second_derivatives;

pub use body::{Body, BodyId, BodyRef};
pub use coordinates::{BodyState, Coordinates};
pub use forces::{
    CircleCircle, CircleLine, ConvexPolygon, ForceElement, Gravity, Line, PointForce, PolygonPair,
    RotationalSpringDamper, SegmentSegment, ShapeLine, SpringDamper, Torque,
};
pub use mass::MassMatrix;
pub use point::PointState;
pub use rotation::{perp, rotation, rotation_derivative};

/// Two-component vector used for planar geometry.
pub type Vec2 = nalgebra::Vector2<f64>;
