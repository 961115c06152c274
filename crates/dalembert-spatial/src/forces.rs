//! Applied forces on spatial bodies, as generalized forces on `(ṙ, ω')`: a force `F` at body
//! point `s = A s'` contributes `F` and `Aᵀ(s × F)`, a torque `T` contributes `Aᵀ T` (Nikravesh
//! §6.5). Gravity and the gyroscopic term `−ω' × J'ω'` are added by the model.

use crate::frame::{Frame, NV};
use crate::BodyRef;
use dalembert_system::ModelError;
use nalgebra::Vector3;

type V3 = Vector3<f64>;

/// A force element, placed in the initial configuration (global components).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Force {
    /// A constant global force at a body point.
    PointForce {
        /// Name.
        name: String,
        /// The body.
        body: BodyRef,
        /// Point of application in the initial configuration (global).
        point: [f64; 3],
        /// Force (global, constant).
        force: [f64; 3],
    },
    /// A constant global torque on a body.
    Torque {
        /// Name.
        name: String,
        /// The body.
        body: BodyRef,
        /// Torque (global, constant).
        torque: [f64; 3],
    },
    /// A translational spring–damper between two points: tension `k (ℓ − ℓ₀) + c ℓ̇`.
    SpringDamper {
        /// Name.
        name: String,
        /// First body and its point in the initial configuration (global).
        body_i: BodyRef,
        /// Point on the first body.
        point_i: [f64; 3],
        /// Second body.
        body_j: BodyRef,
        /// Point on the second body.
        point_j: [f64; 3],
        /// Stiffness `k`.
        stiffness: f64,
        /// Damping `c`.
        damping: f64,
        /// Free length `ℓ₀`.
        free_length: f64,
    },
}

impl Force {
    /// The element's name.
    pub fn name(&self) -> &str {
        match self {
            Force::PointForce { name, .. } | Force::Torque { name, .. } | Force::SpringDamper { name, .. } => name,
        }
    }
}

/// A force element in body-frame terms.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum ForceData {
    PointForce {
        body: usize,
        point: V3,
        force: V3,
    },
    Torque {
        body: usize,
        torque: V3,
    },
    SpringDamper {
        ends: [(Option<usize>, V3); 2],
        stiffness: f64,
        damping: f64,
        free_length: f64,
    },
}

/// Adds the generalized force of global force `f` at global arm `s` on body `b`.
#[inline]
pub(crate) fn add_point_force(out: &mut [f64], b: usize, frame: &Frame, s: &V3, f: &V3) {
    let o = NV * b;
    let n = frame.a.transpose() * s.cross(f);
    for k in 0..3 {
        out[o + k] += f[k];
        out[o + 3 + k] += n[k];
    }
}

impl ForceData {
    /// Converts `force` with the bodies' initial frames (`index` maps a body to its index,
    /// `frame` to its initial frame).
    pub fn new(
        force: &Force,
        index: &dyn Fn(BodyRef) -> Result<Option<usize>, ModelError>,
        frame: &dyn Fn(Option<usize>) -> Frame,
    ) -> Result<Self, ModelError> {
        let bad = |what: &str| ModelError::InvalidParameter {
            element: format!("force '{}'", force.name()),
            what: what.to_string(),
        };
        let moving = |b: BodyRef| index(b)?.ok_or_else(|| bad("acts on the ground: give it a moving body"));
        let local = |b: Option<usize>, p: &[f64; 3]| {
            let f = frame(b);
            f.a.transpose() * (V3::from(*p) - f.r)
        };
        let finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
        Ok(match force {
            Force::PointForce {
                body, point, force: f, ..
            } => {
                if !finite(point) || !finite(f) {
                    return Err(bad("point and force must be finite"));
                }
                let b = moving(*body)?;
                ForceData::PointForce {
                    body: b,
                    point: local(Some(b), point),
                    force: V3::from(*f),
                }
            }
            Force::Torque { body, torque, .. } => {
                if !finite(torque) {
                    return Err(bad("torque must be finite"));
                }
                ForceData::Torque {
                    body: moving(*body)?,
                    torque: V3::from(*torque),
                }
            }
            Force::SpringDamper {
                body_i,
                point_i,
                body_j,
                point_j,
                stiffness,
                damping,
                free_length,
                ..
            } => {
                if !finite(point_i) || !finite(point_j) {
                    return Err(bad("points must be finite"));
                }
                for (v, what) in [
                    (stiffness, "stiffness"),
                    (damping, "damping"),
                    (free_length, "free length"),
                ] {
                    if !(v.is_finite() && *v >= 0.0) {
                        return Err(bad(&format!("{what} must be finite and non-negative, got {v}")));
                    }
                }
                let (bi, bj) = (index(*body_i)?, index(*body_j)?);
                if bi == bj {
                    return Err(bad("must connect two different bodies"));
                }
                ForceData::SpringDamper {
                    ends: [(bi, local(bi, point_i)), (bj, local(bj, point_j))],
                    stiffness: *stiffness,
                    damping: *damping,
                    free_length: *free_length,
                }
            }
        })
    }

    /// Adds the element's generalized force at the state behind `frame`.
    pub fn add(&self, frame: &dyn Fn(Option<usize>) -> Frame, out: &mut [f64]) {
        match self {
            ForceData::PointForce { body, point, force } => {
                let f = frame(Some(*body));
                add_point_force(out, *body, &f, &f.global(point), force);
            }
            ForceData::Torque { body, torque } => {
                let f = frame(Some(*body));
                let n = f.a.transpose() * torque;
                for k in 0..3 {
                    out[NV * body + 3 + k] += n[k];
                }
            }
            ForceData::SpringDamper {
                ends,
                stiffness,
                damping,
                free_length,
            } => {
                let (fi, fj) = (frame(ends[0].0), frame(ends[1].0));
                let (si, sj) = (fi.global(&ends[0].1), fj.global(&ends[1].1));
                let d = fj.r + sj - fi.r - si;
                let length = d.norm();
                if length == 0.0 {
                    // Coincident ends: the line of action is undefined, and the element exerts
                    // no force there (exact for a free length of zero).
                    return;
                }
                let u = d / length;
                let rate = u.dot(&(fj.point_velocity(&sj) - fi.point_velocity(&si)));
                let tension = stiffness * (length - free_length) + damping * rate;
                if let Some(b) = ends[0].0 {
                    add_point_force(out, b, &fi, &si, &(tension * u));
                }
                if let Some(b) = ends[1].0 {
                    add_point_force(out, b, &fj, &sj, &(-tension * u));
                }
            }
        }
    }

    /// Potential energy of a conservative element (zero for the others).
    pub fn potential(&self, frame: &dyn Fn(Option<usize>) -> Frame) -> f64 {
        match self {
            ForceData::SpringDamper {
                ends,
                stiffness,
                free_length,
                ..
            } => {
                let (fi, fj) = (frame(ends[0].0), frame(ends[1].0));
                let d = fj.point(&ends[1].1) - fi.point(&ends[0].1);
                0.5 * stiffness * (d.norm() - free_length).powi(2)
            }
            _ => 0.0,
        }
    }

    /// True when the element is conservative with its potential counted by [`ForceData::potential`].
    pub fn is_conservative(&self) -> bool {
        matches!(self, ForceData::SpringDamper { damping, .. } if *damping == 0.0)
    }
}
