//! Any formulation with joint friction or joint limits ([`Frictional`], `docs/friction.md`,
//! `docs/limits.md`): the formulation's frictionless accelerations, its response to a unit force
//! along each friction element and each held limit, and the stick–slip law of
//! [`crate::friction`] and the impact law of [`crate::limit`] on top. One code for every
//! formulation.

use crate::friction::{slip_force, solve_friction, FrictionTerms, FrictionWork, Mode, SLIP_END};
use crate::limit::{unwrap_angle, LIMIT_SLACK};
use crate::{Baumgarte, DynamicsError, Formulation, FormulationStats, MultibodySystem};

mod cones;
mod impacts;

/// A formulation whose system has joint friction ([`MultibodySystem::frictions`]) or joint
/// limits ([`MultibodySystem::limits`]).
///
/// Each evaluation costs one evaluation of the inner formulation plus, per friction element and
/// per held limit, a solve with its factorization (its response to a unit force along the
/// joint); a free limit costs nothing but its event function. Nothing is allocated after setup.
pub struct Frictional {
    inner: Box<dyn Formulation>,
    terms: Vec<FrictionTerms>,
    work: FrictionWork,
    forces: Vec<f64>,
    dense: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    /// `v̇` and `λ` at an event ([`Formulation::at_event`]).
    event_qdd: Vec<f64>,
    event_lambda: Vec<f64>,
    /// True once the modes were set ([`Formulation::start_events`]).
    started: bool,
    /// True once [`Frictional::slipping`] gave up since the last event: Newton's method on every
    /// element decides until the next one.
    newton_until_event: bool,
    /// The number of friction elements (the limits follow them in `terms`).
    frictions: usize,
    /// The kinetic energy the impulses at events (impacts, slips stopped) took so far (J).
    impact_loss: f64,
    /// Each limit's coordinate at its last evaluation: a coordinate measured within a turn
    /// ([`crate::JointLimit::within_turn`]) is followed from it across half turns.
    coordinates: Vec<f64>,
    /// Per limit, what its event function is raised by since it last left a bound (rebounding
    /// from an impact, or let go): the function there, zero within round-off, may be just below
    /// zero, and a return within one step would then show no change of sign
    /// ([`Frictional::leave_bound`]).
    raised: Vec<f64>,
    /// True when an evaluation past a free limit's bound is an error
    /// ([`Frictional::refusing_impacts`]).
    refuse_impacts: bool,
    /// Why a limit reached stops the computation ([`Frictional::refusing_impacts`]).
    refusal: String,
    /// An impact's limits (the impacting one first, then the held ones), their `G` and its
    /// factorization's work copy, and their impulses ([`Frictional::solve_impulses`]).
    impact_set: Vec<usize>,
    impact_g: Vec<f64>,
    impact_lu: Vec<f64>,
    impact_p: Vec<f64>,
    /// Each element's rate after an impact, `w⁺` (read for the elements in `impact_set`).
    impact_target: Vec<f64>,
    /// The contacts' friction elements in an impact (the striking contacts' and the held
    /// contacts'): `(friction element, its contact's limit element, σ μ)`, `σ μ` where
    /// it slips through the impact (its row then `P_f + σ μ P_n = 0`), `None` where it sticks
    /// (its rate taken to zero).
    impact_frictions: Vec<(usize, usize, Option<f64>)>,
    /// The limits that strike at an event ([`Frictional::at_event`]), as element indices.
    striking: Vec<usize>,
    /// Per element: in an impact, a striking limit's nearer bound's sign and whether it comes to
    /// rest there ([`Frictional::impact`]); `None` otherwise.
    strike: Vec<Option<(f64, bool)>>,
    /// Per element: a held limit whose impulse would pull in the impact under way (it lets go
    /// where some limit strikes).
    released: Vec<bool>,
    /// Per element: a held limit the impact under way keeps on its bound though its impulse
    /// pulls: let go, it would leave slower than its rest speed ([`Frictional::keep_slow_releases`]).
    kept: Vec<bool>,
    /// The friction elements' `fresh` flags, kept across [`Frictional::release_pulling`]'s
    /// evaluation.
    fresh_kept: Vec<bool>,
    /// Work space of the impulses' least-norm solution where their set is redundant.
    impact_gram: Vec<f64>,
    impact_rhs: Vec<f64>,
    impact_scratch: Vec<f64>,
    /// The slips that stop at an event, with their directions ([`Frictional::stop_slips`]).
    stopping: Vec<(usize, f64)>,
    /// `v̇₀`, `λ₀` of the last evaluation: the inner formulation's, without friction and limits.
    base_qdd: Vec<f64>,
    base_lambda: Vec<f64>,
    /// The response to the slipping elements' forces together ([`Frictional::slipping`]).
    slip_dv: Vec<f64>,
    slip_dlambda: Vec<f64>,
    /// Each slipping element's last iterate `F′` and `φ(F′)` ([`Frictional::mix_slipping`]).
    mix: Vec<(f64, f64)>,
    /// The forces of the last two evaluations at different times, and those times (NaN where
    /// there is none): the forces at the next time are extrapolated from them
    /// ([`Frictional::predict`]).
    past: Vec<f64>,
    latest: Vec<f64>,
    times: (f64, f64),
    /// The system's multipliers `m`, and its reaction loads after them
    /// ([`MultibodySystem::num_reaction_loads`]: a tree in joint coordinates): the multipliers
    /// the friction law reads (`λ`, `Λ_k`) are the `m` extended by these.
    m: usize,
    loads: usize,
    /// `λ` extended by the reaction loads, during an evaluation where there are any.
    ext: Vec<f64>,
}

