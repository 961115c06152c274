//! Semi-implicit (symplectic) Euler, fixed step, first order:
//! `vₙ₊₁ = vₙ + h v̇(tₙ, qₙ, vₙ)`, `qₙ₊₁ = qₙ ⊕ h vₙ₊₁`
//! ([`dalembert_system::MultibodySystem::integrate_positions`], `q + h v` for planar bodies).
//! One evaluation per step; bounded energy error on unconstrained or independent coordinates.

use crate::registry::{no_advice, Applies, MethodEntry, TradeAxis};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper, TangentField};
use crate::{IntegrationError, Method};
use dalembert_system::{Baumgarte, Formulation};

/// The registry entry.
pub(crate) static ENTRY: MethodEntry = MethodEntry {
    name: "symplectic-euler",
    aliases: &["euler"],
    summary: "semi-implicit (symplectic) Euler: order 1, one evaluation per step, bounded energy error",
    order: 1,
    control: StepControl::Fixed,
    keeps_constraints: false,
    applies: Applies::AnyFormulation,
    parameters: &[],
    trade: TradeAxis::Steps,
    advice: no_advice,
    build,
};

impl Method {
    /// Semi-implicit (symplectic) Euler, fixed step.
    pub fn symplectic_euler() -> Self {
        Method::of(&ENTRY)
    }
}

struct SymplecticEuler {
    n_q: usize,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    baumgarte: Option<Baumgarte>,
    /// A tangent at the step's start, and its derivative there.
    s0: Vec<f64>,
    ks: Vec<f64>,
    /// Each tangent at the step's end (sized at the first step of a run with tangents).
    s_new: Vec<Vec<f64>>,
    /// The two sides' positions and velocities of a tangent.
    q_side: [Vec<f64>; 2],
    v_side: Vec<f64>,
}

fn build(_: &Method, s: Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError> {
    let n_v = s.y0.len() - s.n_q;
    Ok(Box::new(SymplecticEuler {
        n_q: s.n_q,
        qdd: vec![0.0; n_v],
        lambda: vec![0.0; s.formulation.system().num_equations()],
        baumgarte: s.baumgarte,
        s0: vec![0.0; s.y0.len()],
        ks: vec![0.0; s.y0.len()],
        s_new: Vec::new(),
        q_side: [vec![0.0; s.n_q], vec![0.0; s.n_q]],
        v_side: vec![0.0; n_v],
    }))
}

impl SymplecticEuler {
    /// `v ← v + h v̇(q, v)`, `q ← q ⊕ h v`; with `tangents`, each tangent carried along: its
    /// velocity part by the derivative of `v̇` (solved with the evaluation's factorization), its
    /// position part by central differences of `q ⊕ h v` along the tangent, with the tangent's
    /// own change. Returns whether the tangents were carried.
    fn run(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
        tangents: Option<&mut dyn TangentField>,
    ) -> Result<bool, IntegrationError> {
        let n_q = self.n_q;
        {
            let (q, qd) = y.split_at(n_q);
            f.accelerations(t, q, qd, self.baumgarte, &mut self.qdd, &mut self.lambda)?;
        }
        let Some(field) = tangents else {
            self.advance(f, h, y);
            return Ok(false);
        };
        let carried = self.tangents(f, t, h, y, &mut *field)?;
        self.advance(f, h, y);
        if carried {
            for (j, s) in self.s_new.iter().enumerate().take(field.count()) {
                field.stepped(j, t, h, y, s);
            }
        }
        Ok(carried)
    }

    /// The run's own step, from the accelerations evaluated.
    fn advance(&self, f: &dyn Formulation, h: f64, y: &mut [f64]) {
        let (q, qd) = y.split_at_mut(self.n_q);
        for (v, a) in qd.iter_mut().zip(&self.qdd) {
            *v += h * a;
        }
        f.system().integrate_positions(q, qd, h);
    }

    /// Each tangent at the step's end, into `s_new`, from the state `y` at its start.
    fn tangents(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &[f64],
        field: &mut dyn TangentField,
    ) -> Result<bool, IntegrationError> {
        let (n_q, count) = (self.n_q, field.count());
        if self.s_new.len() < count {
            self.s_new.resize_with(count, || vec![0.0; y.len()]);
        }
        if !field.begin(f, t, y)? {
            return Ok(false);
        }
        let (q, v) = y.split_at(n_q);
        for j in 0..count {
            self.s0.copy_from_slice(field.tangent(j));
            let solution = (&self.qdd[..], &self.lambda[..]);
            if !field.derivative(f, j, t, y, self.baumgarte, solution, &self.s0, &mut self.ks)? {
                return Ok(false);
            }
            let (s, delta) = (&self.s0, field.delta(j));
            let s_new = &mut self.s_new[j];
            for i in n_q..y.len() {
                s_new[i] = s[i] + h * self.ks[i];
            }
            for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
                let side = &mut self.q_side[k];
                for i in 0..n_q {
                    side[i] = q[i] + sign * delta * s[i];
                }
                for i in 0..v.len() {
                    self.v_side[i] = v[i] + h * self.qdd[i] + sign * delta * s_new[n_q + i];
                }
                f.system().integrate_positions(side, &self.v_side, h);
            }
            let [plus, minus] = &self.q_side;
            for i in 0..n_q {
                s_new[i] = (plus[i] - minus[i]) / (2.0 * delta);
            }
        }
        Ok(true)
    }
}

impl Stepper for SymplecticEuler {
    fn step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<StepOutcome, IntegrationError> {
        self.run(f, t, h, y, None)?;
        Ok(StepOutcome::taken(h))
    }

    fn step_tangents(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
        tangents: &mut dyn TangentField,
    ) -> Result<Option<StepOutcome>, IntegrationError> {
        self.run(f, t, h, y, Some(tangents))?;
        Ok(Some(StepOutcome::taken(h)))
    }
}
