//! Compliant contact with a cam profile (`docs/contact.md`, "Cams"): a roller (a circle) or a
//! flat face on one body pressed against a closed profile ([`Profile`]) on another, with the law
//! of every compliant contact ([`ContactLaw`]: Hunt–Crossley's normal force, Coulomb's friction
//! linear below the smoothing velocity).
//!
//! - A roller of radius `R` centred at `c`: with `x = S(u*)` the profile's point closest to `c`
//!   and `n` the profile's outward unit normal there, the signed distance of the centre from the
//!   profile is `n·(c − x)` and the penetration `δ = R − n·(c − x)`.
//! - A flat face through `p` with unit normal `n` (towards the profile): with `x = S(u*)` the
//!   profile's support point against `n` (the first point the face meets), `δ = −n·(x − p)`.
//!
//! In both `u*` makes the distance least, so its motion along the profile changes `δ` by nothing
//! to first order (the envelope theorem): `δ̇ = −n·(ẋ_c − ẋ)` for the roller and `−n·(ẋ − v_f(x))`
//! for the face, with `ẋ` the velocity of the profile's material point at `u*`, and the force
//! `F_n n` (on the roller's body; `−F_n n` on the face's) is the gradient of `k δⁿ⁺¹ / (n + 1)`:
//! conservative without dissipation and friction. It acts at the middle of the overlap, on the
//! line through the closest points, so where along `n` does not change its moment.

use crate::profile::Profile;
use crate::rigid_contact::{check_shapes, Against};
use dalembert_kinematics::forces::{add_point_force, check_body};
use dalembert_kinematics::rotation::perp;
use dalembert_kinematics::{Body, BodyRef, BodyState, ForceElement, PointState, Vec2};
use dalembert_system::{ContactLaw, ContactResultant, ModelError};

/// A roller or a flat face on `body` in compliant contact with a profile on another body.
#[derive(Debug, Clone)]
pub struct ProfileContact {
    /// The contact's name.
    pub name: String,
    /// The body carrying the roller or the face.
    pub body: BodyRef,
    /// The roller's centre, or a point of the face, local to the body.
    pub centre: Vec2,
    /// The roller's radius (m; not read for a face).
    pub radius: f64,
    /// A face's unit normal, local to the body, towards the profile (`None`: a roller).
    pub face: Option<Vec2>,
    /// The body carrying the profile.
    pub profile_body: BodyRef,
    /// The profile, local to its body.
    pub profile: Profile,
    /// The law.
    pub law: ContactLaw,
}

/// Where the profile is pressed: the penetration `δ`, the unit normal `n` (along which the
/// profile pushes the roller, against which it pushes the face), the middle of the overlap
/// (global), and `δ̇` when velocities were given.
struct Press {
    depth: f64,
    normal: Vec2,
    point: Vec2,
    rate: f64,
}

/// The profile's outward unit normal at tangent `t` (local), for a profile running
/// counter-clockwise when `ccw`.
fn outward(t: Vec2, ccw: bool) -> Vec2 {
    let n = -perp(t) / t.norm();
    if ccw {
        n
    } else {
        -n
    }
}

impl ProfileContact {
    /// The contact's geometry at `(q, v)` (`v` empty: no rate), and the states of the contact's
    /// body and the profile's.
    fn press(&self, q: &[f64], v: &[f64]) -> (Press, [BodyState; 2]) {
        let profile = &self.profile;
        let own = BodyState::of(self.body, q, v);
        let other = BodyState::of(self.profile_body, q, v);
        let ccw = profile.twice_area() > 0.0;
        let to_local = |x: Vec2| other.rotation().transpose() * (x - other.position);
        let press = match self.face {
            Some(normal) => {
                let n = own.rotation() * normal;
                let [point, _, _] = profile.at(profile.support(other.rotation().transpose() * n));
                let x = PointState::new(&other, point);
                let p = PointState::new(&own, self.centre);
                let depth = -n.dot(&(x.position - p.position));
                let rate = if v.is_empty() {
                    0.0
                } else {
                    let face = PointState::new(&own, own_local(&own, x.position));
                    -n.dot(&(x.velocity - face.velocity))
                };
                Press {
                    depth,
                    normal: n,
                    point: x.position + 0.5 * depth * n,
                    rate,
                }
            }
            None => {
                let c = PointState::new(&own, self.centre);
                let [point, tangent, _] = profile.at(profile.closest(to_local(c.position)));
                let x = PointState::new(&other, point);
                let n = other.rotation() * outward(tangent, ccw);
                let depth = self.radius - n.dot(&(c.position - x.position));
                let rate = if v.is_empty() {
                    0.0
                } else {
                    -n.dot(&(c.velocity - x.velocity))
                };
                Press {
                    depth,
                    normal: n,
                    point: c.position - (self.radius - 0.5 * depth) * n,
                    rate,
                }
            }
        };
        (press, [own, other])
    }

