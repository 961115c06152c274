//! The impulses of [`Frictional`]: limits that strike at an event, with the held limits and the
//! contacts' friction ((L3), (L5), (L6), (L9) of `docs/limits.md`), and the slips that stop at an
//! event (`docs/friction.md`, "Events"), each one set of impulses solved together.

use super::{Frictional, STRIKE_TOGETHER};
use crate::friction::{determined, solve_dense, weighted_least_norm, Mode, RELEASE_SHARE};
use crate::limit::{impact_impulse, impact_loss, LIMIT_SLACK};
use crate::{DynamicsError, Formulation};

impl Frictional {
    /// The impacts of the limits in `striking` (their indices among the elements) at `(t, q, v)`,
    /// together, by (L3) and (L5) of `docs/limits.md`: each limit moving towards its nearer bound
    /// strikes; its rate is to leave at `−e w⁻`, or at zero where that rebound is below its rest
    /// speed (it is then held on the bound). The limits already held stay on their bounds, and
    /// the friction element of a striking or a held contact (at rest or sliding) stops its slip
    /// through the impact or, where that needs more than `μ P_n`, slips with `μ P_n` (L6). The
    /// impulses solve `G P = w⁺ − w⁻` with
    /// `G_ab = g_a·A_b` over them all; a limit whose impulse would pull takes none (a held one
    /// lets go), and they are found again (L9). So a block landing flat on two corners bounces
    /// as one body, whatever the order its corners are listed in. Nothing happens where no
    /// limit moves towards its bound.
    pub(super) fn impact(&mut self, t: f64, q: &[f64], v: &mut [f64]) -> Result<bool, DynamicsError> {
        // The striking limits first, with their targets; then the held ones; then the contacts'
        // friction elements.
        self.impact_set.clear();
        self.impact_frictions.clear();
        for i in 0..self.striking.len() {
            let k = self.striking[i];
            let s = self.fill_row(k, t, q, v);
            let limit = &self.inner.system().limits()[k - self.frictions];
            let (sign, rest_speed, restitution) = (limit.nearer_bound(s), limit.rest_speed, limit.restitution);
            let before = self.terms[k].row.dot(v);
            if sign * before >= 0.0 {
                continue;
            }
            // The rebound too small to leave: the joint rests on its bound, its rate zero.
            let held = restitution * before.abs() < rest_speed;
            self.impact_target[k] = if held { 0.0 } else { -restitution * before };
            self.strike[k] = Some((sign, held));
            self.impact_set.push(k);
        }
        let strikes = self.impact_set.len();
        if strikes == 0 {
            return Ok(false);
        }
        // The others at their bounds (within `STRIKE_TOGETHER`), not moving towards them: held
        // through the impact, their rates kept at zero where the strikes' impulses would drive
        // them in (their impulses then push); the pull check lets go of the others (L9). Without
        // it two stops that a chain rests near strike one after the other ever faster (each
        // strike drives the other in), until a crossing falls within the location's round-off
        // and is missed.
        for i in 0..self.striking.len() {
            let k = self.striking[i];
            if self.strike[k].is_none() {
                let s = self.fill_row(k, t, q, v);
                let limit = &self.inner.system().limits()[k - self.frictions];
                if limit.free_event(s) <= LIMIT_SLACK + STRIKE_TOGETHER {
                    self.impact_target[k] = 0.0;
                    self.strike[k] = Some((limit.nearer_bound(s), true));
                    self.impact_set.push(k);
                }
            }
        }
        for j in self.frictions..self.terms.len() {
            if matches!(self.terms[j].mode, Mode::Held(_)) && self.strike[j].is_none() {
                self.impact_set.push(j);
                self.impact_target[j] = 0.0;
            }
        }
        // Each striking contact's friction, and each held contact's: a contact resting or
        // sliding on a floor takes its friction impulse too (L6), within `μ P_n` of its own
        // impulse (its slip stopped where that suffices, else slowed by `μ P_n`).
        let limits = self.impact_set.len();
        for a in 0..limits {
            self.add_contact_friction(self.impact_set[a]);
        }
        let mut qdd = std::mem::take(&mut self.event_qdd);
        let mut lambda = std::mem::take(&mut self.event_lambda);
        let mut result = self.inner.accelerations(t, q, v, None, &mut qdd, &mut lambda);
        for a in 0..self.impact_set.len() {
            let j = self.impact_set[a];
            if a >= strikes {
                self.fill_row(j, t, q, v);
            }
            result = result.and_then(|()| self.response(j, (t, q, v), None, (&qdd, &lambda)));
        }
        self.event_qdd = qdd;
        self.event_lambda = lambda;
        let outcome = result.and_then(|()| self.solve_strikes(t, v));
        // The modes after it: a striking limit held or free; a held one that let go free (only
        // where some limit struck).
        let struck = self.strike.iter().any(|s| s.is_some());
        for k in self.frictions..self.terms.len() {
            if let Some((sign, held)) = self.strike[k].take() {
                self.terms[k].mode = if held { Mode::Held(sign) } else { Mode::Free };
            }
            self.kept[k] = false;
            if std::mem::take(&mut self.released[k]) && struck {
                self.terms[k].mode = Mode::Free;
                self.leave_bound(k, t, q, v);
            }
        }
        outcome?;
        if struck {
            self.follow_contacts(t, q, v);
        }
        Ok(struck)
    }

