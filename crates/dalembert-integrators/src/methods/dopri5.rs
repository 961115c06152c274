//! Dormand–Prince 5(4) with first-same-as-last, a PI step-size controller and Hairer's
//! fourth-order continuous extension for output between steps (Hairer, Nørsett & Wanner,
//! *Solving ODEs I*, §II.5–II.6).

use super::first_order::derivative;
use crate::registry::{no_advice, positive, Applies, MethodEntry, Parameter, TradeAxis};
use crate::stepper::{Setup, StepControl, StepOutcome, Stepper, TangentField};
use crate::{IntegrationError, Method};
use dalembert_system::{Baumgarte, Formulation};

/// The registry entry.
pub(crate) static ENTRY: MethodEntry = MethodEntry {
    name: "dopri5",
    aliases: &["dormand-prince"],
    summary: "Dormand-Prince 5(4): adaptive, PI step control, dense output of order 4",
    order: 5,
    control: StepControl::Adaptive,
    keeps_constraints: false,
    applies: Applies::AnyFormulation,
    parameters: &[
        Parameter {
            key: "rtol",
            default: 1e-8,
            doc: "relative tolerance of the local error",
            valid: positive,
            expected: "must be positive",
        },
        Parameter {
            key: "atol",
            default: 1e-10,
            doc: "absolute tolerance of the local error",
            valid: positive,
            expected: "must be positive",
        },
    ],
    trade: TradeAxis::Tolerances(&["rtol", "atol"]),
    advice: no_advice,
    build,
};

impl Method {
    /// Dormand–Prince 5(4), adaptive, with dense output at the output times.
    pub fn dopri5(rtol: f64, atol: f64) -> Self {
        let mut m = Method::of(&ENTRY);
        m.set(0, rtol);
        m.set(1, atol);
        m
    }
}

fn build(m: &Method, s: Setup<'_>) -> Result<Box<dyn Stepper>, IntegrationError> {
    let (rtol, atol) = (m.value(0), m.value(1));
    let n_v = s.y0.len() - s.n_q;
    let lambda = s.formulation.system().num_equations();
    Ok(Box::new(Stepping {
        dp: Dopri5::new(s.n_q, n_v, lambda, rtol, atol),
        baumgarte: s.baumgarte,
    }))
}

/// The method with the run's Baumgarte gains.
struct Stepping {
    dp: Dopri5,
    baumgarte: Option<Baumgarte>,
}

impl Stepper for Stepping {
    fn step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<StepOutcome, IntegrationError> {
        let (a, _) = self.dp.attempt(f, t, h, y, self.baumgarte, None)?;
        let accepted = a.error <= 1.0;
        if accepted {
            self.dp.accept(h, a.error, y);
        }
        Ok(StepOutcome {
            accepted,
            error: a.error,
            next_step: a.next_step,
        })
    }

    /// The step with the tangents carried through its stages; they do not take part in the
    /// error control (the run's steps are the state's, `docs/sensitivities.md`).
    fn step_tangents(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
        tangents: &mut dyn TangentField,
    ) -> Result<Option<StepOutcome>, IntegrationError> {
        let (a, carried) = self.dp.attempt(f, t, h, y, self.baumgarte, Some(&mut *tangents))?;
        let accepted = a.error <= 1.0;
        if accepted {
            self.dp.accept(h, a.error, y);
            if carried {
                self.dp.accept_tangents(t, h, y, tangents);
            }
        }
        Ok(Some(StepOutcome {
            accepted,
            error: a.error,
            next_step: a.next_step,
        }))
    }

    fn step_unchecked(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &mut [f64],
    ) -> Result<bool, IntegrationError> {
        let (a, _) = self.dp.attempt(f, t, h, y, self.baumgarte, None)?;
        if !a.error.is_finite() {
            return Ok(false);
        }
        self.dp.accept(h, a.error.min(1.0), y);
        Ok(true)
    }

    fn interpolate(&self, theta: f64, out: &mut [f64]) {
        self.dp.interpolate(theta, out);
    }

    fn interpolate_tangent(&self, j: usize, theta: f64, out: &mut [f64]) -> bool {
        match self.dp.tangent_cont.get(j) {
            Some(cont) if self.dp.tangents_carried => {
                interpolate(cont, theta, out);
                true
            }
            _ => false,
        }
    }

    /// The stored last stage stays valid after a normalization (it moves `q` by the order of the
    /// local error); a projection moves it further and invalidates it.
    fn state_changed(&mut self) {
        self.dp.invalidate();
    }
}

