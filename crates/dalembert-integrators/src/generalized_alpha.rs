//! Generalized-α on the index-3 form (Arnold & Brüls, *Multibody Syst. Dyn.* 18, 2007):
//!
//! ```text
//! q_{n+1} = q_n + h q̇_n + h²(½ − β) a_n + h² β a_{n+1}
//! q̇_{n+1} = q̇_n + h(1 − γ) a_n + h γ a_{n+1}
//! (1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) q̈_{n+1} + α_f q̈_n
//! M(q) q̈ + C_qᵀ λ = Q_e(q, q̇, t),   C(q, t) = 0            at t_{n+1}
//! ```
//!
//! with `α_m = (2ρ∞ − 1)/(ρ∞ + 1)`, `α_f = ρ∞/(ρ∞ + 1)`, `γ = ½ + α_f − α_m`, `β = ¼(γ + ½)²`:
//! second order, unconditionally stable, numerical damping of the highest frequencies set by the
//! spectral radius at infinity `ρ∞ ∈ [0, 1]`. Newton iterates on `(q̈_{n+1}, λ_{n+1})` with
//!
//! ```text
//! [ M + β' K + γ' D   C_qᵀ ] [Δq̈]     [ M q̈ + C_qᵀ λ − Q_e ]
//! [ C_q               0    ] [Δλ] = − [ C / β'              ]
//! ```
//!
//! `β' = h² β (1 − α_f)/(1 − α_m)`, `γ' = h γ (1 − α_f)/(1 − α_m)`, `K = ∂(M q̈ + C_qᵀ λ − Q_e)/∂q`,
//! `D = −∂Q_e/∂q̇`. `K` and `D` are formed by finite differences of the residual (the documented
//! fallback; analytic force and constraint Jacobians are future work). The positions satisfy
//! `C = 0` to the Newton tolerance at every step: no drift. On Newton failure the step is halved
//! (down to the minimum step) and grows back after successful steps.
//!
//! This method always solves the index-3 system of the model; the formulation supplies the initial
//! accelerations and the accelerations and multipliers reported at the output times.

use dalembert_constraints::{ConstraintValues, Model};
use dalembert_kinematics::MassMatrix;
use faer::linalg::solvers::Solve;
use faer::Mat;

/// Coefficients of the method for a spectral radius `ρ∞`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Coefficients {
    alpha_m: f64,
    alpha_f: f64,
    gamma: f64,
    beta: f64,
}

impl Coefficients {
    pub fn new(rho_inf: f64) -> Self {
        let r = rho_inf.clamp(0.0, 1.0);
        let alpha_m = (2.0 * r - 1.0) / (r + 1.0);
        let alpha_f = r / (r + 1.0);
        let gamma = 0.5 + alpha_f - alpha_m;
        let beta = 0.25 * (gamma + 0.5).powi(2);
        Coefficients {
            alpha_m,
            alpha_f,
            gamma,
            beta,
        }
    }
}

/// State carried between steps: the pseudo-acceleration `a` and the last `q̈`, `λ`.
pub(crate) struct GeneralizedAlpha {
    coef: Coefficients,
    a: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    mass: MassMatrix,
    values: ConstraintValues,
    /// Newton tolerance on the position update and on `‖C‖∞`.
    pub tolerance: f64,
    /// Newton iterations spent (cumulative).
    pub iterations: u64,
    /// Iteration-matrix factorizations (cumulative).
    pub factorizations: u64,
    /// Residual evaluations (cumulative).
    pub evaluations: u64,
}

/// Newton did not converge (or produced non-finite values) within the iteration limit.
pub(crate) struct NotConverged;

impl GeneralizedAlpha {
    /// Starts from consistent `q̈₀`, `λ₀` (from the formulation).
    pub fn new(model: &Model, rho_inf: f64, qdd0: &[f64], lambda0: &[f64], q0: &[f64]) -> Self {
        GeneralizedAlpha {
            coef: Coefficients::new(rho_inf),
            a: qdd0.to_vec(),
            qdd: qdd0.to_vec(),
            lambda: lambda0.to_vec(),
            mass: model.mass_matrix(q0),
            values: model.constraints().values(),
            tolerance: 1e-10,
            iterations: 0,
            factorizations: 0,
            evaluations: 0,
        }
    }

    /// Positions and velocities for a trial `q̈_{n+1}`.
    fn predict(&self, h: f64, q: &[f64], qd: &[f64], qdd_new: &[f64], q_out: &mut [f64], qd_out: &mut [f64]) {
        let c = self.coef;
        for i in 0..q.len() {
            let a_new =
                ((1.0 - c.alpha_f) * qdd_new[i] + c.alpha_f * self.qdd[i] - c.alpha_m * self.a[i]) / (1.0 - c.alpha_m);
            q_out[i] = q[i] + h * qd[i] + h * h * ((0.5 - c.beta) * self.a[i] + c.beta * a_new);
            qd_out[i] = qd[i] + h * ((1.0 - c.gamma) * self.a[i] + c.gamma * a_new);
        }
    }

    /// `r = M q̈ + C_qᵀ λ − Q_e` and `C / β'` at `(t, q, q̇)`; refreshes `self.values`.
    fn residual(
        &mut self,
        model: &Model,
        t: f64,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        lambda: &[f64],
        bp: f64,
        out: &mut [f64],
    ) {
        self.evaluations += 1;
        let n = q.len();
        let (r, c) = out.split_at_mut(n);
        model.applied_forces(t, q, qd, r);
        r.iter_mut().for_each(|v| *v = -*v);
        self.mass.update(model.bodies(), q);
        self.mass.mul_add(1.0, qdd, r);
        let sys = model.constraints();
        sys.evaluate(t, q, qd, &mut self.values);
        sys.jacobian_transpose_mul_add(&self.values, 1.0, lambda, r);
        for (ci, v) in c.iter_mut().zip(&self.values.c) {
            *ci = v / bp;
        }
    }

