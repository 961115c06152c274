use super::{add_point_force, check_body, ForceElement};
use crate::{Body, BodyRef, BodyState, PointState, Vec2};
use dalembert_system::{ContactLaw, ContactResultant, ModelError};

/// Compliant contact of a circle on a body with a line of the ground or of another body
/// (`docs/contact.md`), the planar counterpart of the spatial sphere–plane element.
///
/// With the circle's centre `c`, radius `R`, the line's point `p₀` and unit normal `n` (out of the
/// line's body), the penetration is `δ = R − n·(c − p₀)` and its rate `δ̇ = −n·(ċ − v)`, `v` the
/// velocity of the line's body's point at `c`. Where `δ > 0` the line pushes at the circle's
/// lowest point `x = c − R n` with [`ContactLaw`]'s normal force (Hunt–Crossley) and friction
/// (Coulomb's, linear below the smoothing velocity) on the two bodies' points' relative velocity
/// at `x` along the line, and the line's body feels the opposite force at `x`. Conservative
/// without dissipation and friction, with the potential `k δⁿ⁺¹ / (n + 1)`: the force at `x` is
/// its gradient on both bodies (`docs/contact.md`, "A line on a moving body").
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
    /// The line: its body, a point and its unit normal in that body's coordinates.
    pub line: Line,
    /// The contact law.
    pub law: ContactLaw,
}

/// A line fixed in a body (the ground's: global coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// The body the line is fixed in.
    pub body: BodyRef,
    /// A point of the line, in the body's coordinates.
    pub point: Vec2,
    /// The line's unit normal, out of the body, in the body's coordinates.
    pub normal: Vec2,
}

impl Line {
    /// A line of the ground through `point` with unit `normal` (global).
    pub fn ground(point: Vec2, normal: Vec2) -> Line {
        Line {
            body: BodyRef::Ground,
            point,
            normal,
        }
    }

    /// Its point and unit normal, global, with its body in state `s`.
    fn placed(&self, s: &BodyState) -> (Vec2, Vec2) {
        (PointState::new(s, self.point).position, s.rotation() * self.normal)
    }

    /// `Err` naming the element when its numbers are not finite, its normal not a unit vector,
    /// or its body is `body` or out of range (`count` bodies).
    pub(super) fn check(&self, name: &str, body: BodyRef, count: usize) -> Result<(), ModelError> {
        let bad = |what: String| {
            Err(ModelError::InvalidParameter {
                element: format!("force '{name}'"),
                what,
            })
        };
        let v = [self.point.x, self.point.y, self.normal.x, self.normal.y];
        if v.iter().any(|x| !x.is_finite()) {
            return bad("the line's point and normal must be finite".into());
        }
        if (self.normal.norm() - 1.0).abs() > 1e-12 {
            return bad(format!(
                "the line's normal must be a unit vector, got length {}",
                self.normal.norm()
            ));
        }
        if self.body == body {
            return bad(match body {
                BodyRef::Ground => "acts on the ground: give it a moving body".into(),
                BodyRef::Body(_) => {
                    "the line is on the body the shape is on: give it another body or the ground".into()
                }
            });
        }
        check_body(name, self.body, count)
    }
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
        let (s, l) = (BodyState::of(self.body, q, &[]), BodyState::of(self.line.body, q, &[]));
        press(
            (self.body, &s),
            (self.centre, self.radius),
            (&self.line, &l),
            &self.law,
            None,
            None,
        )
    }
}

/// A circle of radius `radius` centred at `centre` (body coordinates) of `body` in state `s`
/// against `line` with its body in state `ls`: its penetration, and where it penetrates its
/// contact force's generalized forces on both bodies added to `q_e` and its force (on `body`),
/// normal force and point to `resultant` (the law of [`CircleLine`]). The one computation of
/// every circle, segment and polygon element on a line.
pub(super) fn press(
    (body, s): (BodyRef, &BodyState),
    (centre, radius): (Vec2, f64),
    (line, ls): (&Line, &BodyState),
    law: &ContactLaw,
    q_e: Option<&mut [f64]>,
    resultant: Option<&mut ContactResultant<2>>,
) -> f64 {
    let c = PointState::new(s, centre);
    let (point, normal) = line.placed(ls);
    let depth = radius - normal.dot(&(c.position - point));
    if depth > 0.0 && (q_e.is_some() || resultant.is_some()) {
        let under = point_at(ls, c.position);
        let normal_force = law.normal_force(depth, -normal.dot(&(c.velocity - under.velocity)));
        let lowest = c.position - radius * normal;
        let (x, x_line) = (point_at(s, lowest), point_at(ls, lowest));
        let force = contact_force(law, normal_force, normal, x.velocity - x_line.velocity);
        if let Some(q_e) = q_e {
            add_point_force(body, &x, force, q_e);
            add_point_force(line.body, &x_line, -force, q_e);
        }
        if let Some(r) = resultant {
            r.add(force.into(), normal_force, x.position.into());
        }
    }
    depth
}

impl ForceElement for CircleLine {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body, self.line.body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let (s, l) = (BodyState::of(self.body, q, qd), BodyState::of(self.line.body, q, qd));
        press(
            (self.body, &s),
            (self.centre, self.radius),
            (&self.line, &l),
            &self.law,
            Some(q_e),
            None,
        );
    }

    fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
        let (s, l) = (BodyState::of(self.body, q, qd), BodyState::of(self.line.body, q, qd));
        let mut out = ContactResultant::new(0.0);
        out.gap = -press(
            (self.body, &s),
            (self.centre, self.radius),
            (&self.line, &l),
            &self.law,
            None,
            Some(&mut out),
        );
        let lowest = PointState::new(&s, self.centre).position - self.radius * (l.rotation() * self.line.normal);
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
        if !(self.centre.x.is_finite() && self.centre.y.is_finite()) {
            return Err(ModelError::InvalidParameter {
                element: format!("force '{}'", self.name),
                what: "the circle's centre must be finite".into(),
            });
        }
        self.line.check(&self.name, self.body, count)?;
        check(&self.name, &[self.radius], &self.law)
    }
}