const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
/// Error coefficients `b − b̂`.
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];
/// Dense-output coefficients.
const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// Storage and controller state of the Dormand–Prince method.
struct Dopri5 {
    k: [Vec<f64>; 7],
    y_new: Vec<f64>,
    y_tmp: Vec<f64>,
    /// Continuous-extension coefficients of the last accepted step.
    cont: [Vec<f64>; 5],
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    rtol: f64,
    atol: f64,
    previous_error: f64,
    /// `k[0]` holds `f(t, y)` for the current `y` (first same as last).
    fsal_valid: bool,
    /// Each tangent's stage derivatives and the continuous-extension coefficients of its last
    /// carried step (sized at the first step of a run with tangents).
    tangent_k: Vec<[Vec<f64>; 7]>,
    tangent_cont: Vec<[Vec<f64>; 5]>,
    /// A tangent at a stage.
    s_tmp: Vec<f64>,
    /// `tangent_k[j][0]` holds the tangents' derivative at the current `y` (first same as last).
    tangent_fsal: bool,
    /// True when the last accepted step carried the tangents (their dense output is valid).
    tangents_carried: bool,
}

/// Outcome of one attempted step.
struct Attempt {
    /// Scaled error norm (accept when ≤ 1).
    pub error: f64,
    /// Proposed next step.
    pub next_step: f64,
}

impl Dopri5 {
    pub fn new(n_q: usize, n_v: usize, m: usize, rtol: f64, atol: f64) -> Self {
        let len = n_q + n_v;
        Dopri5 {
            k: std::array::from_fn(|_| vec![0.0; len]),
            y_new: vec![0.0; len],
            y_tmp: vec![0.0; len],
            cont: std::array::from_fn(|_| vec![0.0; len]),
            qdd: vec![0.0; n_v],
            lambda: vec![0.0; m],
            rtol,
            atol,
            previous_error: 1e-4,
            fsal_valid: false,
            tangent_k: Vec::new(),
            tangent_cont: Vec::new(),
            s_tmp: vec![0.0; len],
            tangent_fsal: false,
            tangents_carried: false,
        }
    }

    /// Marks the stored derivative stale (after the state was changed from outside, e.g. projected).
    pub fn invalidate(&mut self) {
        self.fsal_valid = false;
        self.tangent_fsal = false;
    }

