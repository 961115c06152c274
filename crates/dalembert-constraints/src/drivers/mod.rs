//! Drivers: rheonomic constraints `s(q) − f(t) = 0` that prescribe one quantity as a function of time.
//!
//! With this form, `C_t = −f'(t)` and `Q_d` gains `f''(t)`. The driver's **effort** is `−λ`: the
//! generalized force it applies along `s` (a force for a displacement or a coordinate `x`, `y`; a
//! torque for an angle, applied to the second body with its reaction on the first).

mod body_coordinate;
mod distance;
mod joint_angle;
mod joint_displacement;

pub use body_coordinate::{BodyCoordinate, Coordinate};
pub use distance::DistanceDriver;
pub use joint_angle::JointAngle;
pub use joint_displacement::JointDisplacement;