    /// Adds to the impact under way the friction elements of limit element `k`'s contact (one
    /// element, or a cone's two) where `k` strikes or its friction is not free, their rates to
    /// stop (L6).
    fn add_contact_friction(&mut self, k: usize) {
        let (contact, pressed) = (k - self.frictions, self.strike[k].is_some());
        for f in 0..self.frictions {
            let loaded = self.inner.system().frictions()[f].load_limit == Some(contact);
            if loaded && (pressed || self.terms[f].mode != Mode::Free) {
                self.impact_set.push(f);
                self.impact_target[f] = 0.0;
                self.impact_frictions.push((f, k, None));
            }
        }
    }

    /// The held limits the impact under way let go of (their impulses would pull) that would
    /// leave their bounds slower than their rest speeds, or not at all, under the impulses found
    /// without them: each is kept on its bound with its contact's friction (its impulse may then
    /// pull) and true is returned, for the impulses to be found again. The rule that holds a
    /// striking limit whose rebound is below its rest speed ((L3)), for a limit the impact would
    /// lift: a block rocking onto the other corner of an edge lifts the first ever slower (with
    /// `e = 0`, by the ratio of its angular momenta about the two corners), a sequence of impacts
    /// without end in finite time; it stops once the lift is below the rest speed. And a held
    /// limit let go where the impulses drive it into its bound is kept on it.
    fn keep_slow_releases(&mut self, v: &[f64]) -> bool {
        let n = self.impact_set.len();
        let mut kept = false;
        for k in self.frictions..self.terms.len() {
            let Mode::Held(sign) = self.terms[k].mode else { continue };
            if !self.released[k] {
                continue;
            }
            let row = &self.terms[k].row;
            let rate = row.dot(v)
                + (0..n)
                    .map(|b| row.dot(&self.terms[self.impact_set[b]].dv) * self.impact_p[b])
                    .sum::<f64>();
            if sign * rate < self.inner.system().limits()[k - self.frictions].rest_speed {
                self.released[k] = false;
                self.kept[k] = true;
                self.impact_set.push(k);
                self.impact_target[k] = 0.0;
                self.add_contact_friction(k);
                kept = true;
            }
        }
        kept
    }

    /// The sign `σ` with which limit element `k`'s impulse pushes in the impact under way (its
    /// nearer bound's where it strikes, its held bound's where it is held); `None` for a friction
    /// element or a free limit that does not strike.
    pub(super) fn pushing_sign(&self, k: usize) -> Option<f64> {
        match (self.strike.get(k).copied().flatten(), self.terms[k].mode) {
            _ if k < self.frictions => None,
            (Some((sign, _)), _) | (None, Mode::Held(sign)) => Some(sign),
            _ => None,
        }
    }

