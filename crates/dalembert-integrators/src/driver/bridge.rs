//! Across a singular position with checked steps: where an adaptive method's steps collapse at a
//! position where links line up (`SingularPassGuard`), the error control would shrink them until
//! the drift of the state decides the branch. A fixed-step method with projection passes there,
//! its steps jumping the singular instant (docs/stability.md); the bridge does the same with the
//! adaptive method's own steps, taken whatever their error estimate says, and checks each:
//!
//! - from the state before the collapse, one step of `H` (the largest step the run had taken) and
//!   two of `H/2`, each normalized and projected;
//! - the two results must agree to the method's tolerances (`rtol`, `atol`; root-mean-square
//!   norm as the method's own, after dividing by `2⁵ − 1`, the step-doubling estimate of a
//!   fifth-order method): landing on one branch with one step size and on the other with the
//!   other is a difference of the order of the state, far above it;
//! - each trial step's projection may remove at most [`FAR_OFF`] of the kinetic energy;
//! - on agreement the two half steps are taken again as steps of the run (dense output, monitors),
//!   and the run goes on adaptively from `t + H`; otherwise `H` is halved, down to
//!   [`SMALLEST`] of the first, after which the run stops with the guard's `SingularPass`.
//!
//! A run that collapses more than [`MAX_CONSECUTIVE`] times without an accepted step of its own
//! between stops too (a dead point is no pass).

use super::{normalize, project};
use crate::{Method, Stabilization, Stepper};
use dalembert_system::Formulation;

/// The smallest bridge step, as a fraction of the first tried.
const SMALLEST: f64 = 1.0 / 64.0;

/// Share of the kinetic energy a trial step's projection may remove. Measured on
/// `scenes/driven-four-bar.toml` with dopri5 at its first change point: steps of 49, 25 and 12 ms
/// removed 9.2, 1.3 and 0.14 of it; the 6.2 ms step the bridge took removed 2.1e-2, and its result
/// matches RK4 at 1 ms to the printed digits.
const FAR_OFF: f64 = 0.1;

/// Bridges in a row (no accepted step of the method between them) before the run stops.
const MAX_CONSECUTIVE: u32 = 8;

/// Scratch state of the bridge, allocated with the run.
pub(super) struct Bridge {
    /// The state before the bridge.
    saved: Vec<f64>,
    /// The velocities of a trial step before its projection.
    stepped: Vec<f64>,
    /// The result of the whole step.
    whole: Vec<f64>,
    rtol: f64,
    atol: f64,
    consecutive: u32,
}

impl Bridge {
    /// Scratch for states of length `len`; the tolerances of `method` (1e-6 and 1e-9 for one
    /// without them).
    pub(super) fn new(len: usize, method: &Method) -> Self {
        Bridge {
            saved: vec![0.0; len],
            stepped: vec![0.0; len],
            whole: vec![0.0; len],
            rtol: method.get("rtol").unwrap_or(1e-6),
            atol: method.get("atol").unwrap_or(1e-9),
            consecutive: 0,
        }
    }

    /// The method took a step of its own.
    pub(super) fn steady(&mut self) {
        self.consecutive = 0;
    }

    /// From `(t, y)` across the singular position: `Some(h)` when one step of `h` and two of
    /// `h/2` agree (the caller then takes the two half steps again, as steps of its own with dense
    /// output and monitors: [`super::integration`]); `None` when no checked step passed. Either
    /// way `y` is back at the state it was given and the method is told so.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn find(
        &mut self,
        f: &mut dyn Formulation,
        stepper: &mut dyn Stepper,
        y: &mut [f64],
        t: f64,
        first: f64,
        n_q: usize,
        stabilization: Stabilization,
    ) -> Option<f64> {
        self.consecutive += 1;
        if self.consecutive > MAX_CONSECUTIVE || first.is_nan() || first <= 0.0 {
            return None;
        }
        self.saved.copy_from_slice(y);
        let mut h = first;
        let mut found = None;
        while h >= first * SMALLEST {
            if self.agree(f, stepper, y, t, h, n_q, stabilization) {
                found = Some(h);
                break;
            }
            h *= 0.5;
        }
        y.copy_from_slice(&self.saved);
        stepper.state_changed();
        found
    }

    /// The state before the last [`Bridge::find`].
    pub(super) fn saved(&self) -> &[f64] {
        &self.saved
    }

    /// Whether one step of `h` and two of `h/2` from the saved state agree; leaves `y` scratch.
    #[allow(clippy::too_many_arguments)]
    fn agree(
        &mut self,
        f: &mut dyn Formulation,
        stepper: &mut dyn Stepper,
        y: &mut [f64],
        t: f64,
        h: f64,
        n_q: usize,
        stabilization: Stabilization,
    ) -> bool {
        let saved = &self.saved;
        let stepped = &mut self.stepped;
        let mut steps = |state: &mut [f64], parts: usize| -> bool {
            state.copy_from_slice(saved);
            stepper.state_changed();
            let hs = h / parts as f64;
            for k in 0..parts {
                let ts = t + k as f64 * hs;
                f.begin_step();
                if !matches!(stepper.step_unchecked(f, ts, hs, state), Ok(true)) {
                    return false;
                }
                normalize(f, state, n_q);
                stepped.copy_from_slice(state);
                if project(f, ts + hs, state, n_q, stabilization).is_err() {
                    return false;
                }
                stepper.state_changed();
                // A step that lands far off the constraints (its projection removing more than
                // FAR_OFF of the kinetic energy) is no check of anything.
                let (q, v) = state.split_at(n_q);
                for (d, p) in stepped[n_q..].iter_mut().zip(v) {
                    *d -= p;
                }
                let s = f.system();
                let (before, after) = (s.kinetic_energy(&saved[..n_q], &saved[n_q..]), s.kinetic_energy(q, v));
                if s.kinetic_energy(q, &stepped[n_q..]) > FAR_OFF * before.max(after) {
                    return false;
                }
            }
            true
        };
        let mut whole = std::mem::take(&mut self.whole);
        let ok = steps(&mut whole, 1) && steps(y, 2);
        let agree = ok && {
            let sum: f64 = whole
                .iter()
                .zip(y.iter())
                .map(|(a, b)| {
                    let scale = self.atol + self.rtol * a.abs().max(b.abs());
                    ((a - b) / scale).powi(2)
                })
                .sum();
            let rms = (sum / whole.len().max(1) as f64).sqrt() / 31.0;
            rms <= 1.0
        };
        self.whole = whole;
        agree
    }
}
