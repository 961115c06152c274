//! Shared helpers of the integrator tests (included with `mod common;`).
#![allow(dead_code)]

use dalembert_augmented::Augmented;
use dalembert_integrators::{integrate, IntegrationFailure, IntegratorOptions, Statistics};
use dalembert_testkit::Mechanism;

/// Runs `mech` to `t_end` with the augmented formulation; returns the final state and statistics.
pub fn run(
    mech: &Mechanism,
    t_end: f64,
    opts: &IntegratorOptions,
) -> Result<(Vec<f64>, Vec<f64>, Statistics), IntegrationFailure> {
    let mut f = Augmented::with_defaults(mech.model.clone()).unwrap();
    let mut last = (mech.q.clone(), mech.qd.clone());
    let stats = integrate(&mut f, 0.0, t_end, &mech.q, &mech.qd, opts, &mut |s| {
        last = (s.q.to_vec(), s.qd.to_vec());
    })?;
    Ok((last.0, last.1, stats))
}

/// Largest absolute difference.
pub fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
}