impl std::fmt::Debug for Frictional {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Frictional({}, {} elements)", self.inner.name(), self.terms.len())
    }
}

impl Frictional {
    /// `inner` with the friction of its system's joints; an error when the formulation cannot
    /// take an added force (a tree solved outright by the articulated-body algorithm).
    pub fn new(mut inner: Box<dyn Formulation>) -> Result<Self, DynamicsError> {
        let (n, m, loads, frictions, count) = {
            let s = inner.system();
            let f = s.frictions().len();
            let loads = if f > 0 { s.num_reaction_loads() } else { 0 };
            (s.layout().n_v(), s.num_equations(), loads, f, f + s.limits().len())
        };
        let ml = m + loads;
        if count > 0 && !inner.set_extra_force(None) {
            let s = inner.system();
            let joint = match s.frictions().first() {
                Some(f) => format!("{} '{}'", f.element, f.name),
                None => format!("joint '{}'", s.limits()[0].name),
            };
            return Err(DynamicsError::Friction {
                time: 0.0,
                joint,
                what: format!(
                    "the {} formulation solves this model without forces added to it (a tree in joint \
                     coordinates): use absolute coordinates",
                    inner.name()
                ),
            });
        }
        Ok(Frictional {
            inner,
            terms: (0..count).map(|_| FrictionTerms::new(n, ml)).collect(),
            work: FrictionWork::new(count, ml),
            forces: vec![0.0; count],
            dense: vec![0.0; n],
            qdd: vec![0.0; n],
            lambda: vec![0.0; ml],
            event_qdd: vec![0.0; n],
            event_lambda: vec![0.0; m],
            started: false,
            newton_until_event: false,
            frictions,
            impact_loss: 0.0,
            coordinates: vec![0.0; count - frictions],
            raised: vec![0.0; count - frictions],
            refuse_impacts: false,
            refusal: String::new(),
            impact_set: Vec::with_capacity(count),
            impact_g: vec![0.0; count * count],
            impact_lu: vec![0.0; count * count],
            impact_p: vec![0.0; count],
            impact_target: vec![0.0; count],
            impact_frictions: Vec::with_capacity(count),
            striking: Vec::with_capacity(count),
            strike: vec![None; count],
            released: vec![false; count],
            kept: vec![false; count],
            fresh_kept: vec![false; count],
            impact_gram: vec![0.0; count * count],
            impact_rhs: vec![0.0; count],
            impact_scratch: vec![0.0; count],
            stopping: Vec::with_capacity(count),
            base_qdd: vec![0.0; n],
            base_lambda: vec![0.0; ml],
            slip_dv: vec![0.0; n],
            slip_dlambda: vec![0.0; ml],
            mix: vec![(0.0, 0.0); count],
            past: vec![0.0; count],
            latest: vec![0.0; count],
            times: (f64::NAN, f64::NAN),
            m,
            loads,
            ext: vec![0.0; ml],
        })
    }

    /// The formulation for a computation that holds only while every limit is free (a run's
    /// sensitivities, which do not cross an impact): an evaluation where a limit's coordinate
    /// reaches a bound, or starts held on one, is an error naming the limit
    /// ([`DynamicsError::Limit`]), so the run stops there.
    pub fn refusing_impacts(self) -> Self {
        self.refusing_impacts_because("this computation holds only while every limit is free")
    }

    /// [`Frictional::refusing_impacts`], the error saying `why` (what holds only while the limits
    /// are free, and what to use instead).
    pub fn refusing_impacts_because(mut self, why: &str) -> Self {
        self.refuse_impacts = true;
        self.refusal = why.into();
        self
    }

    /// Fills element `k`'s row at `(t, q, v)`; for a limit, returns its coordinate.
    fn fill_row(&mut self, k: usize, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let system = self.inner.system();
        if k < self.frictions {
            system.slip_row(k, t, q, v, &mut self.terms[k].row);
            0.0
        } else {
            let l = k - self.frictions;
            let raw = system.limit_row(l, t, q, v, &mut self.terms[k].row);
            follow(&system.limits()[l], &mut self.coordinates[l], raw)
        }
    }

