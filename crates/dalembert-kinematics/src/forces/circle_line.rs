use super::{add_point_force, check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_system::ModelError;

/// Compliant contact of a circle on a body with a line of the ground (`docs/contact.md`), the
/// planar counterpart of the spatial sphere–plane element.
///
/// With the circle's centre `c`, radius `R`, the line's point `p₀` and unit normal `n` (out of the
/// ground), the penetration is `δ = R − n·(c − p₀)`, `δ̇ = −n·ċ`. Where `δ > 0` the line pushes
/// at the circle's lowest point `x = c − R n` with `F_n = max(0, k δⁿ (1 + d δ̇))` (Hunt–Crossley)
/// and `F_t = −μ F_n v_t / max(|v_t|, v_s)` (Coulomb's friction, linear below the smoothing
/// velocity `v_s`), `v_t` the body point's velocity at `x` along the line. Conservative without
/// dissipation and friction, with the potential `k δⁿ⁺¹ / (n + 1)`.
#[derive(Debug, Clone)]
pub struct CircleLine {
    /// Element name.
    pub name: String,
    /// The body carrying the circle.
    pub body: BodyRef,
    /// The circle's centre in body coordinates.
    pub centre: Vec2,
    /// Radius `R` (m).
    pub radius: f64,
    /// A point of the line (global).
    pub point: Vec2,
    /// The line's unit normal, out of the ground (global).
    pub normal: Vec2,
    /// `k` (N/mⁿ).
    pub stiffness: f64,
    /// `n` (at least 1).
    pub exponent: f64,
    /// Hunt–Crossley's `d` (s/m).
    pub dissipation: f64,
    /// Friction coefficient `μ`.
    pub friction: f64,
    /// `v_s` (m/s).
    pub smoothing_velocity: f64,
}

impl CircleLine {
    fn centre(&self, q: &[f64], qd: &[f64]) -> PointState {
        PointState::new(&BodyState::of(self.body, q, qd), self.centre)
    }

    /// The penetration `δ` at `q` (negative: the gap).
    pub fn penetration(&self, q: &[f64]) -> f64 {
        let c = self.centre(q, &[]);
        self.radius - self.normal.dot(&(c.position - self.point))
    }
}

impl ForceElement for CircleLine {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let s = BodyState::of(self.body, q, qd);
        let c = PointState::new(&s, self.centre);
        let depth = self.radius - self.normal.dot(&(c.position - self.point));
        if depth <= 0.0 {
            return;
        }
        let rate = -self.normal.dot(&c.velocity);
        let normal_force = (self.stiffness * depth.powf(self.exponent) * (1.0 + self.dissipation * rate)).max(0.0);
        // The contact point as a body point: the centre's body coordinates moved by −R n turned
        // into the body's frame.
        let (sin, cos) = s.angle.sin_cos();
        let down = -self.radius * self.normal;
        let local = self.centre + Vec2::new(cos * down.x + sin * down.y, -sin * down.x + cos * down.y);
        let x = PointState::new(&s, local);
        let mut force = normal_force * self.normal;
        if self.friction > 0.0 && normal_force > 0.0 {
            let sliding = x.velocity - self.normal.dot(&x.velocity) * self.normal;
            let speed = sliding.norm();
            force -= (self.friction * normal_force / speed.max(self.smoothing_velocity)) * sliding;
        }
        add_point_force(self.body, &x, force, q_e);
    }

    /// The elastic part's potential, counted whether or not the element dissipates (the
    /// dissipation and friction are its non-conservative work, as a damper's is).
    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        let depth = self.penetration(q);
        Some(if depth > 0.0 {
            self.stiffness * depth.powf(self.exponent + 1.0) / (self.exponent + 1.0)
        } else {
            0.0
        })
    }

    fn contact_gap(&self, _bodies: &[Body], q: &[f64]) -> Option<f64> {
        Some(-self.penetration(q))
    }

    fn is_conservative(&self) -> bool {
        self.dissipation == 0.0 && self.friction == 0.0
    }

    fn validate(&self, count: usize) -> Result<(), ModelError> {
        check_body(&self.name, self.body, count)?;
        let bad = |what: String| {
            Err(ModelError::InvalidParameter {
                element: format!("force '{}'", self.name),
                what,
            })
        };
        let finite = [
            self.centre.x,
            self.centre.y,
            self.point.x,
            self.point.y,
            self.normal.x,
            self.normal.y,
        ];
        if finite.iter().any(|x| !x.is_finite()) {
            return bad("centre, point and normal must be finite".into());
        }
        if (self.normal.norm() - 1.0).abs() > 1e-12 {
            return bad(format!(
                "the line's normal must be a unit vector, got length {}",
                self.normal.norm()
            ));
        }
        for (v, what) in [
            (self.radius, "radius"),
            (self.stiffness, "stiffness"),
            (self.smoothing_velocity, "smoothing velocity"),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{what} must be positive and finite, got {v}"));
            }
        }
        if !(self.exponent.is_finite() && self.exponent >= 1.0) {
            return bad(format!("exponent must be at least 1, got {}", self.exponent));
        }
        for (v, what) in [(self.dissipation, "dissipation"), (self.friction, "friction")] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{what} must be finite and non-negative, got {v}"));
            }
        }
        if self.body == BodyRef::Ground {
            return bad("acts on the ground: give it a moving body".into());
        }
        Ok(())
    }
}
