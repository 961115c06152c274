//! Applied forces as generalized forces (`docs/equations.md` §1).
//!
//! By virtual work, a global force `F` at local point `u` of body `i` contributes
//! `Q_i = [F_x, F_y, (A_θ u)·F]` and a torque `T` contributes `[0, 0, T]`. Each element adds its
//! contribution to the system vector `Q_e` and reports its potential energy where it has one.
//!
//! Users add their own forces by implementing [`ForceElement`].

mod circle_line;
mod gravity;
mod point_force;
mod polygon_pair;
mod rotational_spring_damper;
mod shape_line;
mod spring_damper;
mod swept_pair;
mod torque;

pub use circle_line::{CircleLine, Line};
pub use gravity::Gravity;
pub use point_force::PointForce;
pub use polygon_pair::{ConvexPolygon, PolygonPair};
pub use rotational_spring_damper::RotationalSpringDamper;
pub use shape_line::ShapeLine;
pub use spring_damper::SpringDamper;
pub use swept_pair::{CircleCircle, SegmentSegment};
pub use torque::Torque;

use crate::{Body, BodyRef, PointState, Vec2};
use dalembert_system::TangentValues;

/// An applied force element.
///
/// Implementations must not allocate in [`ForceElement::add_generalized_force`]: it runs inside the
/// stepping loop.
pub trait ForceElement: Send + Sync + std::fmt::Debug {
    /// Name used in messages and output.
    fn name(&self) -> &str;

    /// Adds this element's generalized force at `(t, q, q̇)` to `q_e` (length `3 × bodies`).
    fn add_generalized_force(&self, t: f64, bodies: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]);

    /// Potential energy at `(t, q)`, or `None` for a non-conservative element.
    fn potential_energy(&self, _t: f64, _bodies: &[Body], _q: &[f64]) -> Option<f64> {
        None
    }

    /// True when the element does no work beyond its potential: `T + V` is then conserved by the
    /// exact motion (gravity, springs without damping or actuator). Default `false`.
    fn is_conservative(&self) -> bool {
        false
    }

    /// A contact element's gap at `q` (positive apart, negative in contact): the event function
    /// the integration loop ends a step at where it changes sign. `None` (the default) for an
    /// element that is not a contact; an element answers `Some` or `None` whatever `q`.
    fn contact_gap(&self, _bodies: &[Body], _q: &[f64]) -> Option<f64> {
        None
    }

    /// A compliant contact's resultant at `(q, q̇)` (its gap, normal force, force on its body and
    /// centre of pressure: [`dalembert_system::ContactResultant`], the output columns of
    /// `docs/contact.md`, "Output"). `None` (the default) for an element that is not a contact.
    fn contact_resultant(
        &self,
        _bodies: &[Body],
        _q: &[f64],
        _qd: &[f64],
    ) -> Option<dalembert_system::ContactResultant<2>> {
        None
    }

    /// Checks that every body the element refers to exists in a model of `bodies` moving bodies.
    fn validate(&self, _bodies: usize) -> Result<(), dalembert_system::ModelError> {
        Ok(())
    }

    /// The bodies whose coordinates the element reads or whose generalized forces it writes.
    /// Implicit integrators take the sparsity of their iteration matrix from it; `None` (the
    /// default, for elements that do not say) couples every body with every other, which is right
    /// but makes the iteration matrix dense.
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        None
    }

    /// Adds this element's part of the analytic tangent of the dynamic residual
    /// `r = M q̈ + C_qᵀ λ − Q`: `−∂Q/∂q` and `−∂Q/∂q̇` (coordinate `3 i + c` of body `i`, `c` in
    /// `x, y, θ`). Returns `false` when the element has no analytic derivatives (the default, as
    /// for a user-written force): implicit integrators then difference the residual.
    fn add_tangent(&self, _t: f64, _bodies: &[Body], _q: &[f64], _qd: &[f64], _out: &mut TangentValues<'_>) -> bool {
        false
    }
}

/// Adds the generalized force of global force `f` applied at point `p` of `body` to `q_e`.
/// A point on the ground receives nothing.
#[inline]
pub fn add_point_force(body: BodyRef, p: &PointState, f: Vec2, q_e: &mut [f64]) {
    if let BodyRef::Body(id) = body {
        let k = id.offset();
        q_e[k] += f.x;
        q_e[k + 1] += f.y;
        q_e[k + 2] += p.d_theta().dot(&f);
    }
}

/// Adds torque `tau` on `body` to `q_e` (nothing for the ground).
#[inline]
pub fn add_torque(body: BodyRef, tau: f64, q_e: &mut [f64]) {
    if let BodyRef::Body(id) = body {
        q_e[id.offset() + 2] += tau;
    }
}

/// Checks a body reference against the number of moving bodies.
pub fn check_body(element: &str, body: BodyRef, count: usize) -> Result<(), dalembert_system::ModelError> {
    match body {
        BodyRef::Body(id) if id.0 >= count => Err(dalembert_system::ModelError::UnknownBody {
            element: element.to_string(),
            index: id.0,
            count,
        }),
        _ => Ok(()),
    }
}
