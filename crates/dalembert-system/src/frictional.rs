//! Any formulation with joint friction ([`Frictional`], `docs/friction.md`): the formulation's
//! frictionless accelerations, its response to a unit force in each friction element, and the
//! stick–slip law of [`crate::friction`] on top. One code for every formulation.

use crate::friction::{solve_friction, FrictionTerms, FrictionWork, Mode};
use crate::{Baumgarte, DynamicsError, Formulation, FormulationStats, MultibodySystem};

/// A formulation whose system has joint friction ([`MultibodySystem::frictions`]).
///
/// Each evaluation costs one evaluation of the inner formulation plus, per friction element, a
/// solve with its factorization (its response to a unit friction force); nothing is allocated
/// after setup.
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
        let (n, m, count) = {
            let s = inner.system();
            (s.layout().n_v(), s.num_equations(), s.frictions().len())
        };
        if count > 0 && !inner.set_extra_force(None) {
            return Err(DynamicsError::Friction {
                time: 0.0,
                joint: inner.system().frictions()[0].name.clone(),
                what: format!(
                    "the {} formulation solves this model without forces added to it (a tree in joint \
                     coordinates): use absolute coordinates",
                    inner.name()
                ),
            });
        }
        Ok(Frictional {
            inner,
            terms: (0..count).map(|_| FrictionTerms::new(n, m)).collect(),
            work: FrictionWork::new(count, m),
            forces: vec![0.0; count],
            dense: vec![0.0; n],
            qdd: vec![0.0; n],
            lambda: vec![0.0; m],
            event_qdd: vec![0.0; n],
            event_lambda: vec![0.0; m],
            started: false,
        })
    }
}

impl Formulation for Frictional {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn system(&self) -> &dyn MultibodySystem {
        self.inner.system()
    }

    /// `v̇₀`, `λ₀` without friction; the response `A_k`, `Λ_k` to a unit force along `g_k` from
    /// the formulation's factorization ([`Formulation::force_response`]), or else from a second
    /// evaluation with a force `s g_k` added (`s` the largest multiplier or 1, so that the
    /// difference keeps its digits), divided by `s`; then (F1)–(F3) of `docs/friction.md`.
    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.inner.accelerations(t, q, qd, baumgarte, qdd, lambda)?;
        if self.terms.is_empty() {
            return Ok(());
        }
        if !self.started {
            self.start_events(t, q, qd);
        }
        let scale = lambda.iter().fold(1.0f64, |a, l| a.max(l.abs()));
        for k in 0..self.terms.len() {
            self.inner.system().slip_row(k, t, q, qd, &mut self.terms[k].row);
            self.terms[k].row.write_dense(&mut self.dense);
            let term = &mut self.terms[k];
            if self
                .inner
                .force_response(t, &self.dense, &mut term.dv, &mut term.dlambda)?
            {
                continue;
            }
            self.dense.iter_mut().for_each(|g| *g *= scale);
            self.inner.set_extra_force(Some(&self.dense));
            let solved = self
                .inner
                .accelerations(t, q, qd, baumgarte, &mut self.qdd, &mut self.lambda);
            self.inner.set_extra_force(None);
            solved?;
            let term = &mut self.terms[k];
            for ((r, a), a0) in term.dv.iter_mut().zip(&self.qdd).zip(qdd.iter()) {
                *r = (a - a0) / scale;
            }
            for ((r, l), l0) in term.dlambda.iter_mut().zip(&self.lambda).zip(lambda.iter()) {
                *r = (l - l0) / scale;
            }
        }
        solve_friction(
            self.inner.system(),
            t,
            qd,
            (qdd, lambda),
            &mut self.terms,
            &mut self.work,
        )?;
        for (f, k) in self.forces.iter_mut().zip(&self.terms) {
            *f = k.force;
        }
        Ok(())
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

    /// False: the implicit methods integrate the frictionless index-3 system themselves, which
    /// holds no friction.
    fn is_index3_augmented(&self) -> bool {
        false
    }

    fn set_extra_force(&mut self, extra: Option<&[f64]>) -> bool {
        self.inner.set_extra_force(extra)
    }

    /// Each element's mode from its slip rate at `(q, v)`: stuck within its stick speed,
    /// otherwise slipping in the rate's direction.
    fn start_events(&mut self, t: f64, q: &[f64], v: &[f64]) {
        let system = self.inner.system();
        for (k, (term, spec)) in self.terms.iter_mut().zip(system.frictions()).enumerate() {
            system.slip_row(k, t, q, v, &mut term.row);
            term.mode = Mode::at(term.row.dot(v), spec.stick_speed);
        }
        self.started = true;
    }

    /// The system's event functions, with each friction element's [`Mode::event`] first.
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
    }

    /// The modes whose events changed sign over the step (`crossed`, the first functions are the
    /// friction elements'): a stuck joint whose rate left its stick speed slips in the rate's
    /// direction; a slip whose rate reached zero (to the location's round-off) has it set to
    /// zero by the impulse `P = −w / (g·A)` along its slip row, `v ← v + A P` (the response to a
    /// force is also the response to an impulse, and keeps the constraints' velocities zero),
    /// then sticks if its friction can hold it and otherwise reverses (`docs/friction.md`,
    /// "Events").
    fn at_event(&mut self, t: f64, q: &[f64], v: &mut [f64], crossed: &[bool]) -> Result<bool, DynamicsError> {
        let mut changed = false;
        for k in 0..self.terms.len().min(crossed.len()) {
            if !crossed[k] {
                continue;
            }
            changed = true;
            let sign = match self.terms[k].mode {
                Mode::Stick => {
                    self.inner.system().slip_row(k, t, q, v, &mut self.terms[k].row);
                    self.terms[k].mode = Mode::Slip(self.terms[k].row.dot(v).signum());
                    continue;
                }
                Mode::Slip(sign) => sign,
            };
            let mut qdd = std::mem::take(&mut self.event_qdd);
            let mut lambda = std::mem::take(&mut self.event_lambda);
            let result = self.accelerations(t, q, v, None, &mut qdd, &mut lambda);
            let sticks = result.and_then(|()| {
                let term = &mut self.terms[k];
                let impulse = -term.row.dot(v) / term.row.dot(&term.dv);
                v.iter_mut().zip(&term.dv).for_each(|(x, r)| *x += r * impulse);
                term.mode = Mode::Stick;
                self.accelerations(t, q, v, None, &mut qdd, &mut lambda)?;
                Ok(self.terms[k].sticks)
            });
            self.event_qdd = qdd;
            self.event_lambda = lambda;
            if !sticks? {
                // It slips on where (F3) says: nearly always back (−σ).
                let direction = self.terms[k].direction;
                self.terms[k].mode = Mode::Slip(if direction != 0.0 { direction } else { -sign });
            }
        }
        Ok(changed)
    }

    fn friction_forces(&self) -> &[f64] {
        &self.forces
    }
}
