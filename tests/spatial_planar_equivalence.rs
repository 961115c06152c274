//! A planar mechanism built in 3D (every joint axis along z) gives the planar model's results: a
//! chain of three rods swinging in the x-y plane, modelled with the planar crate and with the
//! spatial one, through every formulation. Accelerations (`ẍ, ÿ, θ̈` against `ẍ, ÿ, ω̇'_z`, the
//! out-of-plane ones zero) and joint reaction forces agree to 1e-12 relative: the two models solve
//! different linear systems (3 vs 6 velocities per body, 2 vs 5 equations per hinge) for the same
//! motion, so only round-off separates them.

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::embedding::Embedding;
use dalembert::spatial::euler_parameters::from_axis_angle;
use dalembert::spatial::{Body, BodyRef, Joint, ModelBuilder};
use dalembert::system::{Formulation, MultibodySystem};
use dalembert_testkit::mechanisms;
use nalgebra::Vector3;
use std::sync::Arc;

/// Every registered formulation with its defaults.
fn formulations(sys: &Arc<dyn MultibodySystem>) -> Vec<Box<dyn Formulation>> {
    dalembert::FORMULATIONS
        .iter()
        .map(|e| (e.build)(sys.clone(), &Default::default()).unwrap_or_else(|err| panic!("{}: {err}", e.name)))
        .collect()
}

fn solve(f: &mut dyn Formulation, q: &[f64], v: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let (mut a, mut lambda) = (vec![0.0; v.len()], vec![0.0; f.system().num_equations()]);
    f.accelerations(0.0, q, v, None, &mut a, &mut lambda)
        .unwrap_or_else(|e| panic!("{}: {e}", f.name()));
    (a, lambda)
}

/// The planar model's accelerations and reactions at its state (augmented formulation), with the
/// scales the comparisons are relative to.
struct PlanarReference {
    a: Vec<f64>,
    reactions: Vec<dalembert::constraints::Reaction>,
    a_scale: f64,
    f_scale: f64,
}

fn planar_reference(planar: &mechanisms::Mechanism) -> PlanarReference {
    let sys: Arc<dyn MultibodySystem> = planar.model.clone();
    let (a, lambda) = solve(&mut Augmented::with_defaults(sys).unwrap(), &planar.q, &planar.qd);
    let reactions = planar.model.constraints().reactions_at(0.0, &planar.q, &lambda);
    PlanarReference {
        a_scale: a.iter().fold(1.0f64, |s, x| s.max(x.abs())),
        f_scale: reactions.iter().fold(1.0f64, |s, r| s.max(r.force.norm())),
        a,
        reactions,
    }
}

#[test]
fn planar_chain_built_in_3d_matches_the_planar_model() {
    let (m, l) = (1.5, 0.8);
    let (angles, rates) = ([-0.4, 0.3, -1.1], [0.7, -1.2, 2.0]);
    let planar = mechanisms::chain(m, l, &angles, &rates, &[]);
    // The same rods in space: body frames turned about z by θ, hinges about z at the pins.
    let mut b = ModelBuilder::new([0.0, -mechanisms::G, 0.0]);
    let mut parent = BodyRef::Ground;
    for k in 0..3 {
        let (x, y, th) = (planar.q[3 * k], planar.q[3 * k + 1], planar.q[3 * k + 2]);
        let (vx, vy, w) = (planar.qd[3 * k], planar.qd[3 * k + 1], planar.qd[3 * k + 2]);
        let body = b.body(
            Body::new(&format!("link{k}"), m, [1e-4 * m, m * l * l / 12.0, m * l * l / 12.0])
                .at([x, y, 0.0])
                .oriented(from_axis_angle(&Vector3::z(), th))
                .moving([vx, vy, 0.0], [0.0, 0.0, w]),
        );
        let pin = [x - 0.5 * l * th.cos(), y - 0.5 * l * th.sin(), 0.0];
        b.joint(Joint::revolute(&format!("J{k}"), parent, body, pin, [0.0, 0.0, 1.0]));
        parent = body;
    }
    let spatial = Arc::new(b.build().unwrap());
    let (q3, v3) = spatial.initial_state();

    let planar_sys: Arc<dyn MultibodySystem> = planar.model.clone();
    let PlanarReference {
        a: a_ref,
        reactions: reactions_ref,
        a_scale,
        f_scale,
    } = planar_reference(&planar);

    let spatial_sys: Arc<dyn MultibodySystem> = spatial.clone();
    for mut f in formulations(&planar_sys).into_iter().chain(formulations(&spatial_sys)) {
        let is_spatial = f.system().layout().n_q() != planar.q.len();
        let (q, v) = if is_spatial {
            (&q3, &v3)
        } else {
            (&planar.q, &planar.qd)
        };
        let (a, lambda) = solve(f.as_mut(), q, v);
        let (mut da, mut df) = (0.0f64, 0.0f64);
        for k in 0..3 {
            let (planar_part, out_of_plane): ([f64; 3], [f64; 3]) = if is_spatial {
                (
                    [a[6 * k], a[6 * k + 1], a[6 * k + 5]],
                    [a[6 * k + 2], a[6 * k + 3], a[6 * k + 4]],
                )
            } else {
                ([a[3 * k], a[3 * k + 1], a[3 * k + 2]], [0.0; 3])
            };
            for c in 0..3 {
                da = da
                    .max((planar_part[c] - a_ref[3 * k + c]).abs())
                    .max(out_of_plane[c].abs());
            }
        }
        if is_spatial {
            for (r, r_ref) in spatial.reactions(0.0, q, &lambda).iter().zip(&reactions_ref) {
                df = df
                    .max((r.force.x - r_ref.force.x).abs())
                    .max((r.force.y - r_ref.force.y).abs());
                df = df.max(r.force.z.abs()).max(r.moment.amax());
            }
        } else {
            for (r, r_ref) in planar
                .model
                .constraints()
                .reactions_at(0.0, q, &lambda)
                .iter()
                .zip(&reactions_ref)
            {
                df = df.max((r.force - r_ref.force).amax());
            }
        }
        let kind = if is_spatial { "spatial" } else { "planar" };
        assert!(
            da < 1e-12 * a_scale && df < 1e-12 * f_scale,
            "{kind} {}: accelerations off by {da:e}, reactions by {df:e}",
            f.name()
        );
    }
}

