//! Branch-switch monitor: a fixed or adaptive run that leaves the branch of its motion at a
//! singular position of a closed chain stops with [`IntegrationError::BranchSwitch`] instead of
//! going on along another motion.
//!
//! Two signs, each measured against the run's largest kinetic energy `T_max` and against the
//! steps before (their maximum, decaying by [`MEMORY`] per step, so a start from rest is forgotten
//! once the motion is under way):
//! - the share of `T_max` one step's velocity projection removes, `T(q, v − v_p) / T_max`
//!   ([`BRANCH_SWITCH_SHARE`]): the step left the branch and the projection put it on another;
//! - for a conservative model stepped at a fixed step, the change of `T + V` in one step over
//!   `T_max` ([`BRANCH_SWITCH_ENERGY`]) that could not be given back: a step that changes the
//!   energy by [`BRANCH_SWITCH_JUMP`] times the steps before near a singular position has its
//!   velocities scaled back to the energy it started from first ([`BranchMonitor::kicked`]: a
//!   stage near the singular position amplifies the rounding in the state into such a kick, on a
//!   branch it keeps; `docs/stability.md`, "Kicks at singular positions").
//!
//! Either sign also fires on a step kicked by a stage near the singular position on a branch the
//! run keeps (IFToMM A02 N-four-bar, checked with the checks off), and the kick has moved the
//! state by then (1e-6 … 4e-5 of the crank's path at the end on A02 N = 2 and 4); a run that truly
//! left its branch showed the same sign (A02 N = 2 written another way, amalgamated, 0.1 ms). The
//! run cannot tell the two apart from these signs, and stops.
//!
//! Either sign counts only where `C_q` is nearly singular after the step (singular values below
//! [`NEAR`] of the largest: links close to lining up; the equations involved are named): a jump
//! elsewhere (an undamped generalized-α growing on a pendulum) is left to the divergence monitor.

use crate::{IntegrationError, Statistics};
use dalembert_system::jacobian_svd::SingularityCheck;
use dalembert_system::{EquationRef, Formulation};

/// Share of the largest kinetic energy one step's velocity projection may remove
/// ([`Statistics::max_projection_share`]) before the run stops as a branch switch, when it is also
/// [`BRANCH_SWITCH_JUMP`] times the shares of the steps before (their maximum, decaying by 1 % per
/// step).
///
/// Measured on the IFToMM A02 N-four-bar (N = 40, RK4 + projection, h = 0.1 … 2 ms, 20 s, every
/// formulation; `cargo run --release --example n_four_bar`): runs that kept the branch removed at
/// most 8.7e-6 in one step (mostly below 1e-7); the two that left it (B₀ error 0.28 and 0.38)
/// removed 9.0e-3 and 4.6e-3 in the step where they left.
pub const BRANCH_SWITCH_SHARE: f64 = 1e-3;

/// Change of `T + V` in one fixed step, as a share of the largest kinetic energy, above which a run
/// of a conservative model stops as a branch switch, when it is also [`BRANCH_SWITCH_JUMP`] times
/// the changes of the steps before.
///
/// Measured on the A02 N-four-bar with N = 2 (RK4 + projection, 20 s; `cargo run --release
/// --example n_four_bar -- 2`): runs that kept the branch (h = 0.25 … 2 ms, every formulation)
/// changed the energy by at most 1.7e-9 in a step; at h = 0.1 ms, where the runs ended 0.14
/// (augmented) and 2.7e-2 (embedding, amalgamated) off without a projection removing much, the
/// change jumped to 5.0e-5 (from below 3e-7) and 4.1e-5 (from below 1e-8).
pub const BRANCH_SWITCH_ENERGY: f64 = 1e-5;

/// How many times the earlier steps' shares one step's share must exceed to count as a branch
/// switch ([`BRANCH_SWITCH_SHARE`], [`BRANCH_SWITCH_ENERGY`]): a coarse step drifts by a similar
/// share on every step, a switch in one.
pub const BRANCH_SWITCH_JUMP: f64 = 100.0;

/// Decay per step of the earlier steps' shares (1e-4 after about 900 steps).
const MEMORY: f64 = 0.99;

/// Relative singular value of `C_q` below which the state after a step is near a singular
/// position. Looser than the adaptive guard's 1e-3 (`SingularPassGuard`): a fixed step of
/// `h` ends up to `h·|v|` past the singular position.
pub const NEAR: f64 = 1e-2;

/// Relative singular value below which `C_q` has lost rank for good (redundant constraints), not
/// come near a singular position.
pub(crate) const RANK_TOLERANCE: f64 = 1e-9;

