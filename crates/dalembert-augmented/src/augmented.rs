//! The augmented formulation type and its [`Formulation`] implementation.

use crate::diagnosis::{diagnose, independent_rows};
use crate::redundant::{checked_solve, Independent};
use dalembert_system::linalg::SaddlePoint;
use dalembert_system::{
    Baumgarte, ConstraintValues, Data, DynamicsError, Formulation, FormulationStats, MultibodySystem,
    RedundancyTreatment, Stage,
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
    /// `M`, `Q`, the constraint values and the right-hand side (the stages before the solve).
    data: Data,
    x: Vec<f64>,
    b: Vec<f64>,
    r: Vec<f64>,
    /// The independent equations of a redundant system (minimum-norm treatment), once found.
    independent: Option<Independent>,
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
    /// The last factorization's solve with right-hand side `[g; h]` (`h = 0` when `None`): false
    /// after a solve on an independent row set, which keeps its own, or when the solve's check
    /// fails.
    fn respond(&mut self, g: &[f64], h: Option<&[f64]>, dqdd: &mut [f64], dlambda: &mut [f64]) -> bool {
        if self.independent.is_some() {
            return false;
        }
        if let Some(solved) = self.data.tree_response(&*self.model, g, dqdd) {
            return solved && dlambda.is_empty();
        }
        let n = g.len();
        self.b[..n].copy_from_slice(g);
        match h {
            Some(h) => self.b[n..].copy_from_slice(h),
            None => self.b[n..].iter_mut().for_each(|v| *v = 0.0),
        }
        let solved = checked_solve(
            &mut self.solver,
            (&self.data.mass, self.model.constraints().pattern(), &self.data.values),
            &self.b,
            (&mut self.x, &mut self.r),
            self.options.residual_tolerance,
        );
        if solved {
            dqdd.copy_from_slice(&self.x[..n]);
            dlambda.copy_from_slice(&self.x[n..]);
        }
        solved
    }

    /// Sets up the formulation: workspaces, and for the sparse back ends the symbolic analysis.
    pub fn new(model: Arc<dyn MultibodySystem>, options: AugmentedOptions) -> Result<Self, DynamicsError> {
        let n = model.layout().n_v();
        let m = model.num_equations();
        // A tree in joint coordinates without constraint equations, under `Backend::Auto`:
        // `M q̈ = Q` solved by the articulated-body algorithm.
        let mut data = Data::new(&*model, options.backend == Backend::Auto);
        model.mass(&model.reference_positions(), &mut data.mass);
        let solver = SaddlePoint::new(
            options.backend,
            &data.mass,
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
            data,
            x: vec![0.0; n + m],
            b: vec![0.0; n + m],
            r: vec![0.0; n + m],
            independent: None,
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
        &self.data.values
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
                &self.data.mass,
                &self.data.values,
                &self.b,
                &mut self.x,
                self.options.residual_tolerance,
            ) {
                return Ok(());
            }
            self.independent = None;
        }
        if self
            .solver
            .factor(&self.data.mass, sys.pattern(), &self.data.values)
            .is_ok()
            && checked_solve(
                &mut self.solver,
                (&self.data.mass, sys.pattern(), &self.data.values),
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
                let rows = independent_rows(t, &*self.model, &self.data.mass, &self.data.values, &self.b, n)?;
                let mut ind = Independent::new(&*self.model, &self.data.mass, rows, &self.options).map_err(|e| {
                    DynamicsError::Factorization {
                        time: t,
                        what: e.to_string(),
                    }
                })?;
                if !ind.solve(
                    &self.data.mass,
                    &self.data.values,
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
            RedundancyTreatment::Error => Err(diagnose(
                t,
                &*self.model,
                &self.data.values,
                self.options.pivot_tolerance,
            )),
        }
    }

    /// Evaluates `M`, `Q_e` and the constraints at `(t, q, q̇)` into the workspaces.
    fn load(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<(), DynamicsError> {
        self.data.load(&*self.model, t, q, qd)
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
        if self.data.start(&*self.model, t, q, qd, baumgarte, qdd, lambda)? == Stage::Solved {
            return Ok(());
        }
        let n = qd.len();
        let (bt, bb) = self.b.split_at_mut(n);
        bt.copy_from_slice(&self.data.q_e);
        bb.copy_from_slice(&self.data.rhs);
        self.factor_and_solve(t)?;
        qdd.copy_from_slice(&self.x[..n]);
        lambda.copy_from_slice(&self.x[n..]);
        if let Some(i) = qdd.iter().position(|v| !v.is_finite()) {
            return Err(self.model.non_finite_acceleration(t, i));
        }
        Ok(())
    }

    fn residuals(&mut self, t: f64, q: &[f64], qd: &[f64], c: &mut [f64], cdot: &mut [f64]) {
        self.data.residuals(&*self.model, (t, q, qd), c, cdot);
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
            let res = self.data.values.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if res <= tolerance {
                break;
            }
            if iterations == MAX_ITERATIONS {
                let sys = self.model.constraints();
                return Err(dalembert_system::ConstraintError::not_converged(
                    sys,
                    &self.data.values.c,
                    t,
                    iterations,
                    tolerance,
                )
                .into());
            }
            self.b[..n].iter_mut().for_each(|v| *v = 0.0);
            for (bi, ci) in self.b[n..].iter_mut().zip(&self.data.values.c) {
                *bi = -ci;
            }
            self.factor_and_solve(t)?;
            self.model.constraints().correct_positions(q, &self.x[..n]);
            iterations += 1;
        }
        self.stats.newton_iterations += iterations as u64;
        let sys = self.model.constraints();
        sys.velocity_residual(&self.data.values, qd, &mut self.data.cdot);
        self.b[..n].iter_mut().for_each(|v| *v = 0.0);
        for (bi, ci) in self.b[n..].iter_mut().zip(&self.data.cdot) {
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

    fn set_extra_force(&mut self, extra: Option<&[f64]>) -> bool {
        self.data.set_extra_force(extra)
    }

    /// `[M C_qᵀ; C_q 0] [Δq̈; Δλ] = [g; 0]` with the last factorization (false after a solve on
    /// an independent row set, which keeps its own).
    fn force_response(
        &mut self,
        _t: f64,
        g: &[f64],
        dqdd: &mut [f64],
        dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        Ok(self.respond(g, None, dqdd, dlambda))
    }

    /// `[M C_qᵀ; C_q 0] [Δq̈; Δλ] = [g; h]` with the last factorization (false as for
    /// [`Formulation::force_response`], and for a tree solved outright).
    fn linear_response(
        &mut self,
        _t: f64,
        g: &[f64],
        h: &[f64],
        dqdd: &mut [f64],
        dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        if self.model.kinematic_tree().is_some() || h.len() != self.b.len() - g.len() {
            return Ok(false);
        }
        Ok(self.respond(g, Some(h), dqdd, dlambda))
    }
}
