//! The system seam carries a body kind the formulations have never seen: bodies with a single
//! coordinate on a line (no planar type anywhere). If formulations and integrators really know only
//! `dalembert-system`, all three run it unchanged and agree with the closed form.
//!
//! Two point masses `m₁`, `m₂` on a line, `x₁` tied to a wall by a spring `k`, `x₂ − x₁ − d = 0`
//! (a rigid link): one oscillator of mass `m₁ + m₂`,
//!
//! ```text
//! x₁(t) = A cos ωt,   ω² = k / (m₁ + m₂),   λ(t) = −m₂ ẍ₂ = m₂ ω² A cos ωt
//! ```
//!
//! (body 2's equation `m₂ ẍ₂ + λ ∂C/∂x₂ = 0` with `∂C/∂x₂ = 1`). RK4 at h = 1 ms over 2 s: its
//! global error is about `(ωh)⁴ ω t / 120 ≈ 1e-14` relative, so 1e-9 on `x₁` and on `λ` leaves room for
//! round-off only.

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::embedding::Embedding;
use dalembert::integrators::{integrate, IntegratorOptions, Method};
use dalembert::system::{
    BlockDiagonal, ConstraintPattern, ConstraintSet, ConstraintValues, DynamicsError, EquationRef, Formulation, Layout,
    MultibodySystem,
};
use std::sync::Arc;

const LINE: &[&str] = &["x"];

#[derive(Debug)]
struct LinkedMasses {
    layout: Layout,
    pattern: ConstraintPattern,
    m: [f64; 2],
    k: f64,
    d: f64,
}

impl LinkedMasses {
    fn new(m: [f64; 2], k: f64, d: f64) -> Self {
        let layout = Layout::new([("first", LINE, LINE), ("second", LINE, LINE)]);
        let pattern = ConstraintPattern::from_segments(1, &layout, [(0, 0), (0, 1)]);
        LinkedMasses {
            layout,
            pattern,
            m,
            k,
            d,
        }
    }
}

impl ConstraintSet for LinkedMasses {
    fn pattern(&self) -> &ConstraintPattern {
        &self.pattern
    }
    fn equation(&self, row: usize) -> EquationRef {
        EquationRef {
            constraint: row,
            name: "link".into(),
            equation: 0,
            label: "distance",
        }
    }
    fn values(&self) -> ConstraintValues {
        ConstraintValues::new(&self.pattern, 0)
    }
    fn evaluate(&self, _t: f64, q: &[f64], _v: &[f64], out: &mut ConstraintValues) {
        let (x1, x2) = (q[0], q[self.layout.bodies()[1].q_offset]);
        out.c[0] = x2 - x1 - self.d;
        out.c_t[0] = 0.0;
        out.gamma[0] = 0.0;
        out.jacobian.copy_from_slice(&[-1.0, 1.0]);
    }
}

impl MultibodySystem for LinkedMasses {
    fn layout(&self) -> &Layout {
        &self.layout
    }
    fn constraints(&self) -> &dyn ConstraintSet {
        self
    }
    fn mass(&self, _q: &[f64], out: &mut BlockDiagonal) {
        out.block_mut(0)[0] = self.m[0];
        out.block_mut(1)[0] = self.m[1];
    }
    fn mass_is_constant(&self) -> bool {
        true
    }
    fn applied_forces(&self, _t: f64, q: &[f64], _v: &[f64], out: &mut [f64]) {
        out[0] = -self.k * q[0];
        out[1] = 0.0;
    }
    fn check_forces(&self, _t: f64, _q: &[f64], _v: &[f64], _q_e: &[f64]) -> Result<(), DynamicsError> {
        Ok(())
    }
    fn kinetic_energy(&self, _q: &[f64], v: &[f64]) -> f64 {
        0.5 * (self.m[0] * v[0] * v[0] + self.m[1] * v[1] * v[1])
    }
    fn potential_energy(&self, _t: f64, q: &[f64]) -> f64 {
        0.5 * self.k * q[0] * q[0]
    }
    fn is_conservative(&self) -> bool {
        true
    }
    fn bodies_without_inertia(&self) -> Vec<String> {
        Vec::new()
    }
}