    /// Element `k`'s response `A_k`, `Λ_k` to a unit force along its row (filled), after the
    /// inner formulation's evaluation at the same state gave `qdd0`, `lambda0`: from the
    /// formulation's factorization ([`Formulation::force_response`]), or else from a second
    /// evaluation with a force `s g_k` added (`s` the largest multiplier or 1, so that the
    /// difference keeps its digits), divided by `s`.
    fn response(
        &mut self,
        k: usize,
        (t, q, v): (f64, &[f64], &[f64]),
        baumgarte: Option<Baumgarte>,
        (qdd0, lambda0): (&[f64], &[f64]),
    ) -> Result<(), DynamicsError> {
        let m = self.m;
        self.terms[k].row.write_dense(&mut self.dense);
        let term = &mut self.terms[k];
        if !self
            .inner
            .force_response(t, &self.dense, &mut term.dv, &mut term.dlambda[..m])?
        {
            let scale = lambda0[..m].iter().fold(1.0f64, |a, l| a.max(l.abs()));
            self.dense.iter_mut().for_each(|g| *g *= scale);
            self.inner.set_extra_force(Some(&self.dense));
            let solved = self
                .inner
                .accelerations(t, q, v, baumgarte, &mut self.qdd, &mut self.lambda[..m]);
            self.inner.set_extra_force(None);
            solved?;
            let term = &mut self.terms[k];
            for ((r, a), a0) in term.dv.iter_mut().zip(&self.qdd).zip(qdd0) {
                *r = (a - a0) / scale;
            }
            for ((r, l), l0) in term.dlambda[..m].iter_mut().zip(&self.lambda).zip(&lambda0[..m]) {
                *r = (l - l0) / scale;
            }
        }
        if self.loads > 0 {
            let term = &mut self.terms[k];
            (self.inner.system()).reaction_loads(t, q, v, &term.dv, true, &mut term.dlambda[m..]);
        }
        Ok(())
    }

    /// The forces the solutions start from at time `t`: where the two evaluations before were at
    /// times `t_a < t_b < t` (a step's stages), extrapolated along the line through their forces
    /// (the stages of a step at `h/2` from each other: the start is off by `O(h²)` instead of
    /// `O(h)`, a step saves an iteration or two); otherwise the last evaluation's.
    fn predict(&mut self, t: f64) {
        let (ta, tb) = self.times;
        if !(t > tb && tb > ta && t - tb <= 2.0 * (tb - ta)) {
            return;
        }
        let s = (t - tb) / (tb - ta);
        for ((term, &now), &before) in self.terms.iter_mut().zip(&self.latest).zip(&self.past) {
            if term.mode != Mode::Free {
                term.force = now + s * (now - before);
            }
        }
    }

    /// Keeps the forces an evaluation at time `t` found ([`Frictional::predict`]).
    fn record(&mut self, t: f64) {
        let (_, tb) = self.times;
        if t > tb {
            std::mem::swap(&mut self.past, &mut self.latest);
            self.times = (tb, t);
        } else if t != tb {
            // Back in time (a step taken again): no line to extend.
            self.times = (f64::NAN, t);
        }
        for (f, term) in self.latest.iter_mut().zip(&self.terms) {
            *f = term.force;
        }
    }

    /// [`Frictional::response`] of element `k` after an evaluation at `(t, q, v)`, from that
    /// evaluation's frictionless `v̇₀`, `λ₀`.
    fn response_from_base(
        &mut self,
        k: usize,
        at: (f64, &[f64], &[f64]),
        baumgarte: Option<Baumgarte>,
    ) -> Result<(), DynamicsError> {
        let qdd0 = std::mem::take(&mut self.base_qdd);
        let lambda0 = std::mem::take(&mut self.base_lambda);
        let result = self.response(k, at, baumgarte, (&qdd0, &lambda0));
        self.base_qdd = qdd0;
        self.base_lambda = lambda0;
        result
    }

    /// The forces of the slipping friction elements, by iterating on them (`docs/friction.md`,
    /// "Cost"): from the last evaluation's forces, the formulation's response to all of them
    /// together (one solve), the holding elements' forces by [`solve_friction`] on that, and each
    /// slipping element's (F1) at the loads found, again until the forces settle. The iteration
    /// contracts by about `μ |L Λ|` (below 1 where the law determines the force). Into `qdd`,
    /// `lambda` (the base `v̇₀`, `λ₀` kept); true when found, false when the iteration gave up
    /// (it contracts by less than half, or the formulation cannot respond to a force outright):
    /// Newton's method on every element then decides, and names a Painlevé configuration.
    fn slipping(
        &mut self,
        (t, q, v): (f64, &[f64], &[f64]),
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        for term in &mut self.terms[..self.frictions] {
            if matches!(term.mode, Mode::Slip(_)) {
                term.given = true;
                if !term.force.is_finite() {
                    term.force = 0.0;
                }
            }
        }
        let found = self.iterate_slipping((t, q, v), qdd, lambda);
        for term in &mut self.terms[..self.frictions] {
            term.given = false;
        }
        found
    }

