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
const TWO: &[&str] = &["s", "u"];

#[derive(Debug)]
struct LinkedMasses {
    layout: Layout,
    pattern: ConstraintPattern,
    m: [f64; 2],
    k: f64,
    d: f64,
}

impl LinkedMasses {
    /// `q_labels` per body: one coordinate (`v = q̇`), or two positions for one velocity (a body
    /// kind whose velocities are not position rates).
    fn new(m: [f64; 2], k: f64, d: f64, q_labels: &'static [&'static str]) -> Self {
        let layout = Layout::new([("first", q_labels, LINE), ("second", q_labels, LINE)]);
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
    let sys: Arc<dyn MultibodySystem> = Arc::new(LinkedMasses::new(m, k, d, LINE));
    let formulations: Vec<Box<dyn Formulation>> = vec![
        Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
        Box::new(Embedding::with_defaults(sys.clone())),
        Box::new(Amalgamated::with_defaults(sys.clone())),
    ];
    let opts = IntegratorOptions::fixed(Method::Rk4, 1e-3, 0.25);
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

/// A system whose velocities are not position rates (two positions per velocity here) is refused by
/// the integrators in one line, not run on a wrong assumption (they still form `q + h v`).
#[test]
fn integrators_refuse_velocities_that_are_not_position_rates() {
    let sys: Arc<dyn MultibodySystem> = Arc::new(LinkedMasses::new([1.0, 1.0], 1.0, 0.3, TWO));
    let mut f = Augmented::with_defaults(sys).unwrap();
    let opts = IntegratorOptions::fixed(Method::Rk4, 1e-3, 0.1);
    let e = integrate(&mut f, 0.0, 0.1, &[0.0, 0.0, 0.3, 0.0], &[0.0, 0.0], &opts, &mut |_| {}).unwrap_err();
    assert_eq!(
        e.to_string().lines().next().unwrap_or_default(),
        "invalid integrator options: the integrators keep positions and velocities in one layout (v = dq/dt); this system has 4 positions and 2 velocities: not supported yet"
    );
}
