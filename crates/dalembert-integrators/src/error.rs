//! Integration failures: always with the time and the cause.

use crate::Statistics;
use dalembert_system::DynamicsError;
use thiserror::Error;

/// Why an integration stopped early.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum IntegrationError {
    /// The formulation failed (singular matrix, redundant constraints, non-finite state, …).
    #[error("integration stopped: {0}")]
    Dynamics(#[from] DynamicsError),
    /// The adaptive step fell below the minimum.
    #[error("t = {time}: step size {step:e} below the minimum {min_step:e} (error estimate {error:.3e}); the problem may be stiff or singular here")]
    StepSizeTooSmall {
        /// Time.
        time: f64,
        /// The step that was rejected.
        step: f64,
        /// The minimum allowed.
        min_step: f64,
        /// The scaled error estimate of the last attempt.
        error: f64,
    },
    /// The state grew without bound (an explicit step beyond its stability limit).
    #[error("t = {time}: the solution diverged ({what}); the step {step:e} s is probably beyond the method's stability limit")]
    Diverged {
        /// Time.
        time: f64,
        /// What grew.
        what: String,
        /// The step in use.
        step: f64,
    },
    /// Invalid options.
    #[error("invalid integrator options: {0}")]
    Options(String),
    /// The caller asked the run to stop (the cancellation flag of [`crate::integrate_cancellable`],
    /// e.g. set on Ctrl-C); every sample up to `time` has been observed.
    #[error("t = {time}: interrupted")]
    Interrupted {
        /// Time of the last accepted step.
        time: f64,
    },
}

/// An error together with the statistics of the run up to it.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{error}")]
pub struct IntegrationFailure {
    /// The cause.
    pub error: IntegrationError,
    /// Statistics up to the failure.
    pub statistics: Box<Statistics>,
}
