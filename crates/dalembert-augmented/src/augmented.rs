//! The augmented formulation type and its [`Formulation`] implementation.

use crate::diagnosis::{diagnose, independent_rows};
use crate::redundant::{checked_solve, Independent};
use dalembert_system::linalg::SaddlePoint;
use dalembert_system::tree::Articulated;
use dalembert_system::{
    Baumgarte, BlockDiagonal, ConstraintValues, DynamicsError, EvaluatedAt, Formulation, FormulationStats,
    MultibodySystem, RedundancyTreatment,
};
use std::sync::Arc;

pub use dalembert_system::linalg::Backend;

/// Settings of the augmented formulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AugmentedOptions {
    /// Back end.
    pub backend: Backend,
    /// With [`Backend::Auto`], the largest `n + m` solved densely when every mass block is positive
    /// definite and the system has loops (loop-free systems take the tree factorization at any
    /// size; the sparse Schur complement above this limit; with singular mass blocks the sparse LU
    /// above twice this). Default 60: one evaluation of a planar chain by the dense and the sparse
    /// Schur complement, 12 links (`n + m = 60`) 2.99 / 2.70 µs, 16 links 5.28 / 3.65 µs, 24 links
    /// 13.9 / 5.2 µs; 8 links 1.53 / 1.88 µs (2026-11-25, a loop of evaluations per back end).
    pub dense_limit: usize,
    /// What to do with redundant constraints.
    pub redundancy: RedundancyTreatment,
    /// Relative pivot threshold of the dense LU below which the matrix counts as singular.
    pub pivot_tolerance: f64,
    /// Relative residual `‖K x − b‖∞ / (‖b‖∞ + s ‖x‖∞)` above which a solve counts as failed
    /// (`s` the largest matrix entry).
    pub residual_tolerance: f64,
}

impl Default for AugmentedOptions {
    fn default() -> Self {
        AugmentedOptions {
            backend: Backend::Auto,
            dense_limit: 60,
            redundancy: RedundancyTreatment::Error,
            pivot_tolerance: 1e-13,
            residual_tolerance: 1e-9,
        }
    }
}

/// The augmented (Lagrange multiplier) formulation of a system.
pub struct Augmented {
    model: Arc<dyn MultibodySystem>,
    options: AugmentedOptions,
    solver: SaddlePoint,
    mass: BlockDiagonal,
    mass_loaded: bool,
    values: ConstraintValues,
    /// The state `values` hold (the monitor's evaluation reused by the next step's first stage).
    evaluated_at: EvaluatedAt,
    q_e: Vec<f64>,
    cdot: Vec<f64>,
    x: Vec<f64>,
    b: Vec<f64>,
    r: Vec<f64>,
    /// The independent equations of a redundant system (minimum-norm treatment), once found.
    independent: Option<Independent>,
    /// A tree in joint coordinates without constraint equations, under `Backend::Auto`: `M q̈ = Q`
    /// solved by the articulated-body algorithm.
    articulated: Option<Articulated>,
    stats: FormulationStats,
}

impl std::fmt::Debug for Augmented {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Augmented")
            .field("backend", &self.solver.name())
            .field("options", &self.options)
            .finish()
    }
}

impl Augmented {
    /// Sets up the formulation: workspaces, and for the sparse back ends the symbolic analysis.
    pub fn new(model: Arc<dyn MultibodySystem>, options: AugmentedOptions) -> Result<Self, DynamicsError> {
        let n = model.layout().n_v();
        let m = model.num_equations();
        let mut mass = model.mass_storage();
        model.mass(&model.reference_positions(), &mut mass);
        let solver = SaddlePoint::new(
            options.backend,
            &mass,
            model.mass_is_constant(),
            model.constraints(),
            options.dense_limit,
            options.pivot_tolerance,
        )
        .map_err(|e| DynamicsError::Factorization {
            time: 0.0,
            what: e.to_string(),
        })?;
        Ok(Augmented {
            mass,
            mass_loaded: false,
            values: model.constraints().values(),
            evaluated_at: EvaluatedAt::new(model.layout().n_q(), model.layout().n_v()),
            q_e: vec![0.0; n],
            cdot: vec![0.0; m],
            x: vec![0.0; n + m],
            b: vec![0.0; n + m],
            r: vec![0.0; n + m],
            independent: None,
            articulated: match options.backend {
                Backend::Auto => Articulated::for_system(&*model),
                _ => None,
            },
            solver,
            options,
            model,
            stats: FormulationStats::default(),
        })
    }

    /// With default options.
    pub fn with_defaults(model: Arc<dyn MultibodySystem>) -> Result<Self, DynamicsError> {
        Self::new(model, AugmentedOptions::default())
    }

