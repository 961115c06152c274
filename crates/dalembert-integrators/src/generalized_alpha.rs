//! Generalized-α on the index-3 form (Arnold & Brüls, *Multibody Syst. Dyn.* 18, 2007):
//!
//! ```text
//! q_{n+1} = q_n ⊕ h Δq_n,   Δq_n = v_n + h(½ − β) a_n + h β a_{n+1}
//! v_{n+1} = v_n + h(1 − γ) a_n + h γ a_{n+1}
//! (1 − α_m) a_{n+1} + α_m a_n = (1 − α_f) q̈_{n+1} + α_f q̈_n
//! M(q) q̈ + C_qᵀ λ = Q_e(q, q̇, t),   C(q, t) = 0            at t_{n+1}
//! ```
//!
//! with `α_m = (2ρ∞ − 1)/(ρ∞ + 1)`, `α_f = ρ∞/(ρ∞ + 1)`, `γ = ½ + α_f − α_m`, `β = ¼(γ + ½)²`:
//! second order, unconditionally stable, numerical damping of the highest frequencies set by the
//! spectral radius at infinity `ρ∞ ∈ [0, 1]`. `q ⊕ h Δq` is the system's position update
//! ([`MultibodySystem::integrate_positions`]): `q + h Δq` for planar bodies, and for Euler parameters
//! with angular velocities the Lie-group form of Brüls, Cardona & Arnold (*Mech. Mach. Theory* 48,
//! 2012), which keeps the method's second order. Newton iterates on `(q̈_{n+1}, λ_{n+1})` with
//!
//! ```text
//! [ M + β' K + γ' D   C_qᵀ ] [Δq̈]     [ M q̈ + C_qᵀ λ − Q_e ]
//! [ C_q               0    ] [Δλ] = − [ C / β'              ]
//! ```
//!
//! `β' = h² β (1 − α_f)/(1 − α_m)`, `γ' = h γ (1 − α_f)/(1 − α_m)`, `K = ∂(M q̈ + C_qᵀ λ − Q_e)/∂q`,
//! `D = −∂Q_e/∂v` (`∂/∂q` along the velocity coordinates: `q ⊕ ε e_j`). `K` and `D` are formed by finite differences of the residual (the documented
//! fallback; analytic force and constraint Jacobians are future work), and the factored matrix is
//! reused across steps of the same size (modified Newton) until it has served 20 steps or Newton
//! contracts slowly. Newton stops when the position update and `‖C‖∞` are below the tolerance
//! **and** the acceleration update is below 1e-10 of the acceleration scale (or has stalled at the
//! round-off floor of `C/β'`, below 1e-6 of it): a test on the positions alone (`β' ∝ h²`) accepts
//! one inexact iteration at small steps, and the velocity error then grows as `1/h`
//! (`tests/ga_order_small_steps.rs`: second order from h = 3.2e-4 down to 1e-5). The positions satisfy `C = 0` to the Newton tolerance at every step: no drift. On Newton failure the step is halved
//! (down to the minimum step) and grows back after successful steps.
//!
//! This method always solves the index-3 system of the model; the formulation supplies the initial
//! accelerations and the accelerations and multipliers reported at the output times.

use dalembert_system::linalg::DenseLu;
use dalembert_system::{BlockDiagonal, ConstraintValues, MultibodySystem};

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
    mass: BlockDiagonal,
    values: ConstraintValues,
    work: Work,
    /// Step size the current iteration matrix was built for (NaN: none), and how many steps it
    /// has served: the matrix is kept across steps (modified Newton) and rebuilt when the step
    /// changes, after `MATRIX_LIFETIME` steps, or when Newton has not converged in 3 iterations.
    matrix_h: f64,
    matrix_age: u32,
    /// Newton tolerance on the position update and on `‖C‖∞`.
    pub tolerance: f64,
    /// Newton iterations spent (cumulative).
    pub iterations: u64,
    /// Iteration-matrix factorizations (cumulative).
    pub factorizations: u64,
    /// Residual evaluations (cumulative).
    pub evaluations: u64,
}

