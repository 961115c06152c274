//! Inverse dynamics of kinematically driven systems (`FORMULATIONS.md` §7).
//!
//! When drivers fix every degree of freedom (`rank C_q = n`), position, velocity and acceleration
//! analysis give `q, v, v̇` from the constraints alone, and `C_qᵀ λ = Q − M v̇` gives the
//! multipliers, hence every joint reaction and every driver effort (`−λ`), which the system's
//! modelling crate reads from them (e.g. `dalembert_constraints::ConstraintSystem::reactions`).

use crate::{DynamicsError, KinematicOptions, MultibodySystem};
use faer::linalg::solvers::Solve;
use faer::Mat;
use std::sync::Arc;

/// The motion and forces of a driven system at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct InverseSolution {
    /// Time.
    pub time: f64,
    /// Positions.
    pub q: Vec<f64>,
    /// Velocities.
    pub qd: Vec<f64>,
    /// Accelerations.
    pub qdd: Vec<f64>,
    /// Multipliers.
    pub lambda: Vec<f64>,
}

/// Inverse dynamics of a fully driven model.
#[derive(Debug)]
pub struct InverseDynamics {
    model: Arc<dyn MultibodySystem>,
    options: KinematicOptions,
}

impl InverseDynamics {
    /// Checks that the model is fully driven at configuration `q` (approximate is fine: it is
    /// assembled first) and prepares the solver.
    pub fn new(model: Arc<dyn MultibodySystem>, q: &[f64], options: KinematicOptions) -> Result<Self, DynamicsError> {
        let sys = model.constraints();
        let mut q = q.to_vec();
        sys.solve_positions(0.0, &mut q, &options)?;
        let mut vals = sys.values();
        sys.evaluate(0.0, &q, &[], &mut vals);
        let s = sys.analyse_structure(&vals, options.rank_tolerance)?;
        if s.degrees_of_freedom != 0 {
            return Err(DynamicsError::Singular {
                time: 0.0,
                what: format!(
                    "inverse dynamics needs a fully driven model; {} degrees of freedom are free",
                    s.degrees_of_freedom
                ),
            });
        }
        if !s.is_full_rank() {
            return Err(DynamicsError::RedundantConstraints {
                time: 0.0,
                rank: s.rank,
                equations: s.equations,
                involved: s.redundant,
            });
        }
        Ok(InverseDynamics { model, options })
    }

    /// Solves at time `t`, starting position analysis from `q_guess`.
    pub fn solve(&self, t: f64, q_guess: &[f64]) -> Result<InverseSolution, DynamicsError> {
        let model = &self.model;
        let sys = model.constraints();
        let n = model.layout().n_v();
        let mut q = q_guess.to_vec();
        sys.solve_positions(t, &mut q, &self.options)?;
        let mut qd = vec![0.0; n];
        sys.solve_velocities(t, &q, &mut qd, &self.options)?;
        let mut qdd = vec![0.0; n];
        sys.solve_accelerations(t, &q, &qd, &mut qdd, &self.options)?;
        // C_qᵀ λ = Q_e − M q̈ (square, n × n).
        let mut rhs = vec![0.0; n];
        model.applied_forces(t, &q, &qd, &mut rhs);
        let mut mass = model.mass_storage();
        model.mass(&q, &mut mass);
        mass.mul_add(-1.0, &qdd, &mut rhs);
        let mut vals = sys.values();
        sys.evaluate(t, &q, &qd, &mut vals);
        let jt = sys.jacobian_dense(&vals).transpose().to_owned();
        let b = Mat::from_fn(n, 1, |i, _| rhs[i]);
        let lam = jt.partial_piv_lu().solve(&b);
        let lambda: Vec<f64> = (0..n).map(|i| lam[(i, 0)]).collect();
        if lambda.iter().any(|v| !v.is_finite()) {
            return Err(DynamicsError::NonFinite {
                time: t,
                what: "multipliers (driven system singular here)".into(),
            });
        }
        Ok(InverseSolution {
            time: t,
            q,
            qd,
            qdd,
            lambda,
        })
    }
}
