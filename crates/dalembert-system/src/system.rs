//! The seam: how formulations and integrators see a multibody system, whatever its bodies are.
//!
//! ```text
//! M(q) v̇ + C_qᵀ λ = Q(t, q, v)          C(q, t) = 0          q̇ = G(q) v  (advanced by integrate_positions)
//! ```
//!
//! `M` is block diagonal (one block per body, [`BlockDiagonal`]); `Q` holds every applied force
//! and the quadratic-velocity terms of the bodies' kinetic energy; the constraints are a fixed
//! pattern plus values ([`ConstraintSet`]). Planar bodies (`x, y, θ`, `v = q̇`) and spatial bodies
//! (Euler parameters, angular velocity) are two implementations; formulations and integrators use
//! only this trait.

use crate::{BlockDiagonal, ConstraintSet, DynamicsError, Layout};

/// A multibody system described to formulations and integrators.
pub trait MultibodySystem: Send + Sync + std::fmt::Debug {
    /// Where each body's positions and velocities sit.
    fn layout(&self) -> &Layout;

    /// The constraints.
    fn constraints(&self) -> &dyn ConstraintSet;

    /// Storage for the mass matrix: one block per body, of its velocity block's size.
    fn mass_storage(&self) -> BlockDiagonal {
        BlockDiagonal::zeros(self.layout().bodies().iter().map(|b| b.v_len()))
    }

    /// Writes `M(q)` into `out` (storage from [`MultibodySystem::mass_storage`]). Must not allocate.
    fn mass(&self, q: &[f64], out: &mut BlockDiagonal);

    /// True when `M` does not depend on `q` (then it need be written only once).
    fn mass_is_constant(&self) -> bool;

    /// A valid configuration at which `M`'s block structure (which blocks are positive definite,
    /// which diagonal) is representative: formulations choose their factorizations from it before
    /// they see a state. Default: all positions zero (right for planar bodies; Euler parameters need
    /// `p = (1, 0, 0, 0)`).
    fn reference_positions(&self) -> Vec<f64> {
        vec![0.0; self.layout().n_q()]
    }

