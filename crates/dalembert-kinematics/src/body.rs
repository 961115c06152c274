//! Rigid bodies and references to them.

use crate::Vec2;
use dalembert_system::ModelError;

/// Index of a moving body in the system (the ground has none).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BodyId(pub usize);

impl BodyId {
    /// Index of this body's `x` coordinate in the system vector `q` (its `y` and `θ` follow).
    #[inline]
    pub fn offset(self) -> usize {
        3 * self.0
    }
}

/// A body as seen by a joint or force: either the fixed ground frame or a moving body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BodyRef {
    /// The fixed global frame. Its pose is identity and its velocity zero.
    Ground,
    /// A moving body of the system.
    Body(BodyId),
}

impl BodyRef {
    /// The moving body, or `None` for the ground.
    #[inline]
    pub fn id(self) -> Option<BodyId> {
        match self {
            BodyRef::Ground => None,
            BodyRef::Body(b) => Some(b),
        }
    }
}

impl From<BodyId> for BodyRef {
    fn from(b: BodyId) -> Self {
        BodyRef::Body(b)
    }
}

/// A planar rigid body.
///
/// Its coordinates `[x, y, θ]` locate its *reference point* and orient its frame. By default the
/// reference point is the centre of mass; [`Body::with_center_of_mass`] moves the centre of mass to
/// a local offset `c`, and the mass matrix then gains the coupling of `docs/equations.md` §1.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Name used in error messages and output columns.
    pub name: String,
    /// Mass in kg (zero allowed: a massless body, where the formulation can handle it).
    pub mass: f64,
    /// Moment of inertia about the centre of mass, kg·m² (zero allowed: a point mass).
    pub inertia: f64,
    /// Local position of the centre of mass relative to the reference point (body frame).
    pub center_of_mass: Vec2,
}

impl Body {
    /// A body whose reference point is its centre of mass.
    ///
    /// Errors if the mass or inertia is negative or not finite.
    pub fn new(name: impl Into<String>, mass: f64, inertia: f64) -> Result<Self, ModelError> {
        let name = name.into();
        if !(mass.is_finite() && mass >= 0.0) {
            return Err(ModelError::InvalidMass {
                body: name,
                value: mass,
            });
        }
        if !(inertia.is_finite() && inertia >= 0.0) {
            return Err(ModelError::InvalidInertia {
                body: name,
                value: inertia,
            });
        }
        Ok(Body {
            name,
            mass,
            inertia,
            center_of_mass: Vec2::zeros(),
        })
    }

    /// A uniform slender rod of length `length`: inertia `m L² / 12` about its centre.
    pub fn rod(name: impl Into<String>, mass: f64, length: f64) -> Result<Self, ModelError> {
        Body::new(name, mass, mass * length * length / 12.0)
    }

    /// Moves the centre of mass to local offset `c` from the reference point.
    pub fn with_center_of_mass(mut self, c: Vec2) -> Result<Self, ModelError> {
        if !(c.x.is_finite() && c.y.is_finite()) {
            return Err(ModelError::InvalidParameter {
                element: format!("body '{}'", self.name),
                what: "centre-of-mass offset must be finite".into(),
            });
        }
        self.center_of_mass = c;
        Ok(self)
    }

    /// Moment of inertia about the reference point, `J_cm + m |c|²`.
    #[inline]
    pub fn inertia_about_reference(&self) -> f64 {
        self.inertia + self.mass * self.center_of_mass.norm_squared()
    }
}