/// Storage allocated once: trial state, residuals, the iteration matrix and its LU.
struct Work {
    qdd: Vec<f64>,
    lam: Vec<f64>,
    q1: Vec<f64>,
    qd1: Vec<f64>,
    /// `Δq_n` of the position update, and a unit velocity for the position perturbations.
    delta: Vec<f64>,
    unit: Vec<f64>,
    res: Vec<f64>,
    rp: Vec<f64>,
    rm: Vec<f64>,
    qp: Vec<f64>,
    qdp: Vec<f64>,
    dx: Vec<f64>,
    /// The iteration matrix and its LU (the seam's dense LU, storage held).
    lu: DenseLu,
}

impl Work {
    fn new(n_q: usize, n: usize, m: usize) -> Self {
        let k = n + m;
        Work {
            qdd: vec![0.0; n],
            lam: vec![0.0; m],
            q1: vec![0.0; n_q],
            qd1: vec![0.0; n],
            delta: vec![0.0; n],
            unit: vec![0.0; n],
            res: vec![0.0; k],
            rp: vec![0.0; k],
            rm: vec![0.0; k],
            qp: vec![0.0; n_q],
            qdp: vec![0.0; n],
            dx: vec![0.0; k],
            lu: DenseLu::new(k, 1),
        }
    }
}

/// Newton did not converge (or produced non-finite values) within the iteration limit.
pub(crate) struct NotConverged;

impl GeneralizedAlpha {
    /// Starts from consistent `q̈₀`, `λ₀` (from the formulation).
    pub fn new(model: &dyn MultibodySystem, rho_inf: f64, qdd0: &[f64], lambda0: &[f64], q0: &[f64]) -> Self {
        let mut mass = model.mass_storage();
        model.mass(q0, &mut mass);
        GeneralizedAlpha {
            coef: Coefficients::new(rho_inf),
            a: qdd0.to_vec(),
            qdd: qdd0.to_vec(),
            lambda: lambda0.to_vec(),
            mass,
            values: model.constraints().values(),
            work: Work::new(q0.len(), qdd0.len(), lambda0.len()),
            tolerance: 1e-10,
            iterations: 0,
            factorizations: 0,
            matrix_h: f64::NAN,
            matrix_age: 0,
            evaluations: 0,
        }
    }

    /// Positions and velocities for the trial `q̈_{n+1}` in `work.qdd` (into `work.q1`, `work.qd1`).
    fn predict(&mut self, model: &dyn MultibodySystem, h: f64, q: &[f64], qd: &[f64]) {
        let c = self.coef;
        let w = &mut self.work;
        for i in 0..qd.len() {
            let a_new =
                ((1.0 - c.alpha_f) * w.qdd[i] + c.alpha_f * self.qdd[i] - c.alpha_m * self.a[i]) / (1.0 - c.alpha_m);
            w.delta[i] = qd[i] + h * ((0.5 - c.beta) * self.a[i] + c.beta * a_new);
            w.qd1[i] = qd[i] + h * ((1.0 - c.gamma) * self.a[i] + c.gamma * a_new);
        }
        w.q1.copy_from_slice(q);
        model.integrate_positions(&mut w.q1, &w.delta, h);
    }

    /// `r = M q̈ + C_qᵀ λ − Q_e` and `C / β'` at `(t, q, q̇)`; refreshes `mass` and `values`.
    #[allow(clippy::too_many_arguments)]
    fn residual(
        mass: &mut BlockDiagonal,
        values: &mut ConstraintValues,
        model: &dyn MultibodySystem,
        t: f64,
        (q, qd): (&[f64], &[f64]),
        (qdd, lambda): (&[f64], &[f64]),
        bp: f64,
        out: &mut [f64],
    ) {
        let (r, c) = out.split_at_mut(qd.len());
        model.applied_forces(t, q, qd, r);
        r.iter_mut().for_each(|v| *v = -*v);
        model.mass(q, mass);
        mass.mul_add(1.0, qdd, r);
        let sys = model.constraints();
        sys.evaluate(t, q, qd, values);
        sys.jacobian_transpose_mul_add(values, 1.0, lambda, r);
        for (ci, v) in c.iter_mut().zip(&values.c) {
            *ci = v / bp;
        }
    }

