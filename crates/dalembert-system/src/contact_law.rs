//! The law of compliant contact, shared by the planar and spatial contact elements
//! (`docs/contact.md`, K1 and K2): a Hunt–Crossley normal force and Coulomb friction regularized
//! below a smoothing velocity.

/// Stiffness, exponent, dissipation, friction and smoothing velocity of a contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaw {
    /// `k` (N/mⁿ).
    pub stiffness: f64,
    /// `n` (1.5 for Hertz's spheres; at least 1).
    pub exponent: f64,
    /// Hunt–Crossley's `d` (s/m).
    pub dissipation: f64,
    /// Friction coefficient `μ`.
    pub friction: f64,
    /// `v_s` (m/s): below it the friction grows linearly with the sliding speed.
    pub smoothing_velocity: f64,
}

impl ContactLaw {
    /// `Err(what)` naming the first parameter out of its range.
    pub fn check(&self) -> Result<(), String> {
        for (v, what) in [
            (self.stiffness, "stiffness"),
            (self.smoothing_velocity, "smoothing velocity"),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{what} must be positive and finite, got {v}"));
            }
        }
        if !(self.exponent.is_finite() && self.exponent >= 1.0) {
            return Err(format!("exponent must be at least 1, got {}", self.exponent));
        }
        for (v, what) in [(self.dissipation, "dissipation"), (self.friction, "friction")] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{what} must be finite and non-negative, got {v}"));
            }
        }
        Ok(())
    }

    /// (K1): `max(0, k δⁿ (1 + d δ̇))` at penetration `depth > 0` growing at `rate`.
    pub fn normal_force(&self, depth: f64, rate: f64) -> f64 {
        (self.stiffness * depth.powf(self.exponent) * (1.0 + self.dissipation * rate)).max(0.0)
    }

    /// (K2) as a factor: the friction force is `−factor · v_t` for the sliding velocity `v_t` of
    /// speed `speed`, so that it is `μ F_n` against the sliding above `v_s` and linear below.
    pub fn friction_factor(&self, normal_force: f64, speed: f64) -> f64 {
        if self.friction == 0.0 || normal_force == 0.0 {
            return 0.0;
        }
        self.friction * normal_force / speed.max(self.smoothing_velocity)
    }

    /// The elastic potential `k δⁿ⁺¹ / (n + 1)` where `depth > 0`, 0 elsewhere.
    pub fn potential(&self, depth: f64) -> f64 {
        if depth <= 0.0 {
            return 0.0;
        }
        self.stiffness * depth.powf(self.exponent + 1.0) / (self.exponent + 1.0)
    }

    /// True without dissipation and friction: the contact then only stores energy.
    pub fn is_conservative(&self) -> bool {
        self.dissipation == 0.0 && self.friction == 0.0
    }
}

/// A compliant contact's resultant at a state, in `D` dimensions, as the output columns give it
/// (`<name>.gap`, `.normal`, the force's and the point's components; `docs/contact.md`,
/// "Output"): built by [`ContactResultant::add`] at each point in contact, then
/// [`ContactResultant::finish`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactResultant<const D: usize> {
    /// The gap (m): positive apart, minus the deepest penetration in contact.
    pub gap: f64,
    /// The sum of the normal forces (N, never negative).
    pub normal: f64,
    /// The contact force on the element's body (a plane or line contact's `body`, a two-sphere
    /// or two-circle contact's second body), global components (N): normal forces and friction.
    pub force: [f64; D],
    /// Where it acts (global): the centre of pressure of the points in contact, `Σ F_n,k x_k /
    /// Σ F_n,k`, or the nearest point out of contact.
    pub point: [f64; D],
}

impl<const D: usize> Default for ContactResultant<D> {
    fn default() -> Self {
        ContactResultant {
            gap: 0.0,
            normal: 0.0,
            force: [0.0; D],
            point: [0.0; D],
        }
    }
}

impl<const D: usize> ContactResultant<D> {
    /// None yet, with the gap `gap`.
    pub fn new(gap: f64) -> Self {
        ContactResultant {
            gap,
            ..Default::default()
        }
    }

    /// Adds a point in contact at `x` with the force `force` on the body, of which `normal` is
    /// the normal force (the point summed weighted by it until [`ContactResultant::finish`]).
    pub fn add(&mut self, force: [f64; D], normal: f64, x: [f64; D]) {
        self.normal += normal;
        for k in 0..D {
            self.force[k] += force[k];
            self.point[k] += normal * x[k];
        }
    }

    /// The centre of pressure from the weighted sum, or `nearest` where no normal force acts.
    pub fn finish(mut self, nearest: [f64; D]) -> Self {
        self.point = if self.normal > 0.0 {
            self.point.map(|p| p / self.normal)
        } else {
            nearest
        };
        self
    }
}