    /// The tangents' derivatives at stage `s` (state `at`, time `ts`), right after the run's
    /// evaluation there: each tangent's stage value `S + h Σ A[s][l] K_l` and its derivative.
    /// Returns false where the field cannot.
    #[allow(clippy::too_many_arguments)]
    fn tangent_stage(
        &mut self,
        f: &mut dyn Formulation,
        field: &mut dyn TangentField,
        s: usize,
        (ts, h): (f64, f64),
        at: &[f64],
        stab: Option<Baumgarte>,
    ) -> Result<bool, IntegrationError> {
        let Dopri5 {
            tangent_k,
            s_tmp,
            qdd,
            lambda,
            ..
        } = self;
        for (j, k) in tangent_k.iter_mut().enumerate().take(field.count()) {
            let start = field.tangent(j);
            for i in 0..s_tmp.len() {
                let mut acc = 0.0;
                for l in 0..s {
                    acc += A[s][l] * k[l][i];
                }
                s_tmp[i] = start[i] + h * acc;
            }
            if !field.derivative(f, j, ts, at, stab, (qdd, lambda), s_tmp, &mut k[s])? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// After [`Dopri5::accept`] of a step whose stages carried the tangents: each tangent at the
    /// step's end (handed to the field), its continuous extension, and its last stage kept as the
    /// next step's first.
    pub fn accept_tangents(&mut self, t: f64, h: f64, y: &[f64], field: &mut dyn TangentField) {
        for j in 0..field.count() {
            let (k, cont) = (&mut self.tangent_k[j], &mut self.tangent_cont[j]);
            let start = field.tangent(j);
            for i in 0..start.len() {
                let mut acc = 0.0;
                for l in 0..6 {
                    acc += A[6][l] * k[l][i];
                }
                self.s_tmp[i] = start[i] + h * acc;
            }
            extension(cont, h, k, start, &self.s_tmp);
            k.swap(0, 6);
            field.stepped(j, t, h, y, &self.s_tmp);
        }
        self.tangent_fsal = true;
        self.tangents_carried = true;
    }

    /// Attempts a step of size `h` from `(t, y)`; the candidate is kept until [`Dopri5::accept`].
    ///
    /// With `tangents`, each stage's tangents are carried right after its evaluation
    /// ([`Dopri5::tangent_stage`]); returns whether they were carried through every stage.
    pub fn attempt(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        h: f64,
        y: &[f64],
        stab: Option<Baumgarte>,
        mut tangents: Option<&mut dyn TangentField>,
    ) -> Result<(Attempt, bool), IntegrationError> {
        let len = y.len();
        let count = tangents.as_ref().map_or(0, |field| field.count());
        if self.tangent_k.len() < count {
            // The first step of a run with tangents.
            self.tangent_k
                .resize_with(count, || std::array::from_fn(|_| vec![0.0; len]));
            self.tangent_cont
                .resize_with(count, || std::array::from_fn(|_| vec![0.0; len]));
            self.tangent_fsal = false;
        }
        let mut carried = tangents.is_some();
        let fresh = !self.fsal_valid;
        if fresh || (carried && !self.tangent_fsal) {
            // The tangents' first stage needs the factorization at `(t, y)`: evaluated again
            // there when the run's first stage was kept (outputs evaluate in between).
            let out = if fresh { &mut self.k[0] } else { &mut self.y_new };
            derivative(f, t, y, stab, &mut self.qdd, &mut self.lambda, out)?;
            self.fsal_valid = true;
            if let Some(field) = tangents.as_deref_mut() {
                carried = field.begin(f, t, y)? && self.tangent_stage(f, field, 0, (t, h), y, stab)?;
                self.tangent_fsal = carried;
            }
        }
        for s in 1..7 {
            for i in 0..len {
                let mut acc = 0.0;
                for j in 0..s {
                    acc += A[s][j] * self.k[j][i];
                }
                self.y_tmp[i] = y[i] + h * acc;
            }
            let (done, rest) = self.k.split_at_mut(s);
            let _ = done;
            derivative(
                f,
                t + C[s] * h,
                &self.y_tmp,
                stab,
                &mut self.qdd,
                &mut self.lambda,
                &mut rest[0],
            )?;
            if let (true, Some(field)) = (carried, tangents.as_deref_mut()) {
                let y_tmp = std::mem::take(&mut self.y_tmp);
                let stage = self.tangent_stage(f, field, s, (t + C[s] * h, h), &y_tmp, stab);
                self.y_tmp = y_tmp;
                carried = stage?;
            }
            if s == 6 {
                self.y_new.copy_from_slice(&self.y_tmp);
            }
        }
        self.tangent_fsal &= carried;
        // Error estimate, scaled by atol + rtol·max(|y|, |y_new|), RMS norm.
        let mut sum = 0.0;
        for i in 0..len {
            let mut e = 0.0;
            for s in 0..7 {
                e += E[s] * self.k[s][i];
            }
            let sc = self.atol + self.rtol * y[i].abs().max(self.y_new[i].abs());
            sum += (h * e / sc).powi(2);
        }
        let error = (sum / len as f64).sqrt();
        // PI controller (α = 0.7/5, β = 0.4/5), factors clamped to [0.2, 5].
        let next_step = if error <= 1.0 {
            let fac = 0.9 * error.max(1e-10).powf(-0.14) * self.previous_error.powf(0.08);
            h * fac.clamp(0.2, 5.0)
        } else {
            h * (0.9 * error.powf(-0.2)).clamp(0.2, 1.0)
        };
        if !error.is_finite() {
            let failed = Attempt {
                error: f64::INFINITY,
                next_step: 0.2 * h,
            };
            return Ok((failed, false));
        }
        Ok((Attempt { error, next_step }, carried))
    }

    /// Accepts the last attempt: prepares dense output over `[t, t + h]` and moves `y` forward.
    /// The tangents' first stage and dense output are stale until [`Dopri5::accept_tangents`].
    pub fn accept(&mut self, h: f64, error: f64, y: &mut [f64]) {
        extension(&mut self.cont, h, &self.k, y, &self.y_new);
        y.copy_from_slice(&self.y_new);
        // First same as last: the last stage is f at the new point.
        self.k.swap(0, 6);
        self.previous_error = error.max(1e-4);
        self.tangent_fsal = false;
        self.tangents_carried = false;
    }

    /// Dense output at fraction `theta ∈ [0, 1]` of the last accepted step.
    pub fn interpolate(&self, theta: f64, out: &mut [f64]) {
        interpolate(&self.cont, theta, out);
    }
}

/// The continuous-extension coefficients of a step of size `h` from `y` to `y_new` with stage
/// derivatives `k` (Hairer, Nørsett & Wanner's dense output of order 4).
fn extension(cont: &mut [Vec<f64>; 5], h: f64, k: &[Vec<f64>; 7], y: &[f64], y_new: &[f64]) {
    let [c1, c2, c3, c4, c5] = cont;
    for i in 0..y.len() {
        let diff = y_new[i] - y[i];
        let bspl = h * k[0][i] - diff;
        c1[i] = y[i];
        c2[i] = diff;
        c3[i] = bspl;
        c4[i] = diff - h * k[6][i] - bspl;
        let mut d = 0.0;
        for s in 0..7 {
            d += D[s] * k[s][i];
        }
        c5[i] = h * d;
    }
}

/// The continuous extension `cont` at fraction `theta` of its step.
fn interpolate(cont: &[Vec<f64>; 5], theta: f64, out: &mut [f64]) {
    let t1 = 1.0 - theta;
    let [c1, c2, c3, c4, c5] = cont;
    for i in 0..out.len() {
        out[i] = c1[i] + theta * (c2[i] + t1 * (c3[i] + theta * (c4[i] + t1 * c5[i])));
    }
}