    /// One step from `(t, q, q̇)` to `t + h`; on success `q`, `qd` hold the new state.
    pub fn step(
        &mut self,
        model: &dyn MultibodySystem,
        t: f64,
        h: f64,
        q: &mut [f64],
        qd: &mut [f64],
    ) -> Result<(), NotConverged> {
        const MAX_ITERATIONS: usize = 12;
        // Relative acceleration update at convergence, and the level below which an update that
        // no longer halves counts as converged to round-off.
        const ACCELERATION_TOLERANCE: f64 = 1e-10;
        const STALL_FLOOR: f64 = 1e-6;
        let mut last_rel = f64::INFINITY;
        let mut last_contraction = 0.0f64;
        let n = qd.len();
        let m = self.lambda.len();
        let c = self.coef;
        let bp = h * h * c.beta * (1.0 - c.alpha_f) / (1.0 - c.alpha_m);
        let gp = h * c.gamma * (1.0 - c.alpha_f) / (1.0 - c.alpha_m);
        let t1 = t + h;
        self.work.qdd.copy_from_slice(&self.qdd);
        self.work.lam.copy_from_slice(&self.lambda);
        const MATRIX_LIFETIME: u32 = 20;
        // Reuse the last iteration matrix when it was built for this step size (modified Newton).
        let mut fresh = false;
        if self.matrix_h != h || self.matrix_age >= MATRIX_LIFETIME {
            self.matrix_h = f64::NAN;
        }
        for it in 0..MAX_ITERATIONS {
            self.predict(model, h, q, qd);
            let w = &mut self.work;
            Self::residual(
                &mut self.mass,
                &mut self.values,
                model,
                t1,
                (&w.q1, &w.qd1),
                (&w.qdd, &w.lam),
                bp,
                &mut w.res,
            );
            self.evaluations += 1;
            if w.res.iter().any(|v| !v.is_finite()) {
                self.matrix_h = f64::NAN;
                return Err(NotConverged);
            }
            // An old matrix that contracts slowly (the update shrank by less than half in the last
            // iteration) is rebuilt after three iterations, any old matrix after six.
            if self.matrix_h.is_nan() || (!fresh && ((it >= 3 && last_contraction > 0.5) || it == 6)) {
                self.factor_iteration_matrix(model, t1, bp, gp);
                self.factorizations += 1;
                self.matrix_h = h;
                self.matrix_age = 0;
                fresh = true;
            }
            let w = &mut self.work;
            for (d, r) in w.dx.iter_mut().zip(&w.res) {
                *d = -r;
            }
            w.lu.solve_vec(&mut w.dx);
            self.iterations += 1;
            let mut dq = 0.0f64;
            let mut da = 0.0f64;
            for i in 0..n {
                w.qdd[i] += w.dx[i];
                dq = dq.max((bp * w.dx[i]).abs());
                da = da.max(w.dx[i].abs());
            }
            // The acceleration update relative to the acceleration scale: the velocities move by
            // γ' Δq̈ and the positions by β' Δq̈, so a test on the positions alone (β' ∝ h²) stops
            // after one inexact iteration at small steps, and the error then grows as 1/h.
            let ascale = 1.0 + w.qdd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let rel = da / ascale;
            // Converged, or stalled at the round-off floor of the index-3 residual (C/β' carries
            // the round-off of C amplified by 1/h²): no further progress is possible there.
            let accurate = rel <= ACCELERATION_TOLERANCE || (it > 0 && rel <= STALL_FLOOR && rel >= 0.5 * last_rel);
            last_contraction = rel / last_rel;
            last_rel = rel;
            for j in 0..m {
                w.lam[j] += w.dx[n + j];
            }
            if !dq.is_finite() {
                self.matrix_h = f64::NAN;
                return Err(NotConverged);
            }
            let qscale = 1.0 + w.q1.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if dq <= self.tolerance * qscale && accurate {
                self.predict(model, h, q, qd);
                let w = &self.work;
                model.constraints().evaluate(t1, &w.q1, &w.qd1, &mut self.values);
                let cmax = self.values.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                if cmax <= self.tolerance {
                    // Accept: advance a, q̈, λ.
                    for i in 0..n {
                        self.a[i] = ((1.0 - c.alpha_f) * w.qdd[i] + c.alpha_f * self.qdd[i] - c.alpha_m * self.a[i])
                            / (1.0 - c.alpha_m);
                    }
                    self.qdd.copy_from_slice(&w.qdd);
                    self.lambda.copy_from_slice(&w.lam);
                    q.copy_from_slice(&w.q1);
                    model.normalize(q);
                    qd.copy_from_slice(&w.qd1);
                    self.matrix_age += 1;
                    return Ok(());
                }
            }
        }
        self.matrix_h = f64::NAN;
        Err(NotConverged)
    }

