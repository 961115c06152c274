//! Kinematic trees in joint coordinates: a system described by its joints rather than by its
//! bodies' absolute coordinates, and the recursions that solve it in O(n).
//!
//! A [`KinematicTree`] lists bodies in an order where every body comes after its parent; each is
//! attached to its parent (or to the ground) by a one-degree-of-freedom joint. Body `i`'s frame
//! has its origin on the joint; at zero joint coordinate it sits at `location` in the parent's
//! frame with axes `rotation` (body axes → parent axes); a revolute joint turns it by `q` about
//! `axis` (body axes), a prismatic joint moves it by `q · axis`. The positions are the joint
//! coordinates, the velocities their rates (`n_q = n_v` = number of joints); [`JointSpace`] is the
//! seam's implementation, so every formulation and integrator runs a tree in joint coordinates.
//!
//! The equations are `docs/equations.md` §5 with the joint coordinates as the independent set: the
//! tree has no constraint equations, `M(q) q̈ = Q(t, q, q̇)`. Every formulation then reduces to that
//! one equation, which [`Articulated`] solves without forming `M` by the articulated-body
//! algorithm (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, table 7.1): the tree's O(n)
//! factorization of `M`. `M` itself (composite-rigid-body algorithm, table 6.2) and `Q`
//! (recursive Newton–Euler, table 5.1, with `q̈ = 0`) serve the methods that need them
//! (generalized-α's residual, the inspection of a model). Spatial algebra: [`algebra`].
//! `docs/joint-coordinates.md` states each equation and what was measured.

pub mod algebra;
mod articulated;
mod recursion;
mod system;

pub use articulated::Articulated;
pub use recursion::WorldFrame;
pub use system::{JointAxisLaw, JointSpace, TreeCoordinate};

use crate::ModelError;
use algebra::{Inertia, M3, V3};

/// The kind of a tree joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum JointKind {
    /// Rotation by `q` (rad) about the axis.
    Revolute,
    /// Translation by `q` (m) along the axis.
    Prismatic,
}

/// A spring–damper–actuator acting on a joint coordinate: the generalized force
/// `effort − stiffness (q − rest) − damping q̇` (N m for a revolute joint, N for a prismatic one).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointForce {
    /// Stiffness (N m/rad or N/m), ≥ 0.
    pub stiffness: f64,
    /// Damping (N m s/rad or N s/m), ≥ 0.
    pub damping: f64,
    /// Coordinate at which the spring is relaxed.
    pub rest: f64,
    /// Constant effort (torque or force).
    pub effort: f64,
}

/// One body of a tree and the joint that attaches it to its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct TreeBody {
    /// Body name (messages, output).
    pub name: String,
    /// The parent body (an index smaller than this body's), or `None` for the ground.
    pub parent: Option<usize>,
    /// Joint kind.
    pub kind: JointKind,
    /// Joint axis in the body frame (normalized by [`KinematicTree::new`]).
    pub axis: [f64; 3],
    /// The body frame's origin (on the joint) in the parent's frame at zero joint coordinate.
    pub location: [f64; 3],
    /// The body frame's axes in the parent's frame at zero joint coordinate (columns; a rotation).
    pub rotation: [[f64; 3]; 3],
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the body frame.
    pub com: [f64; 3],
    /// Inertia tensor about the centre of mass, body axes (symmetric, row by row).
    pub inertia: [[f64; 3]; 3],
    /// Force element on the joint coordinate, if any.
    pub force: Option<JointForce>,
}

/// Per body, what the recursions read (precomputed from [`TreeBody`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Link {
    pub parent: Option<usize>,
    pub kind: JointKind,
    pub axis: V3,
    pub location: V3,
    /// Transpose of the body axes at zero coordinate (parent components → body components).
    pub rotation_t: M3,
    /// `[a]× R_Tᵀ` and `[a]×² R_Tᵀ`: the joint rotation's transform is
    /// `E = R_Jᵀ R_Tᵀ = R_Tᵀ − sin q [a]× R_Tᵀ + (1 − cos q) [a]×² R_Tᵀ` (Rodrigues).
    pub rodrigues: (M3, M3),
    pub mass: f64,
    pub com: V3,
    /// Spatial inertia about the body origin.
    pub inertia: Inertia,
    pub force: Option<JointForce>,
}

/// A kinematic tree in joint coordinates, with gravity. See the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicTree {
    gravity: V3,
    bodies: Vec<TreeBody>,
    pub(crate) links: Vec<Link>,
}