#[test]
fn every_formulation_runs_a_body_kind_it_has_never_seen() {
    let (m, k, d, a): ([f64; 2], f64, f64, f64) = ([1.5, 0.5], 8.0, 0.3, 0.2);
    let omega = (k / (m[0] + m[1])).sqrt();
    let sys: Arc<dyn MultibodySystem> = Arc::new(LinkedMasses::new(m, k, d));
    let formulations: Vec<Box<dyn Formulation>> = vec![
        Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
        Box::new(Embedding::with_defaults(sys.clone())),
        Box::new(Amalgamated::with_defaults(sys.clone())),
    ];
    let opts = IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.25);
    for mut f in formulations {
        let mut worst = (0.0f64, 0.0f64);
        let mut samples = 0;
        integrate(f.as_mut(), 0.0, 2.0, &[a, a + d], &[0.0, 0.0], &opts, &mut |s| {
            let x = a * (omega * s.t).cos();
            let lambda = m[1] * omega * omega * a * (omega * s.t).cos();
            worst.0 = worst.0.max((s.q[0] - x).abs());
            worst.1 = worst.1.max((s.lambda[0] - lambda).abs());
            samples += 1;
        })
        .unwrap_or_else(|e| panic!("{}: {e}", f.name()));
        assert_eq!(samples, 9, "{}", f.name());
        assert!(
            worst.0 < 1e-9 && worst.1 < 1e-9,
            "{}: x₁ off by {:e}, λ by {:e}",
            f.name(),
            worst.0,
            worst.1
        );
    }
}

/// Rotors whose orientation is stored as a unit complex number `(cos θ, sin θ)` (two positions) and
/// whose velocity is `ω = θ̇` (one): the planar analogue of Euler parameters with angular velocity.
/// Positions advance by rotation (`integrate_positions`), their rate is `(−sin θ, cos θ) ω`
/// (`position_rates`), and `normalize` restores the unit length.
///
/// Rotor 1 (inertia `I₁`) is held by a torsional spring `k`; rotor 2 (`I₂`) is geared to it by
/// `C = sin(θ₂ − θ₁ − d) = 0`, so `θ₁ = A cos ωt` with `ω² = k / (I₁ + I₂)` and (rotor 2's equation
/// `I₂ θ̈₂ + λ ∂C/∂θ₂ = 0`, `∂C/∂θ₂ = 1` on the branch `θ₂ = θ₁ + d`) `λ = I₂ ω² A cos ωt`.
#[derive(Debug)]
struct GearedRotors {
    layout: Layout,
    pattern: ConstraintPattern,
    inertia: [f64; 2],
    k: f64,
    d: f64,
}

const UNIT_COMPLEX: &[&str] = &["cos", "sin"];
const SPIN: &[&str] = &["omega"];

impl GearedRotors {
    fn new(inertia: [f64; 2], k: f64, d: f64) -> Self {
        let layout = Layout::new([("first", UNIT_COMPLEX, SPIN), ("second", UNIT_COMPLEX, SPIN)]);
        let pattern = ConstraintPattern::from_segments(1, &layout, [(0, 0), (0, 1)]);
        GearedRotors {
            layout,
            pattern,
            inertia,
            k,
            d,
        }
    }

    /// `θ₁` from the stored unit complex number.
    fn angle(q: &[f64]) -> f64 {
        q[1].atan2(q[0])
    }
}