    /// The iteration of [`Frictional::slipping`], the slipping elements marked given.
    fn iterate_slipping(
        &mut self,
        (t, q, v): (f64, &[f64], &[f64]),
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        let mut last = f64::INFINITY;
        for _ in 0..SLIP_ITERATIONS {
            // Σ g_p F_p over the slipping elements, and the response to it.
            self.dense.iter_mut().for_each(|x| *x = 0.0);
            for term in self.terms[..self.frictions].iter().filter(|term| term.given) {
                for &(i, g) in term.row.entries() {
                    self.dense[i] += g * term.force;
                }
            }
            if !self
                .inner
                .force_response(t, &self.dense, &mut self.slip_dv, &mut self.slip_dlambda[..self.m])?
            {
                return Ok(false);
            }
            if self.loads > 0 {
                let (m, system) = (self.m, self.inner.system());
                system.reaction_loads(t, q, v, &self.slip_dv, true, &mut self.slip_dlambda[m..]);
            }
            for ((a, a0), d) in qdd.iter_mut().zip(&self.base_qdd).zip(&self.slip_dv) {
                *a = a0 + d;
            }
            for ((l, l0), d) in lambda.iter_mut().zip(&self.base_lambda).zip(&self.slip_dlambda) {
                *l = l0 + d;
            }
            let system = self.inner.system();
            // The holding elements' forces under these; a failure is Newton's on every element
            // to report.
            if solve_friction(system, t, v, (qdd, lambda), &mut self.terms, &mut self.work).is_err() {
                return Ok(false);
            }
            // (F1) at the loads found, into `forces` (overwritten after the evaluation).
            let (mut change, mut scale) = (0.0f64, 0.0f64);
            let frictions = system.frictions();
            for (k, term) in self.terms[..self.frictions].iter().enumerate() {
                scale = scale.max(term.force.abs());
                if let (true, Mode::Slip(sign)) = (term.given, term.mode) {
                    let sign = term.along.unwrap_or(sign);
                    let limit = frictions[k]
                        .load_limit
                        .map_or(0.0, |l| self.terms[self.frictions + l].force);
                    let next = slip_force(&frictions[k], sign, term.row.dot(v), lambda, limit);
                    change = change.max((next - term.force).abs());
                    scale = scale.max(next.abs());
                    self.forces[k] = next;
                }
            }
            if !change.is_finite() {
                return Ok(false);
            }
            // The forces of this iterate `F` are kept, so `v̇`, `λ` are theirs; their error is
            // within `|φ(F) − F| / (1 − ρ)` for the contraction `ρ < 1/2`: settled when that
            // change is within `SLIP_TOLERANCE` of the largest force.
            if change <= SLIP_TOLERANCE * scale {
                return Ok(true);
            }
            if last.is_finite() && change >= 0.5 * last {
                return Ok(false);
            }
            self.mix_slipping(last.is_finite());
            last = change;
        }
        Ok(false)
    }

    /// The slipping elements' next forces from this iterate's `F` (their forces) and `φ(F)` (in
    /// `forces`), and the last iterate's (in `mix`, when `secant`): Anderson's mixing of depth
    /// one, `F⁺ = φ(F) − θ (φ(F) − φ(F′))` with `θ` the least-squares combination of the two
    /// residuals `r = φ(F) − F` (`θ = r·Δr / |Δr|²`, `Δr = r − r′`), which takes out the slowest
    /// direction of the contraction (`docs/friction.md`, "Cost"); the plain iteration
    /// `F⁺ = φ(F)` at the first iterate. Keeps `F` and `φ(F)` in `mix`.
    fn mix_slipping(&mut self, secant: bool) {
        let theta = if secant {
            let (mut num, mut den) = (0.0, 0.0);
            for ((term, &next), &(before, next_before)) in
                self.terms[..self.frictions].iter().zip(&self.forces).zip(&self.mix)
            {
                if term.given {
                    let (r, r_before) = (next - term.force, next_before - before);
                    num += r * (r - r_before);
                    den += (r - r_before) * (r - r_before);
                }
            }
            // A contraction below one half has `θ = −ρ / (1 − ρ)` within (−1, 1).
            let theta = num / den;
            if theta.is_finite() {
                theta.clamp(-1.0, 1.0)
            } else {
                0.0
            }
        } else {
            0.0
        };
        for ((term, &next), mix) in self.terms[..self.frictions]
            .iter_mut()
            .zip(&self.forces)
            .zip(&mut self.mix)
        {
            if term.given {
                let next_before = mix.1;
                *mix = (term.force, next);
                term.force = next - if secant { theta * (next - next_before) } else { 0.0 };
            }
        }
    }

    /// Limit element `k` leaves its bound at `(t, q, v)` (it rebounds, or is let go): its event
    /// function is raised by what it lacks of [`LIMIT_SLACK`] there, so that it starts above zero
    /// and a return to the bound within the next step changes its sign. The function at the
    /// located event is zero to the location's round-off (measured −7e-15 to +4e-15 rad on a
    /// chain with pin friction), so the bound moves by as little; a limit held for a while has
    /// drifted past its bound by the integration's error (its rate is held, not its position:
    /// 2e-12 m, measured on a box's corner), by which it is raised, up to [`RAISED_MOST`]. A
    /// function left below zero would cross it at the start of the next step, as the corner
    /// rises, and take the location from a crossing the step holds after it (two other corners
    /// of the box landing: they went through the floor).
    fn leave_bound(&mut self, k: usize, t: f64, q: &[f64], v: &[f64]) {
        let l = k - self.frictions;
        let s = self.fill_row(k, t, q, v);
        let below = LIMIT_SLACK - self.inner.system().limits()[l].free_event(s);
        self.raised[l] = below.clamp(0.0, RAISED_MOST);
    }

    /// Evaluates at `(t, q, v)` into the event buffers, for the elements' holding forces
    /// (`terms[k].hold`).
    fn evaluate_holds(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), DynamicsError> {
        let mut qdd = std::mem::take(&mut self.event_qdd);
        let mut lambda = std::mem::take(&mut self.event_lambda);
        let result = self.accelerations(t, q, v, None, &mut qdd, &mut lambda);
        self.event_qdd = qdd;
        self.event_lambda = lambda;
        result
    }