fn minimum_norm(sys: &Arc<dyn MultibodySystem>) -> Vec<Box<dyn Formulation>> {
    use dalembert::augmented::AugmentedOptions;
    use dalembert::embedding::EmbeddingOptions;
    use dalembert::system::RedundancyTreatment::MinimumNorm;
    vec![
        Box::new(
            Augmented::new(
                sys.clone(),
                AugmentedOptions {
                    redundancy: MinimumNorm,
                    ..Default::default()
                },
            )
            .unwrap(),
        ),
        Box::new(Embedding::new(
            sys.clone(),
            EmbeddingOptions {
                redundancy: MinimumNorm,
                ..Default::default()
            },
        )),
        Box::new(Amalgamated::new(sys.clone(), MinimumNorm)),
    ]
}

#[test]
fn planar_four_bar_built_in_3d_matches_the_planar_model_with_minimum_norm_reactions() {
    // The anchors' four-bar (crank 1, coupler 2.5, rocker 1.5, ground 2; rods of 1 kg/m) with its
    // four hinges along z in space: 3 × 6 − 4 × 5 = −2 by Grübler, one degree of freedom in fact,
    // so three equations are redundant. They are all out of the plane: in the plane the spatial
    // Jacobian is the planar one (full rank), so the in-plane accelerations and reaction forces are
    // unique and must equal the planar model's; the out-of-plane reactions (fz, mx, my) are
    // statically indeterminate, and with nothing loading the bodies out of the plane their
    // minimum-norm values are zero.
    let planar = mechanisms::four_bar(1.1, 2.0, 0.0, false);
    let k = dalembert_testkit::closed_form::FourBar::ANCHOR;
    let lengths = [k.a, k.b, k.c];
    let mut b = ModelBuilder::new([0.0, -mechanisms::G, 0.0]);
    let mut bodies = Vec::new();
    let mut ends = Vec::new();
    for (i, l) in lengths.iter().enumerate() {
        let (x, y, th) = (planar.q[3 * i], planar.q[3 * i + 1], planar.q[3 * i + 2]);
        let (vx, vy, w) = (planar.qd[3 * i], planar.qd[3 * i + 1], planar.qd[3 * i + 2]);
        bodies.push(
            b.body(
                Body::new(&format!("rod{i}"), *l, [1e-4 * l, l * l * l / 12.0, l * l * l / 12.0])
                    .at([x, y, 0.0])
                    .oriented(from_axis_angle(&Vector3::z(), th))
                    .moving([vx, vy, 0.0], [0.0, 0.0, w]),
            ),
        );
        let half = [0.5 * l * th.cos(), 0.5 * l * th.sin()];
        ends.push(([x - half[0], y - half[1], 0.0], [x + half[0], y + half[1], 0.0]));
    }
    let z = [0.0, 0.0, 1.0];
    b.joint(Joint::revolute("A", BodyRef::Ground, bodies[0], ends[0].0, z));
    b.joint(Joint::revolute("B", bodies[0], bodies[1], ends[0].1, z));
    b.joint(Joint::revolute("C", bodies[1], bodies[2], ends[1].1, z));
    b.joint(Joint::revolute("D", BodyRef::Ground, bodies[2], ends[2].0, z));
    let spatial = Arc::new(b.build().unwrap());
    let (q3, v3) = spatial.initial_state();

    let PlanarReference {
        a: a_ref,
        reactions: reactions_ref,
        a_scale,
        f_scale,
    } = planar_reference(&planar);

    let spatial_sys: Arc<dyn MultibodySystem> = spatial.clone();
    for mut f in minimum_norm(&spatial_sys) {
        let (a, lambda) = solve(f.as_mut(), &q3, &v3);
        let mut da = 0.0f64;
        for i in 0..3 {
            for (c, p) in [(0, 0), (1, 1), (5, 2)] {
                da = da.max((a[6 * i + c] - a_ref[3 * i + p]).abs());
            }
            for c in [2, 3, 4] {
                da = da.max(a[6 * i + c].abs());
            }
        }
        let (mut df, mut out_of_plane) = (0.0f64, 0.0f64);
        for (r, r_ref) in spatial.reactions(0.0, &q3, &lambda).iter().zip(&reactions_ref) {
            df = df
                .max((r.force.x - r_ref.force.x).abs())
                .max((r.force.y - r_ref.force.y).abs());
            out_of_plane = out_of_plane
                .max(r.force.z.abs())
                .max(r.moment.x.abs())
                .max(r.moment.y.abs());
            // A hinge about z transmits no moment about z.
            out_of_plane = out_of_plane.max(r.moment.z.abs());
        }
        assert!(
            da < 1e-12 * a_scale && df < 1e-12 * f_scale && out_of_plane < 1e-12 * f_scale,
            "{}: accelerations off by {da:e}, in-plane reactions by {df:e}, out-of-plane reactions {out_of_plane:e}",
            f.name()
        );
    }
}
