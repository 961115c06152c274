//! The friction cones of [`Frictional`]: a spatial rigid contact's friction is two elements, the
//! two tangent rows of its contact, bounded together by `|F_t| ≤ μ N` and slipping against the
//! slip velocity's direction in the tangent plane (`docs/limits.md`, "Friction in spatial rigid
//! contact"). Each element of a cone is an element of [`crate::friction`] whose slip direction
//! is the component along its row of the unit slip direction; this module keeps the two modes
//! together.

use super::Frictional;
use crate::friction::{Mode, SLIP_END};

/// The modes of a cone's two elements at the slip velocity `w` (its two rates): stuck within
/// the stick speed, otherwise slipping along `w`.
pub(super) fn modes_at(w: (f64, f64), stick_speed: f64) -> (Mode, Mode) {
    let size = w.0.hypot(w.1);
    if size <= stick_speed {
        (Mode::Stick, Mode::Stick)
    } else {
        (Mode::Slip(w.0 / size), Mode::Slip(w.1 / size))
    }
}

/// A cone's event function in the modes of its two elements at the slip velocity `w`: positive
/// while the modes hold. Stuck: `w_s − |w|` (the slip leaves the stick speed); slipping with the
/// reference direction `d`: `d·w + 10⁻³ w_s`, the scalar slip's [`Mode::event`] along `d`. It
/// changes sign where the slip stops (its velocity passes zero along `d`, at a thousandth of the
/// stick speed, which the impulse at the event takes back) or where it has turned by a right
/// angle from `d` (then `d` turns with it, [`Frictional::at_event`]).
pub(super) fn event(modes: (Mode, Mode), w: (f64, f64), stick_speed: f64) -> f64 {
    match modes {
        (Mode::Stick, _) => stick_speed - w.0.hypot(w.1),
        (Mode::Slip(a), Mode::Slip(b)) => a * w.0 + b * w.1 + SLIP_END * stick_speed,
        _ => 1.0,
    }
}

/// The direction a slipping cone's force opposes at the slip velocity `w`, with its reference
/// direction `d`: `u = (w + 2 ε d) / |w + 2 ε d|` until its event (`d·w ≥ −ε`, `ε = 10⁻³ w_s`
/// the event's margin), `d` past it. It is the slip velocity's direction to within `2 ε / |w|`
/// (a part in 10⁹ at 1 m/s with a contact's stick speed of 10⁻⁶ m/s, and none at all while the
/// slip runs along `d`); where the slip runs into its stop along `d` it is `d` from
/// `|w| ≤ ε` on, through the event and past it, so a step over the stop sees one smooth law, as
/// a scalar slip's fixed direction: the step's end is past the event, which the driver then
/// locates. Without the shift the force would turn at `w = 0`, before the event, and hold the
/// slip there; without `d` past the event, a fixed step over it would end anywhere.
pub(super) fn slip_direction(d: (f64, f64), w: (f64, f64), stick_speed: f64) -> (f64, f64) {
    let margin = SLIP_END * stick_speed;
    if d.0 * w.0 + d.1 * w.1 + margin < 0.0 {
        return d;
    }
    let shift = 2.0 * margin;
    let u = (w.0 + shift * d.0, w.1 + shift * d.1);
    let size = u.0.hypot(u.1);
    if size > 0.0 && size.is_finite() {
        (u.0 / size, u.1 / size)
    } else {
        d
    }
}

impl Frictional {
    /// The other element of friction element `k`'s cone, if it is one's.
    pub(super) fn cone_of(&self, k: usize) -> Option<usize> {
        self.inner.system().frictions().get(k).and_then(|f| f.cone)
    }

    /// The first elements of the cones, with their partners.
    pub(super) fn cones(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.frictions).filter_map(move |k| self.cone_of(k).filter(|&p| p > k).map(|p| (k, p)))
    }

    /// The slip velocity of the cone `(k, p)` at `v`, from its rows as last filled.
    pub(super) fn cone_rate(&self, (k, p): (usize, usize), v: &[f64]) -> (f64, f64) {
        (self.terms[k].row.dot(v), self.terms[p].row.dot(v))
    }

    /// Sets both elements of cone `(k, p)` to the modes of the slip velocity `w`.
    pub(super) fn set_cone(&mut self, (k, p): (usize, usize), w: (f64, f64)) {
        let stick_speed = self.inner.system().frictions()[k].stick_speed;
        let (a, b) = modes_at(w, stick_speed);
        self.terms[k].mode = a;
        self.terms[p].mode = b;
    }

    /// Sets cone `(k, p)` slipping along the slip velocity `w` (stuck where it is zero): where
    /// its stuck slip left the stick speed, at a location that may end just short of it.
    pub(super) fn slip_cone(&mut self, (k, p): (usize, usize), w: (f64, f64)) {
        let (a, b) = modes_at(w, 0.0);
        self.terms[k].mode = a;
        self.terms[p].mode = b;
    }

    /// Each slipping cone's force direction at the slip velocity at `v` (rows filled at the
    /// evaluation's state), [`slip_direction`], into its elements' [`FrictionTerms::along`]:
    /// (F1) then opposes the slip at every stage of a step.
    ///
    /// [`FrictionTerms::along`]: crate::friction::FrictionTerms::along
    pub(super) fn steer_cones(&mut self, v: &[f64]) {
        for k in 0..self.frictions {
            let Some(p) = self.cone_of(k).filter(|&p| p > k) else {
                continue;
            };
            let (along_k, along_p) = match (self.terms[k].mode, self.terms[p].mode) {
                (Mode::Slip(a), Mode::Slip(b)) => {
                    let stick_speed = self.inner.system().frictions()[k].stick_speed;
                    let u = slip_direction((a, b), self.cone_rate((k, p), v), stick_speed);
                    (Some(u.0), Some(u.1))
                }
                _ => (None, None),
            };
            self.terms[k].along = along_k;
            self.terms[p].along = along_p;
        }
    }

    /// The cones' event functions into `out` (the friction elements' slots, rows filled at `v`):
    /// [`event`] in the first element's slot, none in the second's.
    pub(super) fn cone_events(&self, v: &[f64], out: &mut [f64]) {
        for (k, p) in self.cones() {
            let stick_speed = self.inner.system().frictions()[k].stick_speed;
            let modes = (self.terms[k].mode, self.terms[p].mode);
            let value = event(modes, self.cone_rate((k, p), v), stick_speed);
            if let Some(slot) = out.get_mut(k) {
                *slot = value;
            }
            if let Some(slot) = out.get_mut(p) {
                *slot = 1.0;
            }
        }
    }
}