    /// Lets go, after an event, of the held limits whose holding force pulls at the state it
    /// leaves ((L2) of `docs/limits.md`): their event function, `σ F_hold + adhesion`, starts
    /// the next step negative, so no crossing would end the hold, and a limit whose law gives
    /// it no force while it pulls would stay held however far its body moved off the bound
    /// (a box's corner lifted 8 cm was held there once another corner landed). Released
    /// together, then the holds found again, until none pulls. True where one was let go.
    fn release_pulling(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<bool, DynamicsError> {
        let mut released = false;
        for _ in self.frictions..self.terms.len() {
            if !self.terms[self.frictions..]
                .iter()
                .any(|term| matches!(term.mode, Mode::Held(_)))
            {
                break;
            }
            // The evaluation here must not take the first iterate of an element that has just
            // come to stick from the step that follows.
            for k in 0..self.frictions {
                self.fresh_kept[k] = self.terms[k].fresh;
            }
            let result = self.evaluate_holds(t, q, v);
            for k in 0..self.frictions {
                self.terms[k].fresh = self.fresh_kept[k];
            }
            result?;
            let mut any = false;
            for k in self.frictions..self.terms.len() {
                if let Mode::Held(sign) = self.terms[k].mode {
                    if self.held_event(k, sign) < 0.0 {
                        self.terms[k].mode = Mode::Free;
                        self.leave_bound(k, t, q, v);
                        any = true;
                    }
                }
            }
            if !any {
                break;
            }
            self.follow_contacts(t, q, v);
            released = true;
        }
        Ok(released)
    }

    /// A held limit's event function ((L2) of `docs/limits.md`): its holding force along the
    /// bound's push, less the pull it may take and stay held; negative where it pulls.
    fn held_event(&self, k: usize, sign: f64) -> f64 {
        sign * self.terms[k].hold + self.work.adhesion
    }

    /// [`Formulation::accelerations`] with `lambda` the multipliers extended by the system's
    /// reaction loads (`m + loads` of them).
    fn evaluate(
        &mut self,
        (t, q, qd): (f64, &[f64], &[f64]),
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let m = self.m;
        self.inner.accelerations(t, q, qd, baumgarte, qdd, &mut lambda[..m])?;
        if self.loads > 0 {
            (self.inner.system()).reaction_loads(t, q, qd, qdd, false, &mut lambda[m..]);
        }
        if self.terms.is_empty() {
            return Ok(());
        }
        if !self.started {
            self.start_events(t, q, qd);
        }
        for k in 0..self.terms.len() {
            let s = self.fill_row(k, t, q, qd);
            if self.refuse_impacts && k >= self.frictions {
                let limit = &self.inner.system().limits()[k - self.frictions];
                if self.terms[k].mode != Mode::Free || limit.free_event(s) <= LIMIT_SLACK {
                    return Err(DynamicsError::Limit {
                        time: t,
                        element: format!("{} '{}'", limit.element, limit.name),
                        what: format!(
                            "reaches its limits [{}, {}] (at {s}), and {}",
                            limit.lower, limit.upper, self.refusal
                        ),
                    });
                }
            }
            // A slipping element's force is found by the iteration on them all (no response).
            if !matches!(self.terms[k].mode, Mode::Free | Mode::Slip(_)) {
                self.response(k, (t, q, qd), baumgarte, (qdd, lambda))?;
            }
        }
        self.steer_cones(qd);
        self.base_qdd.copy_from_slice(qdd);
        self.base_lambda.copy_from_slice(lambda);
        let slipping = self.terms[..self.frictions]
            .iter()
            .any(|term| matches!(term.mode, Mode::Slip(_)));
        self.predict(t);
        let found = slipping && !self.newton_until_event && self.slipping((t, q, qd), qdd, lambda)?;
        // Once the iteration on the slipping forces gives up, Newton's method decides until the
        // next event: where redundant holds (four corners of a face) split their forces, the
        // two ways find different splits, and a right-hand side that changed way from one
        // evaluation to the next collapsed the adaptive steps (docs/limits.md, (L14)).
        self.newton_until_event |= slipping && !found;
        if !found {
            // Newton's method on every element: each slipping one's response too.
            for k in 0..self.frictions {
                if matches!(self.terms[k].mode, Mode::Slip(_)) {
                    self.response_from_base(k, (t, q, qd), baumgarte)?;
                }
            }
            qdd.copy_from_slice(&self.base_qdd);
            lambda.copy_from_slice(&self.base_lambda);
            solve_friction(
                self.inner.system(),
                t,
                qd,
                (qdd, lambda),
                &mut self.terms,
                &mut self.work,
            )?;
        }
        for (f, k) in self.forces.iter_mut().zip(&self.terms) {
            *f = k.force;
        }
        for term in &mut self.terms[..self.frictions] {
            term.fresh = false;
        }
        self.record(t);
        Ok(())
    }
}

/// The most iterations of [`Frictional::slipping`] (each contracts by half or more).
const SLIP_ITERATIONS: usize = 40;

/// The change `|φ(F) − F|` of the slipping elements' forces, relative to the largest force, at
/// which [`Frictional::slipping`] keeps `F` (its error is within twice that).
const SLIP_TOLERANCE: f64 = 1e-13;

/// How near its bound (m or rad) a limit counts as at it, to round-off: a free limit this near
/// that does not move towards it is held through an impact where the strikes would drive it in
/// ((L9) of `docs/limits.md`), and a limit that starts this near is raised by what it lacks of
/// the slack. Far above the round-off of a coordinate, far below any gap a run resolves. (Free
/// limits moving towards their bounds join a strike from [`LAND_TOGETHER`].)
const STRIKE_TOGETHER: f64 = 1e-12;

/// How near its bound (m or rad) a free limit moving towards it strikes with another that
/// strikes ([`Frictional::at_event`], (L9) of `docs/limits.md`): the ends of a bar dropped level
/// land together, though a run's state holds them level only to its integration's error (at
/// dopri5 1e-11, 10⁻¹¹ of a metre); struck one after the other, the first end's friction
/// impulse turns the bar, and runs whose states differ at that level (the formulations) do not
/// agree on the order. Far below any gap a run resolves; a limit struck this early is held
/// where it is, at most this far off its bound.
const LAND_TOGETHER: f64 = 1e-10;

/// The most a limit's event function is raised by where it leaves its bound
/// ([`Frictional::leave_bound`]), m or rad: far above a held limit's drift off its bound, far
/// below any gap a run resolves.
const RAISED_MOST: f64 = 1e-9;

/// The rate (m/s or rad/s) below which a limit that starts at its bound and moves away from it
/// starts held: round-off of a rate that is zero (a cam's surface sliding along its follower).
const START_RATE: f64 = 1e-12;

/// The coordinate of `limit` (read within a turn as `raw`) at a start: within half a turn of
/// `last` if that lies within the bounds, else the nearest turn of it that does, else `raw`
/// followed from `last`.
fn start_turn(limit: &crate::JointLimit, last: f64, raw: f64) -> f64 {
    let near = unwrap_angle(last, raw);
    let inside = |s: f64| s >= limit.lower && s <= limit.upper;
    if inside(near) {
        return near;
    }
    let turn = std::f64::consts::TAU;
    (1..4)
        .flat_map(|k| [near - k as f64 * turn, near + k as f64 * turn])
        .find(|&s| inside(s))
        .unwrap_or(near)
}

/// Limit `limit`'s coordinate from the system's value `raw`: followed from `last` across half
/// turns when the system measures it within a turn, and recorded in `last`.
fn follow(limit: &crate::JointLimit, last: &mut f64, raw: f64) -> f64 {
    *last = if limit.within_turn {
        unwrap_angle(*last, raw)
    } else {
        raw
    };
    *last
}

impl Formulation for Frictional {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn system(&self) -> &dyn MultibodySystem {
        self.inner.system()
    }