    /// Builds `[M + β'K + γ'D, C_qᵀ; C_q, 0]` at the trial state in `work` (with `K` and `D` by
    /// central finite differences of the residual) and factors it in place.
    fn factor_iteration_matrix(&mut self, model: &dyn MultibodySystem, t: f64, bp: f64, gp: f64) {
        let w = &mut self.work;
        let n = w.qd1.len();
        let mut k = w.lu.matrix_mut();
        k.fill(0.0);
        model.mass(&w.q1, &mut self.mass);
        for (r, cc, v) in self.mass.entries() {
            k[(r, cc)] = v;
        }
        w.qp.copy_from_slice(&w.q1);
        w.qdp.copy_from_slice(&w.qd1);
        w.unit.fill(0.0);
        let largest_position = w.q1.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for j in 0..n {
            // K column j (perturbing the position along velocity coordinate j: q ⊕ ε e_j), scaled
            // by β'; D column j (the velocity), by γ'.
            w.unit[j] = 1.0;
            for (velocity, scale) in [(false, bp), (true, gp)] {
                let x = w.qd1[j];
                // Relative steps: to the velocity, or to the position coordinate when `v = q̇`
                // (otherwise to the largest position: the direction mixes coordinates).
                let size = match (velocity, w.q1.len() == n) {
                    (true, _) => x.abs(),
                    (false, true) => w.q1[j].abs(),
                    (false, false) => largest_position,
                };
                let h = 1e-7 * (1.0 + size);
                for (sign, out) in [(1.0, &mut w.rp), (-1.0, &mut w.rm)] {
                    let (qs, qds) = if velocity {
                        w.qdp[j] = x + sign * h;
                        (&w.q1, &w.qdp)
                    } else {
                        w.qp.copy_from_slice(&w.q1);
                        model.integrate_positions(&mut w.qp, &w.unit, sign * h);
                        (&w.qp, &w.qd1)
                    };
                    Self::residual(
                        &mut self.mass,
                        &mut self.values,
                        model,
                        t,
                        (qs, qds),
                        (&w.qdd, &w.lam),
                        1.0,
                        out,
                    );
                }
                if velocity {
                    w.qdp[j] = x;
                }
                for i in 0..n {
                    k[(i, j)] += scale * (w.rp[i] - w.rm[i]) / (2.0 * h);
                }
            }
            w.unit[j] = 0.0;
        }
        self.evaluations += 4 * n as u64;
        let sys = model.constraints();
        sys.evaluate(t, &w.q1, &w.qd1, &mut self.values);
        for (&(r, c), &v) in sys.pattern().entries().iter().zip(&self.values.jacobian) {
            k[(n + r, c)] += v;
            k[(c, n + r)] += v;
        }
        w.lu.factor();
    }
}