    /// The impulses of [`Frictional::impact`] over `impact_set` (rows and responses filled),
    /// applied to `v`; a striking limit that takes none is left out of `strike`.
    pub(super) fn solve_strikes(&mut self, t: f64, v: &mut [f64]) -> Result<(), DynamicsError> {
        // Each striking limit alone, (L3) in closed form: its check that the impulse moves the
        // joint.
        for &k in &self.impact_set {
            if let Some(limit) = self.strike[k].and(k.checked_sub(self.frictions)) {
                let term = &self.terms[k];
                impact_impulse(
                    &self.inner.system().limits()[limit],
                    term.row.dot(v),
                    term.row.dot(&term.dv),
                    t,
                )?;
            }
        }
        loop {
            self.solve_impulses(v, t)?;
            // A contact's friction: held through the impact while the impulse that stops its
            // slip is within `μ P_n`, else slipping against the slip before it (`docs/limits.md`,
            // "Friction in rigid contact", (L6)).
            let system = self.inner.system();
            let position = |set: &[usize], k: usize| set.iter().position(|&j| j == k);
            let mut switched = false;
            for i in 0..self.impact_frictions.len() {
                let (f, normal, slip) = self.impact_frictions[i];
                let (Some(a), Some(b), None) =
                    (position(&self.impact_set, f), position(&self.impact_set, normal), slip)
                else {
                    continue;
                };
                let spec = &system.frictions()[f];
                // A cone's two impulses are bounded together (by its first element).
                let cone = match spec.cone {
                    Some(p) if p < f => continue,
                    Some(p) => self.impact_frictions.iter().position(|e| e.0 == p),
                    None => None,
                };
                let other = cone.and_then(|j| position(&self.impact_set, self.impact_frictions[j].0));
                let (p_n, p_t) = (
                    self.impact_p[b],
                    (self.impact_p[a], other.map_or(0.0, |c| self.impact_p[c])),
                );
                let size = p_t.0.hypot(p_t.1);
                if size > spec.coefficient * p_n.abs() {
                    let sign = self.pushing_sign(normal).unwrap_or(1.0);
                    // It slips against its slip before the impact; from rest, against the
                    // impulse that would have held it.
                    let w = (
                        self.terms[f].row.dot(v),
                        cone.map_or(0.0, |j| self.terms[self.impact_frictions[j].0].row.dot(v)),
                    );
                    let speed = w.0.hypot(w.1);
                    let direction = if speed > spec.stick_speed {
                        (w.0 / speed, w.1 / speed)
                    } else {
                        (-p_t.0 / size, -p_t.1 / size)
                    };
                    let mu = spec.coefficient * sign;
                    self.impact_frictions[i].2 = Some(direction.0 * mu);
                    if let Some(j) = cone {
                        self.impact_frictions[j].2 = Some(direction.1 * mu);
                    }
                    switched = true;
                }
            }
            if switched {
                continue;
            }
            // A limit whose impulse would pull takes none (a held one lets go), with its
            // contact's friction, and the impulses are found again; a pull at round-off of the
            // largest impulse does not count ((L2)'s adhesion).
            let n = self.impact_set.len();
            let largest = self.impact_p[..n].iter().fold(0.0f64, |m, p| m.max(p.abs()));
            let pulling = (0..n).find(|&a| {
                let k = self.impact_set[a];
                !self.kept[k]
                    && self
                        .pushing_sign(k)
                        .is_some_and(|sign| sign * self.impact_p[a] < -RELEASE_SHARE * largest)
            });
            let Some(a) = pulling else {
                if self.keep_slow_releases(v) {
                    continue;
                }
                break;
            };
            let k = self.impact_set.remove(a);
            if self.strike[k].take().is_none() {
                self.released[k] = true;
            }
            while let Some(i) = self.impact_frictions.iter().position(|&(_, normal, _)| normal == k) {
                let (f, _, _) = self.impact_frictions.remove(i);
                self.impact_set.retain(|&j| j != f);
            }
            if !self.impact_set.iter().any(|&j| self.strike[j].is_some()) {
                return Ok(());
            }
        }
        self.apply_impulses(v);
        Ok(())
    }

    /// Applies the impulses `impact_p` over `impact_set` (as [`Frictional::solve_impulses`]
    /// leaves them) to `v`, and adds the kinetic energy they take, `−Σ P (w⁻ + w⁺) / 2` with
    /// `w⁺ = w⁻ + G P`, to the balance's impact loss.
    fn apply_impulses(&mut self, v: &mut [f64]) {
        let n = self.impact_set.len();
        for a in 0..n {
            let w_before = self.terms[self.impact_set[a]].row.dot(v);
            let change: f64 = (0..n).map(|b| self.impact_g[a * n + b] * self.impact_p[b]).sum();
            self.impact_loss += impact_loss(self.impact_p[a], w_before, w_before + change);
        }
        for a in 0..n {
            let (term, impulse) = (&self.terms[self.impact_set[a]], self.impact_p[a]);
            v.iter_mut().zip(&term.dv).for_each(|(x, r)| *x += r * impulse);
        }
    }

