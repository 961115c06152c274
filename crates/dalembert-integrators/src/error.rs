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
    #[error("t = {t}: step size {step:e} below the minimum {min_step:e} (error estimate {error:.3e}); the problem may be stiff or singular here", t = dalembert_system::Shortest(*.time))]
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
    /// The state grew without bound (an explicit step beyond its stability limit; for an
    /// implicit method, what its [`Stepper::divergence_hint`](crate::Stepper::divergence_hint)
    /// says).
    #[error("t = {t}: the solution diverged ({what}) at step {step:e} s; {hint}", t = dalembert_system::Shortest(*.time))]
    Diverged {
        /// Time.
        time: f64,
        /// What grew.
        what: String,
        /// The step in use.
        step: f64,
        /// The likely cause, from the method.
        hint: String,
    },
    /// An adaptive method's steps collapsed at a singular position of a closed chain (`C_q` nearly
    /// rank deficient: links lining up). Stepping on would let the motion leave on the other
    /// branch without notice, so the run stops here.
    #[error("t = {t}: {method}'s steps collapse (to {step:.1e} s) at a singular position of the mechanism: the constraint Jacobian is nearly rank deficient (equations involved: {}); {advice}", list(.involved), t = dalembert_system::Shortest(*.time))]
    SingularPass {
        /// Time of the last accepted step.
        time: f64,
        /// The integrator.
        method: &'static str,
        /// The step the error control asked for.
        step: f64,
        /// The equations that become dependent.
        involved: Vec<dalembert_system::EquationRef>,
        /// Why the method cannot go on there, and what to pick instead.
        advice: &'static str,
    },
    /// A step at a singular position of a closed chain (links lining up) looked like a departure
    /// from the branch of the motion: the step's projection removed a large share of the kinetic
    /// energy at once ([`crate::BRANCH_SWITCH_SHARE`]), or the energy of a conservative model
    /// jumped and could not be given back ([`crate::BRANCH_SWITCH_ENERGY`]). Either sign also
    /// follows a step kicked by a stage near the singular position that kept its branch
    /// (`docs/stability.md`, "Kicks at singular positions"); the run cannot tell the two apart
    /// and stops there rather than go on with another motion; every sample before it has been
    /// observed.
    #[error("t = {t}: {sign} {share:.1e} of the largest kinetic energy (earlier steps up to {before:.1e}) near a singular position of the mechanism (constraint Jacobian nearly rank deficient; equations involved: {}): the step left its branch there or was kicked off it by a stage near that position, and the run stops here rather than go on along another branch; where the steps fall near that position decides it: retry with another step size (docs/stability.md)", list(.involved), t = dalembert_system::Shortest(*.time))]
    BranchSwitch {
        /// Time at the end of the step.
        time: f64,
        /// What was measured: the kinetic energy the projection removed, or the change of energy.
        sign: &'static str,
        /// The share of the run's largest kinetic energy.
        share: f64,
        /// The shares of the steps before (decaying maximum).
        before: f64,
        /// The equations that become dependent at the singular position.
        involved: Vec<dalembert_system::EquationRef>,
    },
    /// Invalid options.
    #[error("invalid integrator options: {0}")]
    Options(String),
    /// A step of the run could not be taken again on a model with a parameter changed, so the
    /// run's sensitivity to it cannot follow (`docs/sensitivities.md`).
    #[error("t = {t}: the sensitivity to '{parameter}' stops here: {what}", t = dalembert_system::Shortest(*.time))]
    Sensitivity {
        /// Time at the start of the step.
        time: f64,
        /// The parameter.
        parameter: String,
        /// What failed.
        what: String,
    },
    /// The caller asked the run to stop (the cancellation flag of [`crate::integrate_cancellable`],
    /// e.g. set on Ctrl-C); every sample up to `time` has been observed.
    #[error("t = {t}: interrupted", t = dalembert_system::Shortest(*.time))]
    Interrupted {
        /// Time of the last accepted step.
        time: f64,
    },
}

impl IntegrationError {
    /// The time the integration stopped at, where the error carries it.
    pub fn time(&self) -> Option<f64> {
        match self {
            IntegrationError::Dynamics(d) => d.time(),
            IntegrationError::StepSizeTooSmall { time, .. }
            | IntegrationError::Diverged { time, .. }
            | IntegrationError::SingularPass { time, .. }
            | IntegrationError::BranchSwitch { time, .. }
            | IntegrationError::Sensitivity { time, .. }
            | IntegrationError::Interrupted { time } => Some(*time),
            IntegrationError::Options(_) => None,
        }
    }
}

use dalembert_system::error::list;

/// An error together with the statistics of the run up to it.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{error}")]
pub struct IntegrationFailure {
    /// The cause.
    pub error: IntegrationError,
    /// Statistics up to the failure.
    pub statistics: Box<Statistics>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use dalembert_system::EquationRef;

    /// A singular pass of a large mechanism names twelve equations and counts the rest, so the
    /// message stays one readable line (the N-four-bar with N = 40 involves 121).
    #[test]
    fn singular_pass_lists_twelve_equations_and_counts_the_rest() {
        let involved: Vec<EquationRef> = (0..121)
            .map(|k| EquationRef {
                constraint: k,
                name: format!("O{k}"),
                equation: 0,
                label: "x",
            })
            .collect();
        let msg = IntegrationError::SingularPass {
            time: 0.72,
            method: "dopri5",
            step: 8.4e-6,
            involved,
            advice: "",
        }
        .to_string();
        assert!(msg.contains("'O11' (x) and 109 more)"), "{msg}");
        assert!(!msg.contains("'O12'"), "{msg}");
    }
}
