//! Joints, drivers and their assembly for dalembert (`docs/equations.md` §2 and §7).
//!
//! A constraint touches at most two bodies and writes, per equation `k`:
//!
//! * the residual `C_k(q, t)`,
//! * its Jacobian blocks on the two bodies (`∂C_k/∂[x, y, θ]` of each),
//! * `C_t` (the partial time derivative, non-zero for drivers), and
//! * `Q_d`, the right-hand side of the acceleration equation `C_q q̈ = Q_d`
//!   (`Q_d = −(C_q q̇)_q q̇ − 2 C_qt q̇ − C_tt`, quadratic in the velocities).
//!
//! [`ConstraintSystem`] stacks them into the system vectors and a sparse `C_q` whose pattern is fixed
//! at construction; [`structure`](dalembert_system::structure) finds the number of degrees of freedom and redundant equations from
//! the rank of `C_q`; [`kinematics`](dalembert_system::kinematics) does position, velocity and acceleration analysis.
//!
//! Sign convention for reactions (stated once, in `docs/sign-conventions.md`): the generalized
//! constraint force is `Q_c = −C_qᵀ λ`; a joint's reported reaction is the force (and torque, about
//! the joint's reaction point) that its **second** body exerts on its **first**. A driver's effort is
//! `−λ`, the generalized force the driver applies along the quantity it drives.

pub mod constraint;
pub mod contact_friction;
pub mod drivers;
pub mod friction;
pub mod joints;
pub mod limit;
pub mod model;
pub mod primitives;
pub mod profile;
pub mod profile_contact;
pub mod reactions;
pub mod rigid_contact;
pub mod system;

pub use constraint::{Constraint, ConstraintEval, ConstraintRole, MAX_EQUATIONS};
pub use drivers::{BodyCoordinate, Coordinate, DistanceDriver, JointAngle, JointDisplacement};
pub use friction::{Friction, FrictionJoint, STICK_SPEED};
pub use joints::{Distance, Gear, PointOnLine, Prismatic, RackPinion, Revolute, Rigid};
pub use limit::Limit;
pub use model::Model;
pub use profile::Profile;
pub use profile_contact::ProfileContact;
pub use reactions::Reaction;
pub use rigid_contact::{Against, RigidContact};
pub use system::ConstraintSystem;