impl ConstraintSet for GearedRotors {
    fn pattern(&self) -> &ConstraintPattern {
        &self.pattern
    }
    fn equation(&self, _row: usize) -> EquationRef {
        EquationRef {
            constraint: 0,
            name: "gear".into(),
            equation: 0,
            label: "angle",
        }
    }
    fn values(&self) -> ConstraintValues {
        ConstraintValues::new(&self.pattern, 0)
    }
    fn evaluate(&self, _t: f64, q: &[f64], v: &[f64], out: &mut ConstraintValues) {
        // Relative rotation φ = θ₂ − θ₁ − d as a unit complex number: z₂ z̄₁ e^{−id}.
        let (c1, s1, c2, s2) = (q[0], q[1], q[2], q[3]);
        let (cr, sr) = (c1 * c2 + s1 * s2, s2 * c1 - c2 * s1);
        let (cd, sd) = (self.d.cos(), self.d.sin());
        let (cphi, sphi) = (cr * cd + sr * sd, sr * cd - cr * sd);
        out.c[0] = sphi;
        out.c_t[0] = 0.0;
        out.jacobian.copy_from_slice(&[-cphi, cphi]);
        // C̈ = cos φ (ω̇₂ − ω̇₁) − sin φ (ω₂ − ω₁)², so Q_d = sin φ (ω₂ − ω₁)².
        let rel = if v.is_empty() { 0.0 } else { v[1] - v[0] };
        out.gamma[0] = sphi * rel * rel;
    }
    fn correct_positions(&self, q: &mut [f64], delta: &[f64]) {
        self.integrate_positions(q, delta, 1.0);
        self.normalize(q);
    }
}

impl MultibodySystem for GearedRotors {
    fn layout(&self) -> &Layout {
        &self.layout
    }
    fn constraints(&self) -> &dyn ConstraintSet {
        self
    }
    fn mass(&self, _q: &[f64], out: &mut BlockDiagonal) {
        out.block_mut(0)[0] = self.inertia[0];
        out.block_mut(1)[0] = self.inertia[1];
    }
    fn mass_is_constant(&self) -> bool {
        true
    }
    fn reference_positions(&self) -> Vec<f64> {
        vec![1.0, 0.0, 1.0, 0.0]
    }
    fn applied_forces(&self, _t: f64, q: &[f64], _v: &[f64], out: &mut [f64]) {
        out[0] = -self.k * Self::angle(q);
        out[1] = 0.0;
    }
    fn check_forces(&self, _t: f64, _q: &[f64], _v: &[f64], _q_e: &[f64]) -> Result<(), DynamicsError> {
        Ok(())
    }
    fn position_rates(&self, q: &[f64], v: &[f64], out: &mut [f64]) {
        for b in 0..2 {
            let (c, s) = (q[2 * b], q[2 * b + 1]);
            out[2 * b] = -s * v[b];
            out[2 * b + 1] = c * v[b];
        }
    }
    fn integrate_positions(&self, q: &mut [f64], v: &[f64], h: f64) {
        for b in 0..2 {
            let (c, s) = (q[2 * b], q[2 * b + 1]);
            let (cw, sw) = ((h * v[b]).cos(), (h * v[b]).sin());
            q[2 * b] = c * cw - s * sw;
            q[2 * b + 1] = s * cw + c * sw;
        }
    }
    fn normalize(&self, q: &mut [f64]) {
        for z in q.chunks_exact_mut(2) {
            let r = (z[0] * z[0] + z[1] * z[1]).sqrt();
            z.iter_mut().for_each(|x| *x /= r);
        }
    }
    fn kinetic_energy(&self, _q: &[f64], v: &[f64]) -> f64 {
        0.5 * (self.inertia[0] * v[0] * v[0] + self.inertia[1] * v[1] * v[1])
    }
    fn potential_energy(&self, _t: f64, q: &[f64]) -> f64 {
        0.5 * self.k * Self::angle(q).powi(2)
    }
    fn is_conservative(&self) -> bool {
        true
    }
    fn bodies_without_inertia(&self) -> Vec<String> {
        Vec::new()
    }
}

