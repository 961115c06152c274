//! The system seam of dalembert: how formulations and integrators see a multibody system.
//!
//! * [`Layout`]: per-body blocks of the positions `q` (`n_q`) and velocities `v` (`n_v`);
//! * [`BlockDiagonal`]: the mass matrix, one square block per body, of any size;
//! * [`ConstraintSet`]: constraints as a fixed sparsity pattern of `C_q` plus values, and the
//!   analyses written once on it (structure, kinematic analysis, coordinate partitioning);
//! * [`MultibodySystem`]: mass, forces, constraints, position update and energy;
//! * [`TimeFunction`]: prescribed functions of time (drivers, time-varying forces) of any model,
//!   and named [`inputs`] a run sets between steps;
//! * [`tree`]: kinematic trees in joint coordinates ([`JointSpace`]) and the articulated-body
//!   algorithm that solves them in O(n);
//! * [`Formulation`]: the forward-dynamics interface every formulation implements and every
//!   integrator consumes, with its errors ([`DynamicsError`]) and settings.
//!
//! Nothing here knows whether a body is planar or spatial: `dalembert-constraints` implements the
//! seam for planar bodies, `dalembert-spatial` for spatial ones. Equations follow `docs/equations.md`; `docs/architecture.md` shows where
//! each part lives.

pub mod axis_law;
pub mod blocks;
pub mod constraint_set;
pub mod contact_law;
pub mod data;
pub mod error;
pub mod evaluated_at;
pub mod finite;
pub mod formulation;
pub mod friction;
pub mod frictional;
pub mod gram;
pub mod inputs;
pub mod inverse;
pub mod jacobian_svd;
pub mod kinematics;
pub mod layout;
pub mod limit;
pub mod linalg;
pub mod minimum_norm;
pub mod model_error;
pub mod number;
pub mod partition;
pub mod power;
pub mod residual_tangent;
pub mod segment_distance;
pub mod sparse_pattern;
pub mod structure;
pub mod system;
pub mod tangent;
pub mod time_function;
pub mod tree;

pub use axis_law::AxisLaw;
pub use blocks::BlockDiagonal;
pub use constraint_set::{ConstraintPattern, ConstraintSet, ConstraintValues, Segment};
pub use contact_law::{ContactLaw, ContactResultant};
pub use data::{Data, Stage};
pub use error::{ConstraintError, EquationRef};
pub use evaluated_at::EvaluatedAt;
pub use finite::all_finite;
pub use formulation::{
    Baumgarte, DynamicsError, Energy, Formulation, FormulationEntry, FormulationSettings, FormulationStats,
    RedundancyTreatment,
};
pub use friction::{solve_friction, FrictionTerms, FrictionWork, JointFriction, Mode, SlipRow};
pub use frictional::Frictional;
pub use kinematics::{KinematicOptions, KinematicReport};
pub use layout::{BodyBlock, Layout};
pub use limit::{JointLimit, LIMIT_SLACK, REST_SPEED};
pub use model_error::ModelError;
pub use number::Shortest;
pub use partition::{Partition, PartitionTracker, Repartition, VelocityTransform};
pub use power::{PowerProbe, PowerScratch};
pub use residual_tangent::{ResidualTangent, TangentAt};
pub use structure::StructureReport;
pub use system::MultibodySystem;
pub use tangent::{TangentPattern, TangentValues};
pub use time_function::TimeFunction;
pub use tree::{JointSpace, KinematicTree};