    /// The force on the contact's body (on the profile's: its opposite), the normal force and
    /// the point where they act as each body's point, or `None` apart, where `press` found the
    /// geometry with the bodies in `states`.
    fn load(&self, press: &Press, [own, other]: &[BodyState; 2]) -> Option<(Vec2, f64, [PointState; 2])> {
        if press.depth <= 0.0 {
            return None;
        }
        let x_own = PointState::new(own, own_local(own, press.point));
        let x_other = PointState::new(other, own_local(other, press.point));
        // The direction the profile pushes the contact's body: out of it for a roller, back
        // from it for a face.
        let n = if self.face.is_some() {
            -press.normal
        } else {
            press.normal
        };
        let normal_force = self.law.normal_force(press.depth, press.rate);
        let slip = x_own.velocity - x_other.velocity;
        let sliding = slip - n.dot(&slip) * n;
        let force = normal_force * n - self.law.friction_factor(normal_force, sliding.norm()) * sliding;
        Some((force, normal_force, [x_own, x_other]))
    }
}

/// The point at global `x` in the coordinates of the body in state `s`.
fn own_local(s: &BodyState, x: Vec2) -> Vec2 {
    s.rotation().transpose() * (x - s.position)
}

impl ForceElement for ProfileContact {
    fn bodies(&self) -> Option<Vec<BodyRef>> {
        Some(vec![self.body, self.profile_body])
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn add_generalized_force(&self, _t: f64, _b: &[Body], q: &[f64], qd: &[f64], q_e: &mut [f64]) {
        let (press, states) = self.press(q, qd);
        if let Some((force, _, [x_own, x_other])) = self.load(&press, &states) {
            add_point_force(self.body, &x_own, force, q_e);
            add_point_force(self.profile_body, &x_other, -force, q_e);
        }
    }

    fn contact_resultant(&self, _b: &[Body], q: &[f64], qd: &[f64]) -> Option<ContactResultant<2>> {
        let (press, states) = self.press(q, qd);
        let mut out = ContactResultant::new(-press.depth);
        if let Some((force, normal_force, [x_own, _])) = self.load(&press, &states) {
            out.add(force.into(), normal_force, x_own.position.into());
        }
        Some(out.finish(press.point.into()))
    }

    /// The elastic part's potential where the two overlap.
    fn potential_energy(&self, _t: f64, _b: &[Body], q: &[f64]) -> Option<f64> {
        Some(self.law.potential(self.press(q, &[]).0.depth))
    }

    fn contact_gap(&self, _bodies: &[Body], q: &[f64]) -> Option<f64> {
        Some(-self.press(q, &[]).0.depth)
    }

    fn is_conservative(&self) -> bool {
        self.law.is_conservative()
    }

    fn validate(&self, count: usize) -> Result<(), ModelError> {
        check_body(&self.name, self.body, count)?;
        check_body(&self.name, self.profile_body, count)?;
        let (body, profile) = (self.profile_body, self.profile.clone());
        let against = match self.face {
            Some(normal) => Against::ProfileFace { body, profile, normal },
            None => Against::Profile { body, profile },
        };
        check_shapes(&self.name, self.body, self.radius, &against)?;
        self.law.check().map_err(|what| ModelError::InvalidParameter {
            element: format!("force '{}'", self.name),
            what,
        })
    }
}