impl KinematicTree {
    /// Checks the bodies (errors name the body and what is wrong) and makes the tree.
    pub fn new(gravity: [f64; 3], bodies: Vec<TreeBody>) -> Result<Self, ModelError> {
        let bad = |body: &TreeBody, what: String| ModelError::InvalidParameter {
            element: format!("body '{}'", body.name),
            what,
        };
        if !gravity.iter().all(|g| g.is_finite()) {
            return Err(ModelError::InvalidParameter {
                element: "gravity".into(),
                what: "must be finite".into(),
            });
        }
        let mut links = Vec::with_capacity(bodies.len());
        for (i, b) in bodies.iter().enumerate() {
            if let Some(p) = b.parent {
                if p >= i {
                    return Err(bad(b, format!("parent #{p} must come before the body (#{i})")));
                }
            }
            if !(b.mass.is_finite() && b.mass >= 0.0) {
                return Err(ModelError::InvalidMass {
                    body: b.name.clone(),
                    value: b.mass,
                });
            }
            let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
            let inertia = M3::from_fn(|r, c| b.inertia[r][c]);
            if !finite(inertia.as_slice()) || (inertia - inertia.transpose()).amax() > 1e-12 * inertia.amax() {
                return Err(bad(b, "inertia tensor must be finite and symmetric".into()));
            }
            let mut moments: Vec<f64> = inertia.symmetric_eigenvalues().iter().copied().collect();
            moments.sort_by(f64::total_cmp);
            let tol = 1e-12 * inertia.amax();
            if moments[0] < -tol {
                return Err(bad(b, "inertia tensor must be positive semi-definite".into()));
            }
            if moments[0] + moments[1] < moments[2] - tol {
                return Err(bad(
                    b,
                    format!(
                        "principal moments {:e}, {:e}, {:e} violate the triangle inequality J1 + J2 >= J3 of any rigid body",
                        moments[0], moments[1], moments[2]
                    ),
                ));
            }
            let axis = V3::from(b.axis);
            if !finite(&b.axis) || axis.norm() < 1e-12 {
                return Err(bad(b, "joint axis must be a finite non-zero vector".into()));
            }
            let rotation = M3::from_fn(|r, c| b.rotation[r][c]);
            let orthonormal = (rotation.transpose() * rotation - M3::identity()).amax() < 1e-9;
            if !finite(rotation.as_slice()) || !orthonormal || rotation.determinant() < 0.0 {
                return Err(bad(b, "rotation must be a proper rotation matrix".into()));
            }
            if !finite(&b.location) || !finite(&b.com) {
                return Err(bad(b, "location and centre of mass must be finite".into()));
            }
            if let Some(f) = &b.force {
                let ok = finite(&[f.stiffness, f.damping, f.rest, f.effort]) && f.stiffness >= 0.0 && f.damping >= 0.0;
                if !ok {
                    return Err(bad(
                        b,
                        "joint force: stiffness and damping finite and ≥ 0, rest and effort finite".into(),
                    ));
                }
            }
            let com = V3::from(b.com);
            let (axis, rotation_t) = (axis.normalize(), rotation.transpose());
            let ax = axis.cross_matrix();
            links.push(Link {
                rodrigues: (ax * rotation_t, ax * ax * rotation_t),
                parent: b.parent,
                kind: b.kind,
                axis,
                location: V3::from(b.location),
                rotation_t,
                mass: b.mass,
                com,
                inertia: Inertia::rigid(b.mass, &com, &inertia),
                force: b.force,
            });
        }
        Ok(KinematicTree {
            gravity: V3::from(gravity),
            bodies,
            links,
        })
    }

    /// The bodies as given.
    pub fn bodies(&self) -> &[TreeBody] {
        &self.bodies
    }

    /// Number of joints (= bodies = coordinates).
    pub fn len(&self) -> usize {
        self.links.len()
    }

    /// True when the tree has no body.
    pub fn is_empty(&self) -> bool {
        self.links.is_empty()
    }

    /// Gravitational acceleration (global).
    pub fn gravity(&self) -> [f64; 3] {
        self.gravity.into()
    }

    /// The generalized force of joint `i`'s force element at `(q, q̇)` (0 without one).
    #[inline]
    pub(crate) fn joint_force(&self, i: usize, q: f64, qd: f64) -> f64 {
        self.links[i]
            .force
            .map_or(0.0, |f| f.effort - f.stiffness * (q - f.rest) - f.damping * qd)
    }

    /// The power of the joint dampers at the joint rates `qd`: `−Σ c q̇²`.
    pub fn damping_power(&self, qd: &[f64]) -> f64 {
        self.links
            .iter()
            .zip(qd)
            .map(|(l, &w)| l.force.map_or(0.0, |f| -f.damping * w * w))
            .sum()
    }

    /// True when every joint force is conservative (no damping).
    pub fn is_conservative(&self) -> bool {
        self.links.iter().all(|l| l.force.is_none_or(|f| f.damping == 0.0))
    }
}