    /// The back end in use: `"dense"`, `"schur"`, `"sparse"`, `"sparse-schur"` or `"tree"`.
    pub fn backend_name(&self) -> &'static str {
        self.solver.name()
    }

    /// The constraint values of the last evaluation (`C`, `C_q`, `C_t`, `Q_d`).
    pub fn values(&self) -> &ConstraintValues {
        &self.values
    }

    /// Factors and solves `K x = b` (b in `self.b`), checking the residual. On success `self.x` holds
    /// the solution.
    ///
    /// With the minimum-norm treatment of redundant constraints, a singular matrix hands over to an
    /// [`Independent`] row set, kept for the following evaluations while its rows stay independent
    /// and the dropped ones dependent on them (`crate::redundant`).
    fn factor_and_solve(&mut self, t: f64) -> Result<(), DynamicsError> {
        let sys = self.model.constraints();
        self.stats.factorizations += 1;
        if let Some(ind) = &mut self.independent {
            if ind.solve(
                &self.mass,
                &self.values,
                &self.b,
                &mut self.x,
                self.options.residual_tolerance,
            ) {
                return Ok(());
            }
            self.independent = None;
        }
        if self.solver.factor(&self.mass, sys.pattern(), &self.values).is_ok()
            && checked_solve(
                &mut self.solver,
                (&self.mass, sys.pattern(), &self.values),
                &self.b,
                (&mut self.x, &mut self.r),
                self.options.residual_tolerance,
            )
        {
            return Ok(());
        }
        match self.options.redundancy {
            RedundancyTreatment::MinimumNorm => {
                let n = self.model.layout().n_v();
                let rows = independent_rows(t, &*self.model, &self.mass, &self.values, &self.b, n)?;
                let mut ind = Independent::new(&*self.model, &self.mass, rows, &self.options).map_err(|e| {
                    DynamicsError::Factorization {
                        time: t,
                        what: e.to_string(),
                    }
                })?;
                if !ind.solve(
                    &self.mass,
                    &self.values,
                    &self.b,
                    &mut self.x,
                    self.options.residual_tolerance,
                ) {
                    return Err(self
                        .model
                        .singular_mass_error(t, "saddle-point matrix of the independent equations singular"));
                }
                self.independent = Some(ind);
                Ok(())
            }
            RedundancyTreatment::Error => Err(diagnose(t, &*self.model, &self.values, self.options.pivot_tolerance)),
        }
    }

    /// Evaluates `M`, `Q_e` and the constraints at `(t, q, q̇)` into the workspaces.
    fn load(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<(), DynamicsError> {
        self.model.check_state(t, q, qd)?;
        if !(self.mass_loaded && self.model.mass_is_constant()) {
            self.model.mass(q, &mut self.mass);
            self.mass_loaded = true;
        }
        self.model.applied_forces(t, q, qd, &mut self.q_e);
        self.model.check_forces(t, q, qd, &self.q_e)?;
        self.evaluated_at
            .evaluate(self.model.constraints(), t, q, qd, &mut self.values);
        self.model.constraints().check_values(t, &self.values)?;
        Ok(())
    }
}

impl Formulation for Augmented {
    fn name(&self) -> &'static str {
        "augmented"
    }

    fn system(&self) -> &dyn MultibodySystem {
        &*self.model
    }

    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.stats.evaluations += 1;
        self.model.check_lengths(&[("q̈", qdd.len())], &[("λ", lambda.len())])?;
        if let Some(tree) = &mut self.articulated {
            return tree.solve(&*self.model, t, q, qd, qdd);
        }
        self.load(t, q, qd)?;
        let n = qd.len();
        let sys = self.model.constraints();
        if baumgarte.is_some() {
            sys.velocity_residual(&self.values, qd, &mut self.cdot);
        }
        let (bt, bb) = self.b.split_at_mut(n);
        bt.copy_from_slice(&self.q_e);
        Baumgarte::apply(baumgarte, &self.values.gamma, &self.values.c, &self.cdot, bb);
        self.factor_and_solve(t)?;
        qdd.copy_from_slice(&self.x[..n]);
        lambda.copy_from_slice(&self.x[n..]);
        if let Some(i) = qdd.iter().position(|v| !v.is_finite()) {
            return Err(self.model.non_finite_acceleration(t, i));
        }
        Ok(())
    }

    fn residuals(&mut self, t: f64, q: &[f64], qd: &[f64], c: &mut [f64], cdot: &mut [f64]) {
        self.evaluated_at
            .residuals(self.model.constraints(), (t, q, qd), &mut self.values, c, cdot);
    }

    /// Mass-weighted projection with the same saddle-point matrix:
    /// `[M C_qᵀ; C_q 0] [Δq; μ] = [0; −C]` repeated until `‖C‖∞ ≤ tolerance`, then
    /// `[M C_qᵀ; C_q 0] [Δq̇; μ] = [0; −(C_q q̇ + C_t)]`.
    fn project(&mut self, t: f64, q: &mut [f64], qd: &mut [f64], tolerance: f64) -> Result<usize, DynamicsError> {
        const MAX_ITERATIONS: usize = 20;
        let n = qd.len();
        let mut iterations = 0;
        loop {
            self.load(t, q, qd)?;
            let res = self.values.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if res <= tolerance {
                break;
            }
            if iterations == MAX_ITERATIONS {
                let sys = self.model.constraints();
                return Err(dalembert_system::ConstraintError::not_converged(
                    sys,
                    &self.values.c,
                    t,
                    iterations,
                    tolerance,
                )
                .into());
            }
            self.b[..n].iter_mut().for_each(|v| *v = 0.0);
            for (bi, ci) in self.b[n..].iter_mut().zip(&self.values.c) {
                *bi = -ci;
            }
            self.factor_and_solve(t)?;
            self.model.constraints().correct_positions(q, &self.x[..n]);
            iterations += 1;
        }
        self.stats.newton_iterations += iterations as u64;
        let sys = self.model.constraints();
        sys.velocity_residual(&self.values, qd, &mut self.cdot);
        self.b[..n].iter_mut().for_each(|v| *v = 0.0);
        for (bi, ci) in self.b[n..].iter_mut().zip(&self.cdot) {
            *bi = -ci;
        }
        self.factor_and_solve(t)?;
        qd.iter_mut().zip(&self.x[..n]).for_each(|(a, d)| *a += d);
        Ok(iterations)
    }

    fn stats(&self) -> FormulationStats {
        self.stats
    }

    fn is_index3_augmented(&self) -> bool {
        true
    }
}
