//! What a run watches after every accepted step (blow-up, constraint drift, energy, the branch
//! at singular positions, a cancel request) and counts (steps, rejections, work), with the work
//! buffers of the evaluations at output states. Allocated with the run; nothing while stepping.

use super::{inf_norm, project};
use crate::branch::BranchMonitor;
use crate::{IntegrationError, Stabilization, Statistics};
use dalembert_system::{Baumgarte, DynamicsError, Energy, Formulation, FormulationStats};
use std::sync::atomic::{AtomicBool, Ordering};

/// Monitors, counters and output buffers of one run.
pub(super) struct Monitors {
    /// Number of positions `n_q` (`y = [q; v]` splits there).
    pub n: usize,
    pub stats: Statistics,
    /// The formulation's counters when the run started.
    pub start: FormulationStats,
    pub c: Vec<f64>,
    pub cdot: Vec<f64>,
    pub qdd: Vec<f64>,
    pub lambda: Vec<f64>,
    /// The friction forces of the joints at the last sample (`Formulation::friction_forces`).
    pub friction: Vec<f64>,
    /// The joint limits' forces at the last sample (`Formulation::limit_forces`).
    pub limit: Vec<f64>,
    pub energy0: f64,
    pub scale0: f64,
    pub divergence_factor: f64,
    /// The Baumgarte gains the method integrates with (the samples' `q̈` and `λ` use them too).
    pub baumgarte: Option<Baumgarte>,
    /// Stops the run where it leaves its branch at a singular position.
    pub branch: BranchMonitor,
}

impl Monitors {
    /// Updates the monitors after an accepted step; fails on blow-up, and with
    /// [`IntegrationError::Interrupted`] when `cancel` is set. `energy` is the energy at `y` where
    /// the step already evaluated it ([`Monitors::undo_kick`]).
    pub fn monitor(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        y: &[f64],
        h: f64,
        energy: Option<Energy>,
        cancel: &AtomicBool,
    ) -> Result<(), IntegrationError> {
        let size = inf_norm(y);
        if !size.is_finite() {
            return Err(DynamicsError::NonFinite {
                time: t,
                what: "state after the step".into(),
            }
            .into());
        }
        if size > self.divergence_factor * self.scale0 {
            return Err(IntegrationError::Diverged {
                time: t,
                what: format!("state magnitude {size:.3e} vs initial {:.3e}", self.scale0),
                step: h,
                hint: String::new(),
            });
        }
        let (q, qd) = y.split_at(self.n);
        f.residuals(t, q, qd, &mut self.c, &mut self.cdot);
        let s = &mut self.stats;
        s.max_constraint_violation = s.max_constraint_violation.max(inf_norm(&self.c));
        s.max_velocity_violation = s.max_velocity_violation.max(inf_norm(&self.cdot));
        let energy = energy.unwrap_or_else(|| f.energy(t, q, qd));
        s.max_energy_change = s.max_energy_change.max((energy.total() - self.energy0).abs());
        self.branch.after_step(f, t, (q, qd), energy, s.steps == 0)?;
        s.steps += 1;
        s.min_step_taken = s.min_step_taken.min(h);
        s.max_step_taken = s.max_step_taken.max(h);
        if cancel.load(Ordering::Relaxed) {
            return Err(IntegrationError::Interrupted { time: t });
        }
        Ok(())
    }

    /// Undoes a kick: where the step ending at `t` at `y` changed a conservative model's energy
    /// by [`crate::BRANCH_SWITCH_JUMP`] times the earlier steps near a singular position
    /// ([`BranchMonitor::kicked`]), the velocities are scaled to give back the energy the step
    /// started from. Returns the energy at `y` where the run watches the energy and left `y` as
    /// it was (for [`Monitors::monitor`], so it is evaluated once per step).
    pub fn undo_kick(&mut self, f: &mut dyn Formulation, t: f64, y: &mut [f64]) -> Option<Energy> {
        if !self.branch.watches_energy() {
            return None;
        }
        let (q, v) = y.split_at_mut(self.n);
        let energy = f.energy(t, q, v);
        let Some(start) = self.branch.kicked(f, t, (q, v), energy, self.stats.steps == 0) else {
            return Some(energy);
        };
        let room = start - energy.potential;
        if energy.kinetic <= 0.0 || room <= 0.0 {
            return Some(energy);
        }
        let scale = (room / energy.kinetic).sqrt();
        for x in v {
            *x *= scale;
        }
        self.stats.kicks_undone += 1;
        // Evaluated again at the scaled state: its rounding, not the product's.
        None
    }

    /// Counts a rejected step; fails when the next step would fall below the minimum.
    pub fn rejected(&mut self, t: f64, next: f64, error: f64, min_step: f64) -> Result<(), IntegrationError> {
        self.stats.rejected += 1;
        if next < min_step {
            return Err(IntegrationError::StepSizeTooSmall {
                time: t,
                step: next,
                min_step,
                error,
            });
        }
        Ok(())
    }

    /// [`project`] after an accepted step at `t`, measuring the share of the kinetic energy the
    /// velocity projection removed ([`Statistics::max_projection_share`]).
    pub fn project_step(
        &mut self,
        f: &mut dyn Formulation,
        t: f64,
        y: &mut [f64],
        stabilization: Stabilization,
    ) -> Result<bool, IntegrationError> {
        let n_q = self.n;
        self.branch.before_projection(&y[n_q..]);
        if !project(f, t, y, n_q, stabilization)? {
            return Ok(false);
        }
        let (q, v) = y.split_at(n_q);
        self.branch.after_projection(f, t, q, v, &mut self.stats)?;
        Ok(true)
    }

    /// The statistics so far: the formulation's work since the start plus the work the method
    /// did outside it (`method`: an implicit method's own Newton solves); wall time is the
    /// caller's.
    pub fn statistics(&self, f: &dyn Formulation, method: FormulationStats) -> Statistics {
        let now = f.stats();
        let mut s = self.stats;
        s.evaluations = now.evaluations - self.start.evaluations + method.evaluations;
        s.factorizations = now.factorizations - self.start.factorizations + method.factorizations;
        s.newton_iterations = now.newton_iterations - self.start.newton_iterations + method.newton_iterations;
        s.repartitions = now.repartitions - self.start.repartitions;
        s.handovers = now.handovers - self.start.handovers;
        if s.steps == 0 {
            s.min_step_taken = 0.0;
        }
        s.energy_scale = self.branch.energy_scale();
        s
    }
}
