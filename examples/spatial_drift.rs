//! Measures what the normalization of Euler parameters buys (figures in `docs/spatial.md`): the
//! anchors' heavy top (10 s) and a torque-free asymmetric body (100 s), RK4 and Dormand–Prince,
//! with the library's normalization after every step and with it switched off (a wrapper whose
//! `normalize` does nothing). Prints `max ||p| − 1|`, the energy drift and the largest constraint
//! violation.
//!
//! ```sh
//! cargo run --release --example spatial_drift
//! ```

use dalembert::augmented::Augmented;
use dalembert::integrators::{integrate, IntegratorOptions, Method};
use dalembert::spatial::{Body, Model, ModelBuilder};
use dalembert::system::{BlockDiagonal, ConstraintSet, DynamicsError, Layout, MultibodySystem};
use std::sync::Arc;

/// The model with `normalize` switched off.
#[derive(Debug)]
struct Unnormalized(Arc<Model>);

impl MultibodySystem for Unnormalized {
    fn layout(&self) -> &Layout {
        self.0.layout()
    }
    fn constraints(&self) -> &dyn ConstraintSet {
        self.0.constraints()
    }
    fn mass(&self, q: &[f64], out: &mut BlockDiagonal) {
        self.0.mass(q, out)
    }
    fn mass_is_constant(&self) -> bool {
        true
    }
    fn reference_positions(&self) -> Vec<f64> {
        self.0.reference_positions()
    }
    fn applied_forces(&self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        self.0.applied_forces(t, q, v, out)
    }
    fn check_forces(&self, t: f64, q: &[f64], v: &[f64], q_e: &[f64]) -> Result<(), DynamicsError> {
        self.0.check_forces(t, q, v, q_e)
    }
    fn position_rates(&self, q: &[f64], v: &[f64], out: &mut [f64]) {
        self.0.position_rates(q, v, out)
    }
    fn integrate_positions(&self, q: &mut [f64], v: &[f64], h: f64) {
        self.0.integrate_positions(q, v, h)
    }
    fn kinetic_energy(&self, q: &[f64], v: &[f64]) -> f64 {
        self.0.kinetic_energy(q, v)
    }
    fn potential_energy(&self, t: f64, q: &[f64]) -> f64 {
        self.0.potential_energy(t, q)
    }
    fn is_conservative(&self) -> bool {
        self.0.is_conservative()
    }
    fn bodies_without_inertia(&self) -> Vec<String> {
        self.0.bodies_without_inertia()
    }
}

fn measure(name: &str, model: &Arc<Model>, t_end: f64) {
    let (q0, v0) = model.initial_state();
    let methods = [
        ("RK4 h = 1e-3", IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.01)),
        ("RK4 h = 1e-4", IntegratorOptions::fixed(Method::rk4(), 1e-4, 0.01)),
        (
            "dopri5 1e-8",
            IntegratorOptions::fixed(Method::dopri5(1e-8, 1e-8), 1e-3, 0.01),
        ),
    ];
    for (label, opts) in methods {
        for normalized in [true, false] {
            let sys: Arc<dyn MultibodySystem> = if normalized {
                model.clone()
            } else {
                Arc::new(Unnormalized(model.clone()))
            };
            let mut f = Augmented::with_defaults(sys.clone()).expect("formulation");
            let e0 = sys.kinetic_energy(&q0, &v0) + sys.potential_energy(0.0, &q0);
            let (mut unit, mut de) = (0.0f64, 0.0f64);
            let t0 = std::time::Instant::now();
            let result = integrate(&mut f, 0.0, t_end, &q0, &v0, &opts, &mut |s| {
                for c in s.q.chunks_exact(7) {
                    let n = (c[3] * c[3] + c[4] * c[4] + c[5] * c[5] + c[6] * c[6]).sqrt();
                    unit = unit.max((n - 1.0).abs());
                }
                de = de.max((s.energy - e0).abs() / e0.abs().max(1.0));
            });
            let wall = t0.elapsed().as_secs_f64();
            match result {
                Ok(stats) => println!(
                    "{name:<22} {label:<13} normalize {normalized:<5}  max ||p|-1| {unit:.1e}  energy {de:.1e} (relative)  max |C| {:.1e}  {wall:.2} s",
                    stats.max_constraint_violation
                ),
                Err(e) => println!("{name:<22} {label:<13} normalize {normalized:<5}  stopped: {}", e.error),
            }
        }
    }
}

fn main() {
    measure("heavy top (anchors)", &dalembert_testkit::spatial::heavy_top(), 10.0);
    let mut b = ModelBuilder::new([0.0; 3]);
    b.body(Body::new("brick", 1.0, [1.0, 2.0, 3.0]).moving([0.0; 3], [0.1, 2.0, 0.1]));
    measure("torque-free brick", &Arc::new(b.build().expect("model")), 100.0);
}