    fn begin_step(&mut self) {
        self.inner.begin_step();
    }

    /// `v̇₀`, `λ₀` without friction and limits; each element's response to a unit force along
    /// it (not a free limit's: it has no force); then (F1)–(F3) of `docs/friction.md` and
    /// (L1)–(L2) of `docs/limits.md`. Where the system has reaction loads (a tree in joint
    /// coordinates), the friction reads them after the multipliers.
    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        if self.loads == 0 {
            return self.evaluate((t, q, qd), baumgarte, qdd, lambda);
        }
        let mut ext = std::mem::take(&mut self.ext);
        let result = self.evaluate((t, q, qd), baumgarte, qdd, &mut ext);
        lambda.copy_from_slice(&ext[..self.m]);
        self.ext = ext;
        result
    }

    fn residuals(&mut self, t: f64, q: &[f64], qd: &[f64], c: &mut [f64], cdot: &mut [f64]) {
        self.inner.residuals(t, q, qd, c, cdot);
    }

    fn project(&mut self, t: f64, q: &mut [f64], qd: &mut [f64], tolerance: f64) -> Result<usize, DynamicsError> {
        self.inner.project(t, q, qd, tolerance)
    }

    fn stats(&self) -> FormulationStats {
        self.inner.stats()
    }

    /// The inner formulation's where there is no friction and every limit is held free (the run
    /// stops where one is reached: [`Frictional::refusing_impacts`]): the implicit methods then
    /// integrate the inner index-3 system. False otherwise: that system holds no friction and no
    /// impacts.
    fn is_index3_augmented(&self) -> bool {
        self.refuse_impacts && self.frictions == 0 && self.inner.is_index3_augmented()
    }

    fn set_extra_force(&mut self, extra: Option<&[f64]>) -> bool {
        self.inner.set_extra_force(extra)
    }

    /// The inner formulation's, while every element is a free limit: the last evaluation was then
    /// the inner one's alone, with its factorization (a run's sensitivities, which stop where a
    /// limit is reached). False with friction or a held limit.
    fn linear_response(
        &mut self,
        t: f64,
        g: &[f64],
        h: &[f64],
        dqdd: &mut [f64],
        dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        if self.frictions > 0 || self.terms.iter().any(|term| term.mode != Mode::Free) {
            return Ok(false);
        }
        self.inner.linear_response(t, g, h, dqdd, dlambda)
    }