    /// Each rigid contact's friction element's mode from its contact's: free while the contact
    /// is free; where the contact has just come to rest, stuck or slipping by its slip rate. A
    /// stuck element whose rate an impulse took beyond its stick speed slips in its direction; a
    /// slipping one whose slip an impulse stopped (within its stick speed) sticks, and one whose
    /// slip it turned slips the other way.
    pub(super) fn follow_contacts(&mut self, t: f64, q: &[f64], v: &[f64]) {
        for k in 0..self.frictions {
            let system = self.inner.system();
            let spec = &system.frictions()[k];
            let held = spec
                .load_limit
                .map(|l| matches!(self.terms[self.frictions + l].mode, Mode::Held(_)));
            if held == Some(false) {
                self.terms[k].mode = Mode::Free;
                continue;
            }
            let stick_speed = spec.stick_speed;
            let mode = self.terms[k].mode;
            if let Some(p) = spec.cone {
                if p > k {
                    self.follow_cone((k, p), (t, q, v));
                }
                continue;
            }
            if matches!(mode, Mode::Free | Mode::Stick | Mode::Slip(_)) {
                system.slip_row(k, t, q, v, &mut self.terms[k].row);
                let w = self.terms[k].row.dot(v);
                let turned = matches!(mode, Mode::Slip(sign) if sign * w <= stick_speed);
                if mode == Mode::Free || turned || (mode == Mode::Stick && w.abs() > stick_speed) {
                    self.terms[k].mode = Mode::at(w, stick_speed);
                    self.terms[k].fresh = self.terms[k].mode == Mode::Stick;
                }
            }
        }
    }

    /// [`Frictional::follow_contacts`] for the cone `(k, p)` of a held contact: from free, or where
    /// an impulse stopped or turned its slip (its slip velocity now within the stick speed along
    /// the slip's direction), or took a stuck one beyond the stick speed, the modes of its slip
    /// velocity.
    fn follow_cone(&mut self, (k, p): (usize, usize), (t, q, v): (f64, &[f64], &[f64])) {
        self.fill_row(k, t, q, v);
        self.fill_row(p, t, q, v);
        let w = self.cone_rate((k, p), v);
        let stick_speed = self.inner.system().frictions()[k].stick_speed;
        let reset = match (self.terms[k].mode, self.terms[p].mode) {
            (Mode::Slip(a), Mode::Slip(b)) => a * w.0 + b * w.1 <= stick_speed,
            (Mode::Stick, _) => w.0.hypot(w.1) > stick_speed,
            _ => true,
        };
        if reset {
            self.set_cone((k, p), w);
            for j in [k, p] {
                self.terms[j].fresh = self.terms[j].mode == Mode::Stick;
            }
        }
    }

    /// Adds to `stopping` every slipping element not in it whose slip (a cone's: its two rows')
    /// is within its stick speed at `(t, q, v)` ([`Frictional::at_event`]).
    pub(super) fn join_stopping(&mut self, t: f64, q: &[f64], v: &[f64]) {
        for k in 0..self.frictions {
            let Mode::Slip(sign) = self.terms[k].mode else { continue };
            if self.stopping.iter().any(|&(j, _)| j == k) {
                continue;
            }
            let stick_speed = self.inner.system().frictions()[k].stick_speed;
            match self.cone_of(k) {
                Some(p) if p < k => {}
                Some(p) => {
                    self.fill_row(k, t, q, v);
                    self.fill_row(p, t, q, v);
                    let w = self.cone_rate((k, p), v);
                    if let (true, Mode::Slip(other)) = (w.0.hypot(w.1) <= stick_speed, self.terms[p].mode) {
                        self.stopping.push((k, sign));
                        self.stopping.push((p, other));
                    }
                }
                None => {
                    self.fill_row(k, t, q, v);
                    if self.terms[k].row.dot(v).abs() <= stick_speed {
                        self.stopping.push((k, sign));
                    }
                }
            }
        }
    }

    /// The slips that stop at an event (`stopping`): the impulse that sets each one's rate to
    /// zero, `v ← v + Σ A P`, together with the impulses that keep every held limit on its bound
    /// and every stuck element stuck (a block whose corners rest on a floor turns about neither),
    /// from `G P = −w` over them (`G_ab = g_a·A_b`, least-norm where they are redundant); then each
    /// stops, and the evaluation there says whether it sticks (its force found with the others',
    /// [`FrictionTerms::fresh`]).
    pub(super) fn stop_slips(&mut self, t: f64, q: &[f64], v: &mut [f64]) -> Result<(), DynamicsError> {
        let mut qdd = std::mem::take(&mut self.event_qdd);
        let mut lambda = std::mem::take(&mut self.event_lambda);
        let result = self.accelerations(t, q, v, None, &mut qdd, &mut lambda).and_then(|()| {
            self.impact_set.clear();
            self.impact_set.extend(self.stopping.iter().map(|&(k, _)| k));
            for j in 0..self.terms.len() {
                let holds = match self.terms[j].mode {
                    Mode::Held(_) => true,
                    Mode::Stick => j < self.frictions && self.terms[j].sticks,
                    _ => false,
                };
                if holds && !self.impact_set.contains(&j) {
                    self.impact_set.push(j);
                }
            }
            for a in 0..self.impact_set.len() {
                let j = self.impact_set[a];
                self.fill_row(j, t, q, v);
                self.response_from_base(j, (t, q, v), None)?;
            }
            self.impact_frictions.clear();
            for &j in &self.impact_set {
                self.impact_target[j] = 0.0;
            }
            self.solve_impulses(v, t)?;
            self.apply_impulses(v);
            for i in 0..self.stopping.len() {
                let k = self.stopping[i].0;
                self.terms[k].mode = Mode::Stick;
                self.terms[k].fresh = true;
            }
            self.accelerations(t, q, v, None, &mut qdd, &mut lambda)
        });
        self.event_qdd = qdd;
        self.event_lambda = lambda;
        result
    }