/// The equations of `C_q` at `(t, q, v)` when it has singular values below `near` of the largest
/// (above [`RANK_TOLERANCE`]). Allocates its storage: for a run that failed; a run that goes on
/// checks with the [`SingularityCheck`] it keeps ([`BranchMonitor::check`]).
pub(crate) fn near_singular(
    f: &dyn Formulation,
    t: f64,
    (q, v): (&[f64], &[f64]),
    near: f64,
) -> Option<Vec<EquationRef>> {
    let sys = f.system().constraints();
    SingularityCheck::new(sys).near_singular(sys, t, (q, v), near, RANK_TOLERANCE)
}

/// A share measured against the steps before.
#[derive(Default)]
struct Jump {
    /// Maximum of the earlier shares, decaying by [`MEMORY`] per step.
    reference: f64,
}

impl Jump {
    /// Records `share` (or no share, `None`); returns the earlier reference when `share` exceeds
    /// `limit` and [`BRANCH_SWITCH_JUMP`] times it and `confirm()` says so. The first step is
    /// never judged.
    fn record(&mut self, share: Option<f64>, limit: f64, first: bool, confirm: impl FnOnce() -> bool) -> Option<f64> {
        let before = self.reference;
        if let Some(share) = share {
            if !first && share > limit && share > BRANCH_SWITCH_JUMP * before && confirm() {
                return Some(before);
            }
            self.reference = self.reference.max(share);
        }
        self.reference *= MEMORY;
        None
    }
}

/// The monitor of one run.
pub(crate) struct BranchMonitor {
    /// The velocities before a step's projection (length `n_v`).
    v_stepped: Vec<f64>,
    /// The largest kinetic energy seen (initial state, after every projection and every accepted
    /// step).
    largest_kinetic: f64,
    /// `|T + V|` at the start: with `T_max` the scale below which a change is round-off.
    energy0: f64,
    /// `T + V` after the last step.
    last_energy: f64,
    /// Whether the energy check applies (conservative model, fixed step).
    energy_check: bool,
    projection: Jump,
    energy: Jump,
    /// The near-singularity check of the run, sized at setup (a check that finds a regular
    /// position allocates nothing).
    pub(crate) check: SingularityCheck,
}

impl BranchMonitor {
    /// A monitor for a run from `(q0, v0)` with energy `energy0`; `energy_check` when the model is
    /// conservative and the step fixed.
    pub(crate) fn new(f: &dyn Formulation, q0: &[f64], v0: &[f64], energy0: f64, energy_check: bool) -> Self {
        BranchMonitor {
            v_stepped: vec![0.0; v0.len()],
            largest_kinetic: f.system().kinetic_energy(q0, v0),
            energy0,
            last_energy: energy0,
            energy_check,
            projection: Jump::default(),
            energy: Jump::default(),
            check: SingularityCheck::new(f.system().constraints()),
        }
    }

    /// The run's energy scale: the largest of `|E₀|` and the largest kinetic energy seen
    /// ([`Statistics::energy_scale`]).
    pub(crate) fn energy_scale(&self) -> f64 {
        self.largest_kinetic.max(self.energy0.abs())
    }

    /// Whether the energy check applies (conservative model, fixed step).
    pub(crate) fn watches_energy(&self) -> bool {
        self.energy_check
    }

    /// Keeps the stepped velocities `v` before the projection.
    pub(crate) fn before_projection(&mut self, v: &[f64]) {
        self.v_stepped.copy_from_slice(v);
    }

    /// Changes above round-off of the run's energy scale only: at rest there is no motion to
    /// switch.
    fn share(&self, change: f64) -> Option<f64> {
        self.share_with(change, self.largest_kinetic)
    }

    /// [`BranchMonitor::share`] with `largest` for the largest kinetic energy seen.
    fn share_with(&self, change: f64, largest: f64) -> Option<f64> {
        let scale = largest.max(self.energy0.abs());
        (largest > 0.0 && change > 1e-12 * scale).then(|| change / largest)
    }

    /// After the projection of the step ending at `t` to `(q, v)`: the share of the kinetic energy
    /// it removed ([`Statistics::max_projection_share`]).
    pub(crate) fn after_projection(
        &mut self,
        f: &dyn Formulation,
        t: f64,
        q: &[f64],
        v: &[f64],
        stats: &mut Statistics,
    ) -> Result<(), IntegrationError> {
        self.largest_kinetic = self.largest_kinetic.max(f.system().kinetic_energy(q, v));
        for (d, p) in self.v_stepped.iter_mut().zip(v) {
            *d -= p;
        }
        let share = self.share(f.system().kinetic_energy(q, &self.v_stepped));
        let mut involved = None;
        let check = &mut self.check;
        let confirm = || {
            involved = check.near_singular(f.system().constraints(), t, (q, v), NEAR, RANK_TOLERANCE);
            involved.is_some()
        };
        if let Some(before) = self
            .projection
            .record(share, BRANCH_SWITCH_SHARE, stats.steps == 0, confirm)
        {
            return Err(IntegrationError::BranchSwitch {
                time: t,
                sign: "the projection after the step removed",
                share: share.unwrap_or_default(),
                before,
                involved: involved.unwrap_or_default(),
            });
        }
        if let Some(share) = share {
            stats.max_projection_share = stats.max_projection_share.max(share);
        }
        Ok(())
    }