    /// Each friction element's mode from its slip rate at `(q, v)`: stuck within its stick
    /// speed, otherwise slipping in the rate's direction. Each limit is free, or held where it
    /// starts at a bound (within [`LIMIT_SLACK`]) not moving away from it.
    fn start_events(&mut self, t: f64, q: &[f64], v: &[f64]) {
        self.newton_until_event = false;
        let system = self.inner.system();
        for (k, (term, spec)) in self.terms.iter_mut().zip(system.frictions()).enumerate() {
            system.slip_row(k, t, q, v, &mut term.row);
            term.mode = Mode::at(term.row.dot(v), spec.stick_speed);
            term.fresh = term.mode == Mode::Stick;
        }
        for k in 0..self.frictions {
            if let Some(p) = self.cone_of(k).filter(|&p| p > k) {
                self.set_cone((k, p), self.cone_rate((k, p), v));
            }
        }
        let system = self.inner.system();
        let limits = &mut self.terms[self.frictions..];
        for (k, (term, limit)) in limits.iter_mut().zip(system.limits()).enumerate() {
            // The start is where a coordinate measured within a turn is followed from: the turn
            // nearest the last one that lies within the bounds (a joint's range may pass ±π).
            let raw = system.limit_row(k, t, q, v, &mut term.row);
            let s = if limit.within_turn {
                start_turn(limit, self.coordinates[k], raw)
            } else {
                raw
            };
            self.coordinates[k] = s;
            self.times = (f64::NAN, f64::NAN);
            // A start at a bound to round-off, as where it leaves one ([`Frictional::leave_bound`]).
            self.raised[k] = (LIMIT_SLACK - limit.free_event(s)).clamp(0.0, STRIKE_TOGETHER);
            let sign = limit.nearer_bound(s);
            let at_bound = limit.free_event(s) <= 2.0 * LIMIT_SLACK;
            // Not moving away (to round-off: a cam's surface slides along the follower).
            term.mode = if at_bound && sign * term.row.dot(v) <= START_RATE {
                Mode::Held(sign)
            } else {
                Mode::Free
            };
        }
        self.started = true;
        self.follow_contacts(t, q, v);
    }

    /// The system's event functions, with each friction element's [`Mode::event`] first, then
    /// each limit's: a free limit's distance to its nearer bound ([`crate::JointLimit::free_event`]),
    /// a held one's force `σ F` (one evaluation of the formulation).
    fn events(&mut self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        if !self.started {
            self.start_events(t, q, v);
        }
        let system = self.inner.system();
        system.events(t, q, v, out);
        for (k, (term, spec)) in self.terms.iter_mut().zip(system.frictions()).enumerate() {
            if let Some(slot) = out.get_mut(k) {
                system.slip_row(k, t, q, v, &mut term.row);
                *slot = term.mode.event(term.row.dot(v), spec.stick_speed);
            }
        }
        self.cone_events(v, out);
        let held = self.terms[self.frictions..]
            .iter()
            .any(|t| matches!(t.mode, Mode::Held(_)));
        if held {
            // An evaluation that fails leaves the held limits' functions as they were; the
            // step's own evaluation reports the failure.
            if self.evaluate_holds(t, q, v).is_err() {
                return;
            }
        }
        let system = self.inner.system();
        let first = self.frictions;
        for (k, limit) in system.limits().iter().enumerate() {
            let Some(slot) = out.get_mut(first + k) else { break };
            match self.terms[first + k].mode {
                Mode::Held(sign) => *slot = self.held_event(first + k, sign),
                _ => {
                    let raw = system.limit_row(k, t, q, v, &mut self.terms[first + k].row);
                    *slot = limit.free_event(follow(limit, &mut self.coordinates[k], raw)) + self.raised[k];
                }
            }
        }
    }

    /// False for a stuck friction element that its friction could not hold at the last
    /// evaluation ((F3), which is (F1) in the direction it slips): the law does not change where
    /// its rate leaves the stick speed.
    fn event_needs_location(&self, i: usize) -> bool {
        match self.terms.get(i) {
            Some(term) if i < self.frictions => {
                // A cone slips along both rows: either may carry its direction.
                let direction =
                    term.direction != 0.0 || self.cone_of(i).is_some_and(|p| self.terms[p].direction != 0.0);
                !(term.mode == Mode::Stick && !term.sticks && direction)
            }
            _ => true,
        }
    }

    /// A slipping friction element's: a hundredth of the margin its rate passes zero by
    /// ([`Mode::event`]: `10⁻³ w_s`), so that a step ended at its event has the rate past zero by
    /// 0.99 to 1.01 thousandths of the stick speed, which the impulse at the event takes back
    /// (the impulse stands for the slip's friction over the time the location leaves, to first
    /// order). Every other function's is the default.
    fn event_tolerance(&self, i: usize) -> f64 {
        match (self.inner.system().frictions().get(i), self.terms.get(i)) {
            (Some(spec), Some(term)) if matches!(term.mode, Mode::Slip(_)) => 1e-2 * SLIP_END * spec.stick_speed,
            _ => 1e-14,
        }
    }

