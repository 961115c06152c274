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
