//! The check that stops an adaptive method whose steps collapse at a singular position.

use crate::branch::RANK_TOLERANCE;
use crate::IntegrationError;
use dalembert_system::jacobian_svd::SingularityCheck;
use dalembert_system::Formulation;

/// Stops an adaptive method whose steps collapse at a singular position of a closed chain.
///
/// Near a position where links line up (a change point, the horizontal N-four-bar) the two motion
/// branches are `O(√ε)` apart in time for a constraint violation `ε`: an error-controlled step shrinks
/// toward the singular point (the accelerations grow as `1/σ_min(C_q)`) until it resolves the
/// slightly perturbed geometry of the drifted state, which decides the branch by that perturbation
/// (measured on `scenes/driven-four-bar.toml` with dopri5: steps of 1e-6 s, the rocker turning back
/// 3e-5 rad before the line, i.e. a silent switch to the other assembly). When a step falls below
/// `COLLAPSE` × the largest accepted step, `C_q` is checked (the run's [`SingularityCheck`], relative singular
/// value `NEAR`); at a nearly singular `C_q` the loop bridges the position with checked steps
/// ([`bridge`]) or, when no checked step passes, stops with the time and the equations involved.
/// A well-conditioned one (a stiff model) re-arms the check a factor 10 lower, so a stiff run pays
/// one SVD per decade of step size.
///
#[derive(Default)]
pub(super) struct SingularPassGuard {
    pub(super) largest: f64,
    /// Steps below this fraction of the largest are checked.
    armed_below: f64,
}

impl SingularPassGuard {
    const COLLAPSE: f64 = 1e-3;
    pub(super) const NEAR: f64 = 1e-3;

    /// After a bridge across the singular position: the next collapse is checked again.
    pub(super) fn rearm(&mut self) {
        self.armed_below = self.armed_below.max(Self::COLLAPSE);
    }

    pub(super) fn accepted(&mut self, h: f64) {
        if h > self.largest {
            self.largest = h;
            self.armed_below = self.armed_below.max(Self::COLLAPSE);
        }
    }

    pub(super) fn check(
        &mut self,
        f: &dyn Formulation,
        t: f64,
        y: &[f64],
        n_q: usize,
        next: f64,
        method: &'static str,
        singular: &mut SingularityCheck,
    ) -> Result<(), IntegrationError> {
        if next.is_nan() || next >= self.armed_below * self.largest {
            return Ok(());
        }
        self.armed_below = next / self.largest / 10.0;
        match singular.near_singular(f.system().constraints(), t, y.split_at(n_q), Self::NEAR, RANK_TOLERANCE) {
            Some(involved) => Err(IntegrationError::SingularPass {
                time: t,
                method,
                step: next,
                involved,
                advice: "an adaptive error-controlled step resolves the perturbed geometry there and may leave on the other branch, and no checked step bridged it, so the run stops: pass singular positions with ali3-p (augmented formulation) or a fixed-step rk4 with projection (docs/stability.md)",
            }),
            None => Ok(()),
        }
    }
}
