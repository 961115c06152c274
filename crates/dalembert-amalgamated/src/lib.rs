//! The amalgamated formulation (`FORMULATIONS.md` §6): accelerations `q̈`, generalized constraint
//! forces `Q_c` and independent accelerations `q̈_i` are all unknowns of one symmetric system,
//!
//! ```text
//! [ M    −I    0   ] [ q̈   ]   [  Q_e ]
//! [ −I    0    B_i ] [ Q_c ] = [ −γ_i ]
//! [ 0    B_iᵀ  0   ] [ q̈_i ]   [  0   ]
//! ```
//!
//! from `M q̈ = Q_e + Q_c`, `q̈ = B_i q̈_i + γ_i` and `B_iᵀ Q_c = 0` (constraint forces do no work on
//! admissible motions). The multipliers consistent with the other formulations follow from
//! `Q_c = −C_qᵀ λ` on the dependent columns: `C_qdᵀ λ_R = −Q_c,d`.
//!
//! The velocity transformation and its partition are shared with the embedding formulation
//! (`dalembert_constraints::partition`). The system (size `3n − r`) is solved here with dense LU
//! with partial pivoting: `B_i` is generally dense in its dependent rows and its pattern changes at
//! each re-partition, so a sparse symmetric factorization with a reusable analysis needs a
//! structural pattern of `B_i` first (future work, noted in `docs/formulations.md`).

use dalembert_constraints::{
    ConstraintValues, DynamicsError, Formulation, FormulationStats, Model, PartitionTracker, RedundancyTreatment,
    Stabilization,
};
use dalembert_kinematics::MassMatrix;
use faer::linalg::solvers::Solve;
use faer::Mat;
use std::sync::Arc;

/// The amalgamated formulation of a model.
pub struct Amalgamated {
    model: Arc<Model>,
    redundancy: RedundancyTreatment,
    tracker: PartitionTracker,
    mass: MassMatrix,
    values: ConstraintValues,
    q_e: Vec<f64>,
    cdot: Vec<f64>,
    rhs: Vec<f64>,
    stats: FormulationStats,
}

impl std::fmt::Debug for Amalgamated {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Amalgamated")
            .field("partition", &self.tracker.current())
            .finish()
    }
}

impl Amalgamated {
    /// Sets up the formulation; `redundancy` as in the augmented formulation.
    pub fn new(model: Arc<Model>, redundancy: RedundancyTreatment) -> Self {
        let n = model.num_coordinates();
        let m = model.num_equations();
        Amalgamated {
            mass: model.mass_matrix(&vec![0.0; n]),
            values: model.constraints().values(),
            q_e: vec![0.0; n],
            cdot: vec![0.0; m],
            rhs: vec![0.0; m],
            tracker: PartitionTracker::new(1e3),
            redundancy,
            model,
            stats: FormulationStats::default(),
        }
    }

    /// With redundant constraints treated as errors.
    pub fn with_defaults(model: Arc<Model>) -> Self {
        Self::new(model, RedundancyTreatment::Error)
    }

    fn singular(&self, t: f64) -> DynamicsError {
        self.model.constraints().redundancy_error(t, &self.values)
    }
}

impl Formulation for Amalgamated {
    fn name(&self) -> &'static str {
        "amalgamated"
    }

    fn model(&self) -> &Model {
        &self.model
    }

    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        stabilization: Stabilization,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.stats.evaluations += 1;
        self.model.check_state(t, q, qd)?;
        let n = q.len();
        self.mass.update(self.model.bodies(), q);
        self.model.applied_forces(t, q, qd, &mut self.q_e);
        let sys = self.model.constraints();
        sys.evaluate(t, q, qd, &mut self.values);
        if stabilization != Stabilization::None {
            sys.velocity_residual(&self.values, qd, &mut self.cdot);
        }
        stabilization.apply(&self.values.gamma, &self.values.c, &self.cdot, &mut self.rhs);
        let before = self.tracker.log.len();
        let (partition, vt) = match self.tracker.transform(t, sys, &self.values, &self.rhs) {
            Some((p, vt)) => (p.clone(), vt),
            None => return Err(self.singular(t)),
        };
        self.stats.repartitions += (self.tracker.log.len() - before) as u64;
        let redundant = partition.rows.len() < sys.num_equations();
        if redundant && self.redundancy == RedundancyTreatment::Error {
            return Err(self.singular(t));
        }
        let ni = partition.independent.len();
        let dim = 2 * n + ni;
        let mut k = Mat::<f64>::zeros(dim, dim);
        for (b, blk) in self.mass.blocks().iter().enumerate() {
            for r in 0..3 {
                for c in 0..3 {
                    k[(3 * b + r, 3 * b + c)] = blk[(r, c)];
                }
            }
        }
        for i in 0..n {
            k[(i, n + i)] = -1.0;
            k[(n + i, i)] = -1.0;
            for j in 0..ni {
                k[(n + i, 2 * n + j)] = vt.b[(i, j)];
                k[(2 * n + j, n + i)] = vt.b[(i, j)];
            }
        }
        let rhs = Mat::from_fn(dim, 1, |i, _| {
            if i < n {
                self.q_e[i]
            } else if i < 2 * n {
                -vt.gamma[i - n]
            } else {
                0.0
            }
        });
        self.stats.factorizations += 1;
        let sol = k.partial_piv_lu().solve(&rhs);
        let res = (&k * &sol - &rhs).norm_max();
        let accurate = res <= 1e-9 * (rhs.norm_max() + k.norm_max() * sol.norm_max());
        if !accurate {
            let bodies: Vec<String> = self
                .model
                .bodies()
                .iter()
                .filter(|b| b.mass == 0.0 || b.inertia_about_reference() == 0.0)
                .map(|b| b.name.clone())
                .collect();
            return Err(if bodies.is_empty() {
                DynamicsError::Singular {
                    time: t,
                    what: "amalgamated system singular".into(),
                }
            } else {
                DynamicsError::SingularMass { time: t, bodies }
            });
        }
        for i in 0..n {
            qdd[i] = sol[(i, 0)];
        }
        // λ on the independent rows from the dependent columns of Q_c = −C_qᵀ λ.
        let mut y: Vec<f64> = partition.dependent.iter().map(|&d| -sol[(n + d, 0)]).collect();
        vt.solve_dependent_transpose(&mut y);
        sys.scatter_multipliers(t, &self.values, &partition.rows, &y, lambda)?;
        Ok(())
    }

    fn residuals(&mut self, t: f64, q: &[f64], qd: &[f64], c: &mut [f64], cdot: &mut [f64]) {
        self.model.constraints().residuals(t, q, qd, &mut self.values, c, cdot);
    }

    /// Coordinate partitioning (`PartitionTracker::project`): independent coordinates held,
    /// dependent positions by Newton–Raphson, dependent velocities from the velocity equation.
    fn project(&mut self, t: f64, q: &mut [f64], qd: &mut [f64], tolerance: f64) -> Result<usize, DynamicsError> {
        let sys = self.model.constraints();
        self.tracker
            .project_counted(t, sys, &mut self.values, (q, qd), tolerance, &mut self.stats)
    }

    fn stats(&self) -> FormulationStats {
        self.stats
    }
}