    /// Writes (not adds) `Q(t, q, v)`: applied forces plus quadratic-velocity terms. Must not allocate.
    fn applied_forces(&self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]);

    /// `Ok` when `q_e` (from [`MultibodySystem::applied_forces`] at `(t, q, v)`) is finite; otherwise
    /// an error naming the force element at fault.
    fn check_forces(&self, t: f64, q: &[f64], v: &[f64], q_e: &[f64]) -> Result<(), DynamicsError>;

    /// `q̇ = T(q) v` into `out` (length `n_q`): the time derivative of the positions at velocity `v`.
    /// Default: `out = v`, right when `v = q̇`; a system whose velocities are not position rates
    /// (`n_q ≠ n_v`, e.g. Euler parameters with angular velocities) must override it. Explicit
    /// Runge–Kutta methods integrate `q̇ = T(q) v` in the `n_q` coordinates and then call
    /// [`MultibodySystem::normalize`]. Must not allocate.
    fn position_rates(&self, _q: &[f64], v: &[f64], out: &mut [f64]) {
        out.copy_from_slice(v);
    }

    /// `q ← q ⊕ h v`: advances the positions by velocity `v` over `h` (default `q + h v`, right when
    /// `v = q̇`). Must not allocate.
    fn integrate_positions(&self, q: &mut [f64], v: &[f64], h: f64) {
        q.iter_mut().zip(v).for_each(|(x, d)| *x += h * d);
    }

    /// The rates `δ̇` of chart coordinates `δ` about a fixed position `q₀`, `q = q₀ ⊕ δ`
    /// ([`MultibodySystem::integrate_positions`] with `h = 1`), when the velocity is `v`: `δ̇ = v`
    /// by default, right when `⊕` is `+`. A system that rotates by the exponential map must
    /// override it (`δ̇ = J_r(δ)⁻¹ ω'` for a body-frame rotation vector). Linearization uses it
    /// to write the position states' rates (`docs/statics.md`). Must not allocate.
    fn chart_rates(&self, _delta: &[f64], v: &[f64], out: &mut [f64]) {
        out.copy_from_slice(v);
    }

    /// Restores invariants of the position coordinates that the integration does not keep (e.g. unit
    /// Euler parameters). Default: nothing to do.
    fn normalize(&self, _q: &mut [f64]) {}

    /// The number of event functions ([`MultibodySystem::events`]): one per friction element
    /// ([`MultibodySystem::frictions`], first), one per joint limit
    /// ([`MultibodySystem::limits`], next) and one per contact element. Default 0.
    fn num_events(&self) -> usize {
        0
    }

    /// The event functions at `(t, q, v)` into `out` (length [`MultibodySystem::num_events`]):
    /// first each friction element's slip rate `w` (0 while `|w|` is within its stick speed, so
    /// that a sign change is a slip that stops or reverses, `docs/friction.md`), then each
    /// limit's distance to its nearer bound (`docs/limits.md`), then each contact's gap, positive apart and negative in contact, so that a sign change within a
    /// step is a contact beginning or ending there. The integration loop ends a step there
    /// (`docs/contact.md`, "Events"). Allocates nothing.
    fn events(&self, _t: f64, _q: &[f64], _v: &[f64], _out: &mut [f64]) {}

    /// The friction elements of the joints (`docs/friction.md`), in a fixed order. Default none.
    fn frictions(&self) -> &[crate::JointFriction] {
        &[]
    }

    /// The slip row of friction element `k` ([`MultibodySystem::frictions`]) at `(t, q, v)`.
    /// Allocates nothing. Default: an empty row.
    fn slip_row(&self, _k: usize, _t: f64, _q: &[f64], _v: &[f64], row: &mut crate::SlipRow) {
        row.clear();
    }

    /// The number of reaction loads the system computes from the motion, after its multipliers:
    /// a friction element's [`crate::JointFriction::load_rows`] index the multipliers `λ`
    /// extended by these ([`MultibodySystem::reaction_loads`]). A system whose joints are
    /// equations has its reactions in `λ` and none here; a tree in joint coordinates has no
    /// equations, and its joints' forces follow from the accelerations. Default 0.
    fn num_reaction_loads(&self) -> usize {
        0
    }

    /// The reaction loads at `(t, q, v)` under the accelerations `qdd` into `out` (length
    /// [`MultibodySystem::num_reaction_loads`]); with `response`, only their part linear in
    /// `qdd` (no velocities, no gravity, no applied force): the loads' change under a change
    /// `qdd` of the accelerations. Allocates nothing. Default: nothing.
    fn reaction_loads(&self, _t: f64, _q: &[f64], _v: &[f64], _qdd: &[f64], _response: bool, _out: &mut [f64]) {}

    /// The joint limits (`docs/limits.md`), in a fixed order. Default none.
    fn limits(&self) -> &[crate::JointLimit] {
        &[]
    }

    /// The row of limited joint `k` ([`MultibodySystem::limits`]) at `(t, q, v)` into `row`
    /// (its rate `w = g·v` and the bias of `ẇ`), and its coordinate `s` (zero in the file's
    /// configuration) as the result. Allocates nothing. Default: an empty row at 0.
    fn limit_row(&self, _k: usize, _t: f64, _q: &[f64], _v: &[f64], row: &mut crate::SlipRow) -> f64 {
        row.clear();
        0.0
    }

    /// The bodies (layout indices) whose coordinates each applied-force element reads and whose
    /// generalized forces it writes, one group per element; the quadratic-velocity terms and the
    /// mass of a body couple it only with itself and need no group. `None` when some element does
    /// not say (a user-written force): every body may then depend on every other. Implicit
    /// integrators take the sparsity of their iteration matrix from it
    /// ([`crate::TangentPattern`]). Default `None`.
    fn force_coupling(&self) -> Option<Vec<Vec<usize>>> {
        None
    }

    /// The dynamic residual `r = M(q) q̈ + C_qᵀ λ − Q(t, q, v)` into `r` (length `n_v`), with `mass`
    /// and `values` (from [`Self::mass_storage`] and the constraint set's `values()`) refreshed at
    /// `(t, q, v)`. Allocates nothing: implicit integrators call it in their Newton iterations.
    fn dynamics_residual(
        &self,
        t: f64,
        (q, v): (&[f64], &[f64]),
        (qdd, lambda): (&[f64], &[f64]),
        (mass, values): (&mut BlockDiagonal, &mut crate::ConstraintValues),
        r: &mut [f64],
    ) {
        self.constraints().evaluate(t, q, v, values);
        self.dynamics_residual_evaluated(t, (q, v), (qdd, lambda), (mass, values), r);
    }

    /// [`Self::dynamics_residual`] with `values` already evaluated at `(t, q, v)` (an implicit
    /// method that needed `C` there first: ALI3-P's multipliers `λ* + α C`). Refreshes `mass`.
    fn dynamics_residual_evaluated(
        &self,
        t: f64,
        (q, v): (&[f64], &[f64]),
        (qdd, lambda): (&[f64], &[f64]),
        (mass, values): (&mut BlockDiagonal, &crate::ConstraintValues),
        r: &mut [f64],
    ) {
        self.applied_forces(t, q, v, r);
        r.iter_mut().for_each(|x| *x = -*x);
        self.mass(q, mass);
        mass.mul_add(1.0, qdd, r);
        self.constraints().jacobian_transpose_mul_add(values, 1.0, lambda, r);
    }

    /// Adds the analytic tangent of the dynamic residual `r = M(q) q̈ + C_qᵀ λ − Q(t, q, v)` at
    /// `(t, q, v, q̈, λ)` to `out`: `∂r/∂q` (along the velocity coordinates, `q ⊕ ε e_j`) and
    /// `∂r/∂v`, on the pattern of [`crate::TangentPattern`]. Returns `false` when some element has
    /// no analytic derivatives (a user-written force or constraint): implicit integrators then
    /// difference the residual instead. Default `false`.
    fn residual_tangent(
        &self,
        _t: f64,
        (_q, _v): (&[f64], &[f64]),
        (_qdd, _lambda): (&[f64], &[f64]),
        _out: &mut crate::TangentValues<'_>,
    ) -> bool {
        false
    }

    /// For a system with a [`MultibodySystem::kinematic_tree`]: adds to `out` (one per joint) the
    /// joints' generalized forces at `(t, q, v)` that the tree's own joint forces do not hold
    /// (a model's torque laws about the joints' axes, [`crate::tree::JointAxisLaw`]), for the
    /// articulated-body solve. Default: none.
    fn add_joint_forces(&self, _t: f64, _q: &[f64], _v: &[f64], _out: &mut [f64]) {}

    /// The system as a kinematic tree in joint coordinates, when it is one ([`crate::JointSpace`]):
    /// with no constraint equations every formulation's equations are then `M q̈ = Q`, and the
    /// formulations solve them by the articulated-body algorithm ([`crate::tree::Articulated`])
    /// instead of forming `M`. Default `None`.
    fn kinematic_tree(&self) -> Option<&crate::KinematicTree> {
        None
    }

    /// Kinetic energy at `(q, v)`.
    fn kinetic_energy(&self, q: &[f64], v: &[f64]) -> f64;

    /// Potential energy of the conservative elements at `(t, q)`.
    fn potential_energy(&self, t: f64, q: &[f64]) -> f64;

    /// True when `T + V` is a first integral of the exact motion.
    fn is_conservative(&self) -> bool;

    /// True when some constraint equation is a driver (a prescribed motion, whose force does
    /// work: `docs/energy.md`, eq. E3). The default, true for any model with equations, is safe:
    /// it only makes the work along a run's steps evaluate the multipliers.
    fn is_driven(&self) -> bool {
        self.num_equations() > 0
    }

    /// The power of the applied forces that [`MultibodySystem::potential_energy`] does not
    /// count (dampers, actuators, applied forces and torques) at `(t, q, v)`: the rate at which
    /// they change `T + V` (`docs/energy.md`, eq. E2). Zero for a conservative model. Its work
    /// buffers are `scratch` ([`crate::power::PowerScratch::new`] for this model): it allocates
    /// nothing.
    ///
    /// The default is `vᵀ Q_e + dV/dt` along the motion (`dV/dt` by a central difference through
    /// [`MultibodySystem::integrate_positions`] over ±1e-6 s), which holds where
    /// [`MultibodySystem::applied_forces`] carries no inertial terms that do work (the spatial
    /// gyroscopic moment `−ω × J ω` does none); a model whose `Q_e` holds such terms overrides it.
    fn nonconservative_power(&self, t: f64, q: &[f64], v: &[f64], scratch: &mut crate::power::PowerScratch) -> f64 {
        self.applied_forces(t, q, v, &mut scratch.forces);
        let applied: f64 = v.iter().zip(&scratch.forces).map(|(a, b)| a * b).sum();
        applied + potential_rate(self, t, q, v, scratch)
    }

    /// Names of the bodies without mass or inertia (to explain a singular system).
    fn bodies_without_inertia(&self) -> Vec<String>;

    /// Number of constraint equations `m`.
    fn num_equations(&self) -> usize {
        self.constraints().num_equations()
    }

    /// The error for a singular system whose cause is not a rank-deficient `C_q`: `SingularMass`
    /// naming the bodies without mass or inertia when there are any, otherwise `Singular` with `what`.
    fn singular_mass_error(&self, t: f64, what: &str) -> DynamicsError {
        let bodies = self.bodies_without_inertia();
        if bodies.is_empty() {
            DynamicsError::Singular {
                time: t,
                what: what.to_string(),
            }
        } else {
            DynamicsError::SingularMass { time: t, bodies }
        }
    }

    /// `Ok` when every position and velocity is finite and the slices have the layout's lengths;
    /// otherwise the error names the body and the coordinate.
    fn check_state(&self, t: f64, q: &[f64], v: &[f64]) -> Result<(), DynamicsError> {
        let l = self.layout();
        for (what, expected, got) in [("q", l.n_q(), q.len()), ("v", l.n_v(), v.len())] {
            if expected != got {
                return Err(DynamicsError::WrongLength { what, expected, got });
            }
        }
        if crate::all_finite(q) && crate::all_finite(v) {
            return Ok(());
        }
        if let Some(i) = q.iter().position(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite {
                time: t,
                what: format!("position {}", l.describe_position(i)),
            });
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFinite {
                time: t,
                what: format!("velocity {}", l.describe_velocity(i)),
            });
        }
        Ok(())
    }

    /// `Ok` when every velocity-sized slice (`(name, length)` in `velocities`) has `n_v` entries and
    /// every equation-sized one has `m`; otherwise the error names the first slice that does not.
    fn check_lengths(
        &self,
        velocities: &[(&'static str, usize)],
        equations: &[(&'static str, usize)],
    ) -> Result<(), DynamicsError> {
        let (n, m) = (self.layout().n_v(), self.num_equations());
        let wrong = velocities
            .iter()
            .map(|&(w, l)| (w, l, n))
            .chain(equations.iter().map(|&(w, l)| (w, l, m)))
            .find(|&(_, l, e)| l != e);
        match wrong {
            None => Ok(()),
            Some((what, got, expected)) => Err(DynamicsError::WrongLength { what, expected, got }),
        }
    }

    /// The error for a non-finite acceleration at velocity coordinate `i`.
    fn non_finite_acceleration(&self, t: f64, i: usize) -> DynamicsError {
        let what = format!("acceleration of body '{}'", self.layout().velocity_owner(i).0.name);
        DynamicsError::NonFinite { time: t, what }
    }
}

/// `dV/dt` along the motion through `(t, q, v)`: a central difference over ±`H` s, positions
/// moved by [`MultibodySystem::integrate_positions`] (so that they stay on their manifold), with
/// error `O(H²)` and round-off `ε V / H`. The moved positions are `scratch`'s.
pub fn potential_rate<S: MultibodySystem + ?Sized>(
    system: &S,
    t: f64,
    q: &[f64],
    v: &[f64],
    scratch: &mut crate::power::PowerScratch,
) -> f64 {
    const H: f64 = 1e-6;
    let (ahead, behind) = (&mut scratch.ahead, &mut scratch.behind);
    ahead.copy_from_slice(q);
    behind.copy_from_slice(q);
    system.integrate_positions(ahead, v, H);
    system.integrate_positions(behind, v, -H);
    (system.potential_energy(t + H, ahead) - system.potential_energy(t - H, behind)) / (2.0 * H)
}