    /// The impulses `P` over `impact_set` (rows and responses filled) that take each element's
    /// rate to its `impact_target`: `G P = w⁺ − w⁻` with `G_ab = g_a·A_b` (kept in `impact_g`),
    /// a slipping friction element's row `P_f + σ μ P_n = 0` instead ([`Frictional::impact`]),
    /// into `impact_p`.
    pub(super) fn solve_impulses(&mut self, v: &[f64], t: f64) -> Result<(), DynamicsError> {
        let n = self.impact_set.len();
        for a in 0..n {
            let k = self.impact_set[a];
            let row = &self.terms[k].row;
            for b in 0..n {
                self.impact_g[a * n + b] = row.dot(&self.terms[self.impact_set[b]].dv);
            }
            self.impact_p[a] = self.impact_target[k] - row.dot(v);
        }
        // A contact's friction slipping through the impact: `P_f + σ μ P_n = 0` for its row.
        let set = &self.impact_set;
        let slips = &self.impact_frictions;
        let equations = |lu: &mut [f64], rhs: &mut [f64]| {
            lu[..n * n].copy_from_slice(&self.impact_g[..n * n]);
            for &(f, normal, slip) in slips {
                let (Some(slip), Some(a), Some(b)) = (
                    slip,
                    set.iter().position(|&j| j == f),
                    set.iter().position(|&j| j == normal),
                ) else {
                    continue;
                };
                let row = &mut lu[a * n..a * n + n];
                row.iter_mut().for_each(|x| *x = 0.0);
                row[a] = 1.0;
                row[b] = slip;
                rhs[a] = 0.0;
            }
        };
        equations(&mut self.impact_lu, &mut self.impact_p);
        self.impact_rhs[..n].copy_from_slice(&self.impact_p[..n]);
        // Nearly redundant (two corners of an edge level to the integration's error): the LU
        // accepts the matrix, but its impulses carry a large share along the direction the
        // corners hold together (measured: 8e4 N·s, equal and opposite at the two corners of a
        // 2 kg box's edge, to stop slips of 1e-7 m/s), so the least-norm split decides there too.
        // The test reads `G` where a slipping friction's row replaced its row (entries 1 and
        // `μ`): the scale it compares is the same.
        if solve_dense(&mut self.impact_lu[..n * n], &mut self.impact_p[..n], n)
            && determined(&self.impact_p[..n], &self.impact_g[..n * n], &self.impact_rhs[..n])
        {
            return Ok(());
        }
        // Redundant: two corners of a block held on a floor, or stuck on it, hold one motion; the
        // impulses of least weighted norm, as `solve_friction`'s forces (friction impulses weigh
        // more than the limits', so a body the normal impulses can hold is held by them).
        equations(&mut self.impact_lu, &mut self.impact_rhs);
        let frictions = self.frictions;
        if weighted_least_norm(
            &mut self.impact_lu[..n * n],
            &mut self.impact_rhs[..n],
            (n, |c| set[c] < frictions),
            (&mut self.impact_gram[..n * n], &mut self.impact_scratch[..n]),
            &mut self.impact_p[..n],
        ) {
            return Ok(());
        }
        let system = self.inner.system();
        let names: Vec<&str> = self
            .impact_set
            .iter()
            .map(|&j| match j.checked_sub(self.frictions) {
                Some(l) => system.limits()[l].name.as_str(),
                None => system.frictions()[j].name.as_str(),
            })
            .collect();
        Err(DynamicsError::Limit {
            time: t,
            element: format!("joints '{}'", names.join("', '")),
            what: "the impulses of an impact with these joints held are not determined (their joints move together)"
                .into(),
        })
    }
}