    /// The modes whose events changed sign over the step (`crossed`, the first functions are the
    /// friction elements'): a stuck joint whose rate left its stick speed slips in the rate's
    /// direction; a slip whose rate reached zero (to the location's round-off) has it set to
    /// zero by the impulse `P = −w / (g·A)` along its slip row, `v ← v + A P` (the response to a
    /// force is also the response to an impulse, and keeps the constraints' velocities zero),
    /// then sticks if its friction can hold it and otherwise reverses (`docs/friction.md`,
    /// "Events").
    fn at_event(&mut self, t: f64, q: &[f64], v: &mut [f64], crossed: &[bool]) -> Result<bool, DynamicsError> {
        // The forces jump at an event: no line through them.
        self.times = (f64::NAN, f64::NAN);
        self.newton_until_event = false;
        let mut changed = false;
        for k in 0..self.terms.len().min(crossed.len()) {
            if !crossed[k] {
                continue;
            }
            match self.terms[k].mode {
                // A rigid contact's friction while the contact is free: no event.
                Mode::Free if k < self.frictions => continue,
                Mode::Free => {
                    // Struck together after the loop (L9).
                    self.striking.push(k);
                    continue;
                }
                Mode::Held(_) => {
                    // Its force reached zero: the joint leaves the bound (a contact's friction
                    // with it).
                    self.terms[k].mode = Mode::Free;
                    self.leave_bound(k, t, q, v);
                    self.follow_contacts(t, q, v);
                    changed = true;
                    continue;
                }
                Mode::Stick | Mode::Slip(_) => changed = true,
            }
            let cone = self.cone_of(k).map(|p| (k, p));
            match (self.terms[k].mode, cone) {
                (Mode::Stick, Some(pair)) => {
                    // Its slip left the stick speed: it slips along the slip velocity, whose
                    // size is the stick speed to the location's round-off (either side of it).
                    self.fill_row(k, t, q, v);
                    self.fill_row(pair.1, t, q, v);
                    self.slip_cone(pair, self.cone_rate(pair, v));
                }
                (Mode::Stick, None) => {
                    self.inner.system().slip_row(k, t, q, v, &mut self.terms[k].row);
                    self.terms[k].mode = Mode::Slip(self.terms[k].row.dot(v).signum());
                }
                (Mode::Slip(sign), Some(pair)) => {
                    // Stopped (its slip velocity within the stick speed), or turned past a right
                    // angle from its reference direction, which then turns with it.
                    self.fill_row(k, t, q, v);
                    self.fill_row(pair.1, t, q, v);
                    let w = self.cone_rate(pair, v);
                    if w.0.hypot(w.1) > self.inner.system().frictions()[k].stick_speed {
                        self.set_cone(pair, w);
                    } else if let Mode::Slip(other) = self.terms[pair.1].mode {
                        self.stopping.push((k, sign));
                        self.stopping.push((pair.1, other));
                    }
                }
                (Mode::Slip(sign), None) => self.stopping.push((k, sign)),
                (Mode::Free | Mode::Held(_), _) => {}
            }
        }
        if !self.striking.is_empty() {
            // The free limits within `LAND_TOGETHER` of their bounds strike with them (where
            // they move towards them): corners that land together to within the integration's
            // error.
            for k in self.frictions..self.terms.len() {
                if self.terms[k].mode == Mode::Free && !self.striking.contains(&k) {
                    let s = self.fill_row(k, t, q, v);
                    let limit = &self.inner.system().limits()[k - self.frictions];
                    if limit.free_event(s) <= LIMIT_SLACK + LAND_TOGETHER {
                        self.striking.push(k);
                    }
                }
            }
            let struck = self.impact(t, q, v);
            for i in 0..self.striking.len() {
                let k = self.striking[i];
                if self.terms[k].mode == Mode::Free {
                    // It rebounds.
                    self.leave_bound(k, t, q, v);
                }
            }
            self.striking.clear();
            changed |= struck?;
        }
        if !self.stopping.is_empty() {
            // The slips that stop at this event, together (two corners of a block sliding on a
            // floor stop at once), with every other slip already within its stick speed: the
            // impulse that stops one moves the others' contact points too, and one left just past
            // its stop would start the next step with its event already passed.
            self.join_stopping(t, q, v);
            self.stop_slips(t, q, v)?;
            for &(k, sign) in &self.stopping {
                // A cone its friction cannot hold stays stuck: (F3) slips it against the force
                // that would hold it, and its event turns it to slip along the slip velocity
                // once that leaves the stick speed (a direction from a rate of zero would be
                // round-off).
                if !self.terms[k].sticks && self.inner.system().frictions()[k].cone.is_none() {
                    // It slips on where (F3) says: nearly always back (−σ).
                    let direction = self.terms[k].direction;
                    self.terms[k].mode = Mode::Slip(if direction != 0.0 { direction } else { -sign });
                }
            }
            self.stopping.clear();
        }
        changed |= self.release_pulling(t, q, v)?;
        Ok(changed)
    }

    fn friction_forces(&self) -> &[f64] {
        &self.forces[..self.frictions]
    }

    fn limit_forces(&self) -> &[f64] {
        &self.forces[self.frictions..]
    }

    fn impact_loss(&self) -> f64 {
        self.impact_loss
    }
}
