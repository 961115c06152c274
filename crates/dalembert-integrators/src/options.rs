//! The settings of one integration run.

use crate::{Method, Stabilization};

/// Settings of one integration run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IntegratorOptions {
    /// Method, with its parameters.
    pub method: Method,
    /// How the constraints are kept (ignored by a method that keeps them itself).
    pub stabilization: Stabilization,
    /// Fixed step, or the initial step of an adaptive method (s). A fixed step is shortened, if
    /// needed, so that a whole number of steps spans each output interval.
    pub step: f64,
    /// Interval between output samples (s).
    pub output_every: f64,
    /// Smallest step an adaptive method, or a fixed-step method that halves its step on a
    /// rejected one, may take before it gives up (s).
    pub min_step: f64,
    /// Largest step an adaptive method may take (s); defaults to the output interval.
    pub max_step: f64,
    /// Integration stops with an error when the state grows past this many times its initial
    /// scale (blow-up of an unstable step), before non-finite numbers appear.
    pub divergence_factor: f64,
    /// True to integrate the work `W` of the non-conservative forces, drivers and friction
    /// along the run's steps, into each sample's [`crate::Sample::work`], for a model whose
    /// forces switch (contacts, friction, limits): the energy balance of such a run then does not
    /// depend on its output interval (`docs/energy.md`, "Along the steps"). It costs the power at
    /// every step's end (with friction or drivers, an evaluation). Off by default;
    /// `dalembert::Simulation`'s runs turn it on.
    pub work_along_steps: bool,
}

impl IntegratorOptions {
    /// `method` with step `h` (the initial step of an adaptive method), output every `every`, no
    /// stabilization.
    pub fn fixed(method: Method, h: f64, every: f64) -> Self {
        IntegratorOptions {
            method,
            stabilization: Stabilization::None,
            step: h,
            output_every: every,
            min_step: 1e-12,
            max_step: every,
            divergence_factor: 1e8,
            work_along_steps: false,
        }
    }

    /// The same options with the work integrated along the steps, or not
    /// ([`IntegratorOptions::work_along_steps`]).
    pub fn with_work_along_steps(mut self, on: bool) -> Self {
        self.work_along_steps = on;
        self
    }

    /// The same options with another stabilization.
    pub fn with_stabilization(mut self, stabilization: Stabilization) -> Self {
        self.stabilization = stabilization;
        self
    }
}
