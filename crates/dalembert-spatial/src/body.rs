//! Rigid bodies: mass, inertia tensor about the centre of mass in the body frame, initial pose and
//! velocity.

use crate::euler_parameters::{self, EulerParameters};
use dalembert_system::ModelError;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// A rigid body. Its coordinates are its centre of mass and the orientation of its body frame
/// (whose origin is the centre of mass).
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Name (messages and output).
    pub name: String,
    /// Mass.
    pub mass: f64,
    /// Inertia tensor about the centre of mass, in body-frame components (symmetric).
    pub inertia: Matrix3<f64>,
    /// Initial centre of mass (global).
    pub position: Vector3<f64>,
    /// Initial orientation (normalized by the model).
    pub orientation: EulerParameters,
    /// Initial velocity of the centre of mass (global).
    pub velocity: Vector3<f64>,
    /// Initial angular velocity (global components).
    pub angular_velocity: Vector3<f64>,
}

impl Body {
    /// A body at rest at the origin, not rotated, with principal moments of inertia along its
    /// frame's axes.
    pub fn new(name: &str, mass: f64, principal_inertia: [f64; 3]) -> Self {
        Body {
            name: name.to_string(),
            mass,
            inertia: Matrix3::from_diagonal(&Vector3::from(principal_inertia)),
            position: Vector3::zeros(),
            orientation: euler_parameters::IDENTITY,
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
        }
    }

    /// Sets the full inertia tensor (body frame, about the centre of mass).
    pub fn with_inertia(mut self, inertia: Matrix3<f64>) -> Self {
        self.inertia = inertia;
        self
    }

    /// Sets the initial centre of mass.
    pub fn at(mut self, position: [f64; 3]) -> Self {
        self.position = Vector3::from(position);
        self
    }

    /// Sets the initial orientation.
    pub fn oriented(mut self, orientation: EulerParameters) -> Self {
        self.orientation = orientation;
        self
    }

    /// Sets the initial velocity and angular velocity (global components).
    pub fn moving(mut self, velocity: [f64; 3], angular_velocity: [f64; 3]) -> Self {
        self.velocity = Vector3::from(velocity);
        self.angular_velocity = Vector3::from(angular_velocity);
        self
    }

    /// Places the body by a reference point other than its centre of mass: `reference` (global) is
    /// a body point and `center_of_mass` the centre of mass from it in body axes, so the centre of
    /// mass is `reference + A c` and, with the velocity set by [`Body::moving`] read as the
    /// reference point's, moves at `v + ω × A c`. Call after [`Body::oriented`] and
    /// [`Body::moving`]. The model's coordinates stay the centre of mass (`docs/spatial.md`).
    pub fn with_reference_point(mut self, reference: [f64; 3], center_of_mass: [f64; 3]) -> Self {
        let arm = euler_parameters::rotation(&euler_parameters::normalized(&self.orientation))
            * Vector3::from(center_of_mass);
        self.position = Vector3::from(reference) + arm;
        self.velocity += self.angular_velocity.cross(&arm);
        self
    }

    /// `Ok` when the data describe a physical body; otherwise an error naming it.
    pub(crate) fn validate(&self) -> Result<(), ModelError> {
        let bad = |what: String| ModelError::InvalidParameter {
            element: format!("body '{}'", self.name),
            what,
        };
        if !(self.mass.is_finite() && self.mass >= 0.0) {
            return Err(ModelError::InvalidMass {
                body: self.name.clone(),
                value: self.mass,
            });
        }
        let j = &self.inertia;
        if !j.iter().all(|x| x.is_finite()) {
            return Err(bad("inertia must be finite".into()));
        }
        let scale = j.abs().max().max(f64::MIN_POSITIVE);
        if (j - j.transpose()).abs().max() > 1e-12 * scale {
            return Err(bad("inertia tensor must be symmetric".into()));
        }
        let mut e = SymmetricEigen::new(*j).eigenvalues;
        e.as_mut_slice().sort_by(f64::total_cmp);
        if e[0] < -1e-12 * scale {
            return Err(bad(format!(
                "inertia tensor must be positive semi-definite (eigenvalue {:.3e})",
                e[0]
            )));
        }
        // A rigid body's principal moments satisfy J₁ + J₂ ≥ J₃.
        if e[0] + e[1] < e[2] * (1.0 - 1e-12) {
            return Err(bad(format!(
                "principal moments {:.6e}, {:.6e}, {:.6e} violate the triangle inequality J1 + J2 >= J3 of any rigid body",
                e[0], e[1], e[2]
            )));
        }
        let vectors = [self.position, self.velocity, self.angular_velocity];
        if !vectors.iter().all(|v| v.iter().all(|x| x.is_finite())) {
            return Err(bad("position and velocities must be finite".into()));
        }
        let n2: f64 = self.orientation.iter().map(|x| x * x).sum();
        if !(n2.is_finite() && n2 > 1e-24) {
            return Err(bad("orientation (Euler parameters) must be finite and not zero".into()));
        }
        Ok(())
    }

    /// True when the body has no mass or a singular inertia tensor.
    pub(crate) fn lacks_inertia(&self) -> bool {
        self.mass <= 0.0 || self.inertia.determinant() <= 1e-300
    }
}

/// The inertia tensor about the centre of mass from the tensor `at_point` about a body point from
/// which the centre of mass lies at `center_of_mass` (body axes): the parallel-axis theorem
/// `J_c = J_o − m (|c|² I − c cᵀ)`.
pub fn inertia_about_center(mass: f64, at_point: &Matrix3<f64>, center_of_mass: [f64; 3]) -> Matrix3<f64> {
    let c = Vector3::from(center_of_mass);
    at_point - mass * (Matrix3::identity() * c.norm_squared() - c * c.transpose())
}
