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

/// Compliant contact of two circles on two bodies (either may be the ground), with the law of
/// [`CircleLine`]: they overlap by `δ = Rᵢ + Rⱼ − |cⱼ − cᵢ|` along `n = (cⱼ − cᵢ) / |cⱼ − cᵢ|`,
/// `δ̇ = −n·(ċⱼ − ċᵢ)`; the normal force pushes `j` along `n` and `i` against it at the middle of
/// the overlap, and friction acts on the bodies' relative sliding there.
#[derive(Debug, Clone)]
pub struct CircleCircle {
    /// Element name.
    pub name: String,
    /// The two bodies.
    pub bodies: (BodyRef, BodyRef),
    /// The circles' centres in their bodies' coordinates.
    pub centres: (Vec2, Vec2),
    /// Radii `Rᵢ`, `Rⱼ` (m).
    pub radii: (f64, f64),
    /// The contact law.
    pub law: ContactLaw,
}

/// The body point at global `x` of the body in state `s`.
fn point_at(s: &BodyState, x: Vec2) -> PointState {
    let d = x - s.position;
    PointState::new(s, Vec2::new(s.cos * d.x + s.sin * d.y, -s.sin * d.x + s.cos * d.y))
}

/// The contact force at a point where the normal force is `normal_force` along `n` and the
/// bodies slide at `slip` (the second's point relative to the first's).
fn contact_force(law: &ContactLaw, normal_force: f64, n: Vec2, slip: Vec2) -> Vec2 {
    let sliding = slip - n.dot(&slip) * n;
    normal_force * n - law.friction_factor(normal_force, sliding.norm()) * sliding
}

/// `Err` naming the element when a radius or the law is out of range.
fn check(name: &str, radii: &[f64], law: &ContactLaw) -> Result<(), ModelError> {
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

impl CircleCircle {
    /// The centres' states and the overlap `δ` at `(q, q̇)`.
    fn geometry(&self, q: &[f64], qd: &[f64]) -> (PointState, PointState, f64) {
        let ci = PointState::new(&BodyState::of(self.bodies.0, q, qd), self.centres.0);
        let cj = PointState::new(&BodyState::of(self.bodies.1, q, qd), self.centres.1);
        let depth = self.radii.0 + self.radii.1 - (cj.position - ci.position).norm();
        (ci, cj, depth)
    }
}

impl CircleCircle {
    /// The contact force on the second body (on the first: its opposite), the normal force and
    /// the middle of the overlap as each body's point, or `None` apart (or concentric: no
    /// direction to push along).
    fn load(&self, q: &[f64], qd: &[f64]) -> Option<(Vec2, f64, [PointState; 2])> {
        let (ci, cj, depth) = self.geometry(q, qd);
        let d = cj.position - ci.position;
        let length = d.norm();
        if depth <= 0.0 || length == 0.0 {
            return None;
        }
        let n = d / length;
        let normal_force = self.law.normal_force(depth, -n.dot(&(cj.velocity - ci.velocity)));
        let x = ci.position + (self.radii.0 - 0.5 * depth) * n;
        let (si, sj) = (BodyState::of(self.bodies.0, q, qd), BodyState::of(self.bodies.1, q, qd));
        let (xi, xj) = (point_at(&si, x), point_at(&sj, x));
        let force = contact_force(&self.law, normal_force, n, xj.velocity - xi.velocity);
        Some((force, normal_force, [xi, xj]))
    }
}

impl ForceElement for CircleCircle {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.bodies.0, self.bodies.1])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        if let Some((force, _, [xi, xj])) = self.load(q, qd) {
            add_point_force(self.bodies.1, &xj, force, q_e);
            add_point_force(self.bodies.0, &xi, -force, q_e);
        }
    }

    fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
        let (ci, cj, depth) = self.geometry(q, qd);
        let d = cj.position - ci.position;
        let n = if d.norm() > 0.0 { d / d.norm() } else { Vec2::zeros() };
        let mut out = ContactResultant::new(-depth);
        if let Some((force, normal_force, [_, xj])) = self.load(q, qd) {
            out.add(force.into(), normal_force, xj.position.into());
        }
        Some(out.finish((ci.position + (self.radii.0 - 0.5 * depth) * n).into()))
    }

    /// The elastic part's potential where the circles overlap.
    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        Some(self.law.potential(self.geometry(q, &[]).2))
    }

    fn contact_gap(&self, _bodies: &[Body], q: &[f64]) -> Option<f64> {
        Some(-self.geometry(q, &[]).2)
    }

    fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }

    fn validate(&self, count: usize) -> Result<(), ModelError> {
        check_body(&self.name, self.bodies.0, count)?;
        check_body(&self.name, self.bodies.1, count)?;
        if self.bodies.0 == self.bodies.1 {
            return Err(ModelError::InvalidParameter {
                element: format!("force '{}'", self.name),
                what: "must be between two different bodies".into(),
            });
        }
        check(&self.name, &[self.radii.0, self.radii.1], &self.law)
    }
}
