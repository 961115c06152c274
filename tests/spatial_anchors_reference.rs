//! The spatial scenes of `shared/anchors` (chain3d N = 1, 2, 4, 8; heavytop; slidercrank3d) against
//! the anchors' reference states at t = 1 s (`tests/data/anchors_reference_spatial.json`, copied
//! from `shared/anchors/results/reference_spatial.json`: scipy DOP853 at rtol = atol = 1e-12 on
//! minimal-coordinate tree equations, cross-checked there against a body KKT model to 1e-10 and,
//! for the heavy top, against Kynema's published values to 1e-7).
//!
//! Every formulation with Dormand–Prince at rtol = atol = 1e-11: the position error (centres of
//! mass, and the angle between computed and reference orientations) is held to 1e-7 and the
//! velocity error to 1e-6 (the heavy top spins at 150 rad/s): a few hundred times the integration
//! tolerance, far below any modelling error (a wrong inertia, axis or joint point moves these
//! states by 1e-3 or more).

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::embedding::Embedding;
use dalembert::integrators::{integrate, IntegratorOptions, Method};
use dalembert::spatial::Model;
use dalembert::system::{Formulation, MultibodySystem};
use dalembert_testkit::spatial;
use std::sync::Arc;

fn reference(scene: &str) -> Vec<Vec<f64>> {
    let text = include_str!("data/anchors_reference_spatial.json");
    let json: serde_json::Value = serde_json::from_str(text).unwrap();
    serde_json::from_value(json["scenes"][scene]["bodies"].clone()).unwrap()
}

#[test]
fn spatial_anchor_scenes_match_the_reference_at_one_second() {
    let scenes: Vec<(String, Arc<Model>)> = [1, 2, 4, 8]
        .into_iter()
        .map(|n| (format!("chain3d/{n}"), spatial::chain3d(n)))
        .chain([
            ("heavytop/1".to_string(), spatial::heavy_top()),
            ("slidercrank3d/1".to_string(), spatial::slider_crank_3d()),
        ])
        .collect();
    let opts = IntegratorOptions::fixed(Method::dopri5(1e-11, 1e-11), 1e-4, 1.0);
    for (name, model) in scenes {
        let rows = reference(&name);
        assert_eq!(rows.len(), model.bodies().len(), "{name}");
        let sys: Arc<dyn MultibodySystem> = model.clone();
        let (q0, v0) = model.initial_state();
        let formulations: Vec<Box<dyn Formulation>> = vec![
            Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
            Box::new(Embedding::with_defaults(sys.clone())),
            Box::new(Amalgamated::with_defaults(sys.clone())),
        ];
        for mut f in formulations {
            let mut end = None;
            integrate(f.as_mut(), 0.0, 1.0, &q0, &v0, &opts, &mut |s| {
                if s.t == 1.0 {
                    end = Some((s.q.to_vec(), s.qd.to_vec()));
                }
            })
            .unwrap_or_else(|e| panic!("{name} {}: {e}", f.name()));
            let (q, v) = end.expect("a sample at 1 s");
            let (pos, vel) = spatial::state_errors(&q, &v, &rows);
            assert!(
                pos < 1e-7 && vel < 1e-6,
                "{name} {}: position error {pos:e}, velocity error {vel:e}",
                f.name()
            );
        }
    }
}
