//! The classic fourth-order Runge–Kutta method on `y = [q; v]`, fixed step: four evaluations per
//! step, slow energy drift.

use super::first_order::derivative;
use crate::registry::{no_advice, Applies, MethodEntry, TradeAxis};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper, TangentField};
use crate::{IntegrationError, Method};
use dalembert_system::{Baumgarte, Formulation};

/// The registry entry.
pub(crate) static ENTRY: MethodEntry = MethodEntry {
    name: "rk4",
    aliases: &[],
    summary: "classic Runge-Kutta: order 4, four evaluations per step",
    order: 4,
    control: StepControl::Fixed,
    keeps_constraints: false,
    applies: Applies::AnyFormulation,
    parameters: &[],
    trade: TradeAxis::Steps,
    advice: no_advice,
    build,
};

impl Method {
    /// Classic fourth-order Runge–Kutta, fixed step.
    pub fn rk4() -> Self {
        Method::of(&ENTRY)
    }
}

struct Rk4 {
    k: [Vec<f64>; 4],
    y_tmp: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    baumgarte: Option<Baumgarte>,
    /// The stage derivatives of each tangent the run carries (sized at its first step).
    tk: Vec<[Vec<f64>; 4]>,
    /// A tangent at a stage.
    s_tmp: Vec<f64>,
}

/// The stages' times (fractions of the step), each stage's state `y + C[i] h k[i − 1]`.
const C: [f64; 4] = [0.0, 0.5, 0.5, 1.0];

fn build(_: &Method, s: Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError> {
    let len = s.y0.len();
    Ok(Box::new(Rk4 {
        k: std::array::from_fn(|_| vec![0.0; len]),
        y_tmp: vec![0.0; len],
        qdd: vec![0.0; len - s.n_q],
        lambda: vec![0.0; s.formulation.system().num_equations()],
        baumgarte: s.baumgarte,
        tk: Vec::new(),
        s_tmp: vec![0.0; len],
    }))
}

impl Rk4 {
    /// One step, with the tangents `tangents` carries when given: each stage's tangent
    /// derivative right after the stage, combined with the same weights. Returns whether the
    /// tangents were carried through every stage.
    fn run(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
        mut tangents: Option<&mut dyn TangentField>,
    ) -> Result<bool, IntegrationError> {
        let count = tangents.as_ref().map_or(0, |field| field.count());
        if self.tk.len() < count {
            // The first step of a run with tangents.
            let len = y.len();
            self.tk.resize_with(count, || std::array::from_fn(|_| vec![0.0; len]));
        }
        let Rk4 {
            k,
            y_tmp,
            qdd,
            lambda,
            baumgarte,
            tk,
            s_tmp,
        } = self;
        let b = *baumgarte;
        let mut carried = tangents.is_some();
        for stage in 0..4 {
            let ts = t + C[stage] * h;
            let (done, rest) = k.split_at_mut(stage);
            let at: &[f64] = if stage == 0 {
                y
            } else {
                let previous = &done[stage - 1];
                for i in 0..y.len() {
                    y_tmp[i] = y[i] + C[stage] * h * previous[i];
                }
                y_tmp
            };
            derivative(f, ts, at, b, qdd, lambda, &mut rest[0])?;
            if let (true, Some(field)) = (carried, tangents.as_deref_mut()) {
                if stage == 0 && !field.begin(f, t, y)? {
                    carried = false;
                    continue;
                }
                for (j, tkj) in tk.iter_mut().enumerate().take(count) {
                    let (done, rest) = tkj.split_at_mut(stage);
                    let s = field.tangent(j);
                    match done.last() {
                        None => s_tmp.copy_from_slice(s),
                        Some(previous) => {
                            for i in 0..s.len() {
                                s_tmp[i] = s[i] + C[stage] * h * previous[i];
                            }
                        }
                    }
                    if !field.derivative(f, j, ts, at, b, (qdd, lambda), s_tmp, &mut rest[0])? {
                        carried = false;
                        break;
                    }
                }
            }
        }
        let [k1, k2, k3, k4] = k;
        for i in 0..y.len() {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        if let (true, Some(field)) = (carried, tangents) {
            for (j, [k1, k2, k3, k4]) in tk.iter().enumerate().take(count) {
                let s = field.tangent(j);
                for i in 0..s.len() {
                    s_tmp[i] = s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
                field.stepped(j, t, h, y, s_tmp);
            }
        }
        Ok(carried)
    }
}

impl Stepper for Rk4 {
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
