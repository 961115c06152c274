use super::{add_point_force, check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_system::{ContactLaw, ContactResultant, ModelError};

/// Compliant contact of a circle on a body with a line of the ground (`docs/contact.md`), the
/// planar counterpart of the spatial sphere–plane element.
///
/// With the circle's centre `c`, radius `R`, the line's point `p₀` and unit normal `n` (out of the
/// ground), the penetration is `δ = R − n·(c − p₀)`, `δ̇ = −n·ċ`. Where `δ > 0` the line pushes
/// at the circle's lowest point `x = c − R n` with [`ContactLaw`]'s normal force (Hunt–Crossley)
/// and friction (Coulomb's, linear below the smoothing velocity) on the body point's velocity at
/// `x` along the line. Conservative without dissipation and friction, with the potential
/// `k δⁿ⁺¹ / (n + 1)`.
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
    /// The contact law.
    pub law: ContactLaw,
}

/// The body point at global `x` of the body in state `s`.
pub(super) fn point_at(s: &BodyState, x: Vec2) -> PointState {
    let d = x - s.position;
    PointState::new(s, Vec2::new(s.cos * d.x + s.sin * d.y, -s.sin * d.x + s.cos * d.y))
}

/// The contact force at a point where the normal force is `normal_force` along `n` and the
/// bodies slide at `slip` (the second's point relative to the first's).
pub(super) fn contact_force(law: &ContactLaw, normal_force: f64, n: Vec2, slip: Vec2) -> Vec2 {
    let sliding = slip - n.dot(&slip) * n;
    normal_force * n - law.friction_factor(normal_force, sliding.norm()) * sliding
}

/// `Err` naming the element when a radius or the law is out of range.
pub(super) fn check(name: &str, radii: &[f64], law: &ContactLaw) -> Result<(), ModelError> {
    let bad = |what: String| ModelError::InvalidParameter {
        element: format!("force '{name}'"),
        what,
    };
    if let Some(r) = radii.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
        return Err(bad(format!("radius must be positive and finite, got {r}")));
    }
    law.check().map_err(bad)
}

impl CircleLine {
    /// The penetration `δ` at `q` (negative: the gap).
    pub fn penetration(&self, q: &[f64]) -> f64 {
        let c = PointState::new(&BodyState::of(self.body, q, &[]), self.centre);
        self.radius - self.normal.dot(&(c.position - self.point))
    }
}

/// A circle of radius `radius` centred at `centre` (body coordinates) of `body` in state `s`
/// against the ground's line through `point` with unit `normal`: its penetration, and where it
/// penetrates its contact force's generalized force added to `q_e` and its force, normal force
/// and point to `resultant` (the law of [`CircleLine`]). The one computation of every circle,
/// segment and polygon element on a line.
pub(super) fn press(
    (body, s): (BodyRef, &BodyState),
    (centre, radius): (Vec2, f64),
    (point, normal): (Vec2, Vec2),
    law: &ContactLaw,
    q_e: Option<&mut [f64]>,
    resultant: Option<&mut ContactResultant<2>>,
) -> f64 {
    let c = PointState::new(s, centre);
    let depth = radius - normal.dot(&(c.position - point));
    if depth > 0.0 && (q_e.is_some() || resultant.is_some()) {
        let normal_force = law.normal_force(depth, -normal.dot(&c.velocity));
        let x = point_at(s, c.position - radius * normal);
        let force = contact_force(law, normal_force, normal, x.velocity);
        if let Some(q_e) = q_e {
            add_point_force(body, &x, force, q_e);
        }
        if let Some(r) = resultant {
            r.add(force.into(), normal_force, x.position.into());
        }
    }
    depth
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
        press(
            (self.body, &s),
            (self.centre, self.radius),
            (self.point, self.normal),
            &self.law,
            Some(q_e),
            None,
        );
    }

    fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
        let s = BodyState::of(self.body, q, qd);
        let mut out = ContactResultant::new(-self.penetration(q));
        press(
            (self.body, &s),
            (self.centre, self.radius),
            (self.point, self.normal),
            &self.law,
            None,
            Some(&mut out),
        );
        let lowest = PointState::new(&s, self.centre).position - self.radius * self.normal;
        Some(out.finish(lowest.into()))
    }

    /// The elastic part's potential, counted whether or not the element dissipates (the
    /// dissipation and friction are its non-conservative work, as a damper's is).
    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        Some(self.law.potential(self.penetration(q)))
    }

    fn contact_gap(&self, _bodies: &[Body], q: &[f64]) -> Option<f64> {
        Some(-self.penetration(q))
    }

    fn is_conservative(&self) -> bool {
        self.law.is_conservative()
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
        if self.body == BodyRef::Ground {
            return bad("acts on the ground: give it a moving body".into());
        }
        check(&self.name, &[self.radius], &self.law)
    }
}