    /// The energy the step ending at `t` at `(q, v)` with `energy` started from, when its change
    /// of energy is a kick to undo: [`BRANCH_SWITCH_JUMP`] times the earlier steps' changes,
    /// near a singular position, for a conservative model at a fixed step.
    pub(crate) fn kicked(
        &mut self,
        f: &dyn Formulation,
        t: f64,
        (q, v): (&[f64], &[f64]),
        energy: dalembert_system::Energy,
        first: bool,
    ) -> Option<f64> {
        if !self.energy_check || first {
            return None;
        }
        let largest = self.largest_kinetic.max(energy.kinetic);
        let share = self.share_with((energy.total() - self.last_energy).abs(), largest)?;
        (share > BRANCH_SWITCH_JUMP * self.energy.reference
            && self
                .check
                .is_near_singular(f.system().constraints(), t, (q, v), NEAR, RANK_TOLERANCE))
        .then_some(self.last_energy)
    }

    /// After the step ending at `t` at the state `(q, v)` with `energy` (the monitor's, so nothing
    /// is evaluated twice per step).
    pub(crate) fn after_step(
        &mut self,
        f: &dyn Formulation,
        t: f64,
        (q, v): (&[f64], &[f64]),
        energy: dalembert_system::Energy,
        first: bool,
    ) -> Result<(), IntegrationError> {
        self.largest_kinetic = self.largest_kinetic.max(energy.kinetic);
        if !self.energy_check {
            return Ok(());
        }
        let energy = energy.total();
        let share = self.share((energy - self.last_energy).abs());
        self.last_energy = energy;
        let mut involved = None;
        let check = &mut self.check;
        let confirm = || {
            involved = check.near_singular(f.system().constraints(), t, (q, v), NEAR, RANK_TOLERANCE);
            involved.is_some()
        };
        match self.energy.record(share, BRANCH_SWITCH_ENERGY, first, confirm) {
            Some(before) => Err(IntegrationError::BranchSwitch {
                time: t,
                sign: "the energy of this conservative model changed in one step by",
                share: share.unwrap_or_default(),
                before,
                involved: involved.unwrap_or_default(),
            }),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Feeds `shares` to a fresh [`Jump`] with the projection limit; the index of the first that
    /// counts as a switch.
    fn first_switch(shares: impl IntoIterator<Item = f64>) -> Option<usize> {
        let mut jump = Jump::default();
        shares
            .into_iter()
            .enumerate()
            .find_map(|(k, s)| jump.record(Some(s), BRANCH_SWITCH_SHARE, k == 0, || true).map(|_| k))
    }

    #[test]
    fn a_lone_jump_above_the_limit_counts() {
        // 100 steps drifting by 1e-9, then one removing 5e-3 (the N-four-bar's switches removed
        // 4.6e-3 and 9.0e-3): the 101st step.
        let shares = std::iter::repeat_n(1e-9, 100).chain([5e-3]);
        assert_eq!(first_switch(shares), Some(100));
    }

    #[test]
    fn a_coarse_step_drifting_alike_every_step_never_counts() {
        // 1e-2 on every step: above the limit, but never 100 times the steps before.
        assert_eq!(first_switch(std::iter::repeat_n(1e-2, 10_000)), None);
    }

    #[test]
    fn the_start_is_forgotten_at_the_memory_rate() {
        // A start from rest whose first steps' drift is the whole kinetic energy (share 1), then
        // steps of 1e-12: a later 2e-3 counts once 1 × 0.99^k < 2e-3 / 100, i.e. after
        // k > ln(2e-5) / ln(0.99) = 1076.5 steps; before that it is within the memory.
        let at = |k: usize| first_switch([1.0].into_iter().chain(std::iter::repeat_n(1e-12, k - 1)).chain([2e-3]));
        assert_eq!(at(1070), None);
        assert_eq!(at(1080), Some(1080));
    }

    #[test]
    fn the_first_step_and_unconfirmed_jumps_do_not_count() {
        let mut jump = Jump::default();
        assert_eq!(jump.record(Some(0.5), BRANCH_SWITCH_SHARE, true, || true), None);
        let mut jump = Jump::default();
        jump.record(Some(1e-9), BRANCH_SWITCH_SHARE, true, || true);
        // C_q well conditioned after the step (confirm says no): not a branch switch.
        assert_eq!(jump.record(Some(0.5), BRANCH_SWITCH_SHARE, false, || false), None);
    }
}