    /// One step from `(t, q, q̇)` to `t + h`; on success `q`, `qd` hold the new state.
    pub fn step(&mut self, model: &Model, t: f64, h: f64, q: &mut [f64], qd: &mut [f64]) -> Result<(), NotConverged> {
        const MAX_ITERATIONS: usize = 12;
        let n = q.len();
        let m = self.lambda.len();
        let c = self.coef;
        let bp = h * h * c.beta * (1.0 - c.alpha_f) / (1.0 - c.alpha_m);
        let gp = h * c.gamma * (1.0 - c.alpha_f) / (1.0 - c.alpha_m);
        let t1 = t + h;
        let mut qdd = self.qdd.clone();
        let mut lam = self.lambda.clone();
        let (mut q1, mut qd1) = (vec![0.0; n], vec![0.0; n]);
        let mut res = vec![0.0; n + m];
        let mut lu = None;
        for it in 0..MAX_ITERATIONS {
            self.predict(h, q, qd, &qdd, &mut q1, &mut qd1);
            self.residual(model, t1, &q1, &qd1, &qdd, &lam, bp, &mut res);
            if res.iter().any(|v| !v.is_finite()) {
                return Err(NotConverged);
            }
            if lu.is_none() || it == 3 {
                lu = Some(
                    self.iteration_matrix(model, t1, &q1, &qd1, &qdd, &lam, bp, gp)
                        .partial_piv_lu(),
                );
                self.factorizations += 1;
            }
            let Some(f) = &lu else { return Err(NotConverged) };
            let rhs = Mat::from_fn(n + m, 1, |i, _| -res[i]);
            let dx = f.solve(&rhs);
            self.iterations += 1;
            let mut dq = 0.0f64;
            for i in 0..n {
                qdd[i] += dx[(i, 0)];
                dq = dq.max((bp * dx[(i, 0)]).abs());
            }
            for j in 0..m {
                lam[j] += dx[(n + j, 0)];
            }
            if !dq.is_finite() {
                return Err(NotConverged);
            }
            let qscale = 1.0 + q1.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if dq <= self.tolerance * qscale {
                self.predict(h, q, qd, &qdd, &mut q1, &mut qd1);
                model.constraints().evaluate(t1, &q1, &qd1, &mut self.values);
                let cmax = self.values.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                if cmax <= self.tolerance {
                    // Accept: advance a, q̈, λ.
                    for i in 0..n {
                        self.a[i] = ((1.0 - c.alpha_f) * qdd[i] + c.alpha_f * self.qdd[i] - c.alpha_m * self.a[i])
                            / (1.0 - c.alpha_m);
                    }
                    self.qdd = qdd;
                    self.lambda = lam;
                    q.copy_from_slice(&q1);
                    qd.copy_from_slice(&qd1);
                    return Ok(());
                }
            }
        }
        Err(NotConverged)
    }

    /// `[M + β'K + γ'D, C_qᵀ; C_q, 0]`, with `K` and `D` by central finite differences of the
    /// residual.
    fn iteration_matrix(
        &mut self,
        model: &Model,
        t: f64,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        lam: &[f64],
        bp: f64,
        gp: f64,
    ) -> Mat<f64> {
        let n = q.len();
        let m = lam.len();
        let mut k = Mat::<f64>::zeros(n + m, n + m);
        self.mass.update(model.bodies(), q);
        for (b, blk) in self.mass.blocks().iter().enumerate() {
            for r in 0..3 {
                for cc in 0..3 {
                    k[(3 * b + r, 3 * b + cc)] = blk[(r, cc)];
                }
            }
        }
        let mut rp = vec![0.0; n + m];
        let mut rm = vec![0.0; n + m];
        let (mut qp, mut qdp) = (q.to_vec(), qd.to_vec());
        for j in 0..n {
            // K column j (position), scaled by β'.
            let hq = 1e-7 * (1.0 + q[j].abs());
            qp[j] = q[j] + hq;
            self.residual(model, t, &qp, qd, qdd, lam, 1.0, &mut rp);
            qp[j] = q[j] - hq;
            self.residual(model, t, &qp, qd, qdd, lam, 1.0, &mut rm);
            qp[j] = q[j];
            for i in 0..n {
                k[(i, j)] += bp * (rp[i] - rm[i]) / (2.0 * hq);
            }
            // D column j (velocity), scaled by γ'.
            let hv = 1e-7 * (1.0 + qd[j].abs());
            qdp[j] = qd[j] + hv;
            self.residual(model, t, q, &qdp, qdd, lam, 1.0, &mut rp);
            qdp[j] = qd[j] - hv;
            self.residual(model, t, q, &qdp, qdd, lam, 1.0, &mut rm);
            qdp[j] = qd[j];
            for i in 0..n {
                k[(i, j)] += gp * (rp[i] - rm[i]) / (2.0 * hv);
            }
        }
        let sys = model.constraints();
        sys.evaluate(t, q, qd, &mut self.values);
        for (&(r, c), &v) in sys.pattern().iter().zip(&self.values.jacobian) {
            k[(n + r, c)] += v;
            k[(c, n + r)] += v;
        }
        k
    }
}