/// Largest error in `θ₁` and in `λ` over 2 s against the closed form, and the largest `|z| − 1`.
fn rotor_errors(f: &mut dyn Formulation, method: Method, h: f64) -> (f64, f64, f64) {
    let (inertia, k, d, a): ([f64; 2], f64, f64, f64) = ([1.5, 0.5], 8.0, 0.3, 0.2);
    let omega: f64 = (k / (inertia[0] + inertia[1])).sqrt();
    let q0 = [a.cos(), a.sin(), (a + d).cos(), (a + d).sin()];
    let opts = IntegratorOptions::fixed(method, h, 0.25);
    let mut worst = (0.0f64, 0.0f64, 0.0f64);
    integrate(f, 0.0, 2.0, &q0, &[0.0, 0.0], &opts, &mut |s| {
        let theta = a * (omega * s.t).cos();
        let lambda = inertia[1] * omega * omega * a * (omega * s.t).cos();
        worst.0 = worst.0.max((GearedRotors::angle(s.q) - theta).abs());
        worst.1 = worst.1.max((s.lambda[0] - lambda).abs());
        for z in s.q.chunks_exact(2) {
            worst.2 = worst.2.max(((z[0] * z[0] + z[1] * z[1]).sqrt() - 1.0).abs());
        }
    })
    .unwrap_or_else(|e| panic!("{} {method:?}: {e}", f.name()));
    worst
}

fn rotor_formulations() -> Vec<Box<dyn Formulation>> {
    let sys: Arc<dyn MultibodySystem> = Arc::new(GearedRotors::new([1.5, 0.5], 8.0, 0.3));
    vec![
        Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
        Box::new(Embedding::with_defaults(sys.clone())),
        Box::new(Amalgamated::with_defaults(sys)),
    ]
}

/// RK4 and Dormand–Prince integrate `q̇ = T(q) v` in the stored coordinates and normalize after each
/// step: the closed form to 1e-9 (RK4 at 1 ms: `(ωh)⁴ ω t / 120 ≈ 1e-14` relative, as above; dopri5
/// at rtol = atol = 1e-11), and `|z| = 1` to round-off (1e-14: normalized after every step).
#[test]
fn every_formulation_runs_bodies_whose_velocities_are_not_position_rates() {
    for mut f in rotor_formulations() {
        for method in [Method::rk4(), Method::dopri5(1e-11, 1e-11)] {
            let (theta, lambda, unit) = rotor_errors(f.as_mut(), method, 1e-3);
            assert!(
                theta < 1e-9 && lambda < 1e-9 && unit < 1e-14,
                "{} {method:?}: θ₁ off by {theta:e}, λ by {lambda:e}, |z| − 1 = {unit:e}",
                f.name()
            );
        }
    }
}

/// The one-step methods advance the stored rotation by `q ⊕ h v` and keep their order: halving the
/// step divides the error by 2 (semi-implicit Euler, first order: ratio ≥ 1.8) or by 4
/// (generalized-α on the Lie group, Brüls–Cardona–Arnold 2012, second order: ratio ≥ 3.5).
#[test]
fn one_step_methods_keep_their_order_on_the_rotation() {
    for mut f in rotor_formulations() {
        let mut methods = vec![(Method::symplectic_euler(), 1.8, 1e-3)];
        if f.is_index3_augmented() {
            methods.push((Method::generalized_alpha(0.8), 3.5, 4e-3));
        }
        for (method, ratio, h) in methods {
            let coarse = rotor_errors(f.as_mut(), method, h);
            let fine = rotor_errors(f.as_mut(), method, h / 2.0);
            assert!(
                coarse.0 / fine.0 >= ratio && coarse.2 < 1e-14 && fine.2 < 1e-14,
                "{} {method:?}: θ₁ errors {:e} (h) and {:e} (h/2), |z| − 1 up to {:e}",
                f.name(),
                coarse.0,
                fine.0,
                coarse.2.max(fine.2)
            );
        }
    }
}
