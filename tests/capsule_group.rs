//! A group of capsules in mutual compliant contact (`capsule-group`, `docs/contact.md`, "Groups
//! and the broad phase") against numbers from elsewhere: its generalized forces are those of the
//! same pairs written one by one (`capsule-capsule`, another program for the pairs), at states
//! where many pairs touch, whichever order the members are listed in; a pile of capsules dropped
//! on a floor without dissipation keeps its energy, the pair joined by a joint never pushing.

mod common;

use common::{column, run};
use dalembert::Scene;

/// Eight capsules of radius 0.04 and half-length 0.15 (centre and axis): a stack 0.1 m apart,
/// each crossing the one below 2 cm above it, and `c1` beside `c0`, its end on `c0`'s (where
/// the two are joined, overlapping).
fn cluster() -> Vec<([f64; 3], [f64; 3])> {
    let r = std::f64::consts::FRAC_1_SQRT_2;
    vec![
        ([0.0, 0.0, 0.1], [1.0, 0.0, 0.0]),
        ([0.15, 0.15, 0.1], [0.0, 1.0, 0.0]),
        ([0.02, 0.05, 0.2], [0.0, 1.0, 0.0]),
        ([-0.03, 0.02, 0.3], [r, r, 0.0]),
        ([0.01, -0.02, 0.4], [1.0, 0.0, 0.0]),
        ([0.04, 0.0, 0.5], [0.0, 1.0, 0.0]),
        ([-0.02, 0.03, 0.6], [r, -r, 0.0]),
        ([0.0, 0.01, 0.7], [1.0, 0.0, 0.0]),
    ]
}

fn ends(c: &([f64; 3], [f64; 3])) -> [[f64; 3]; 2] {
    let (p, d) = c;
    [0, 1].map(|s| {
        let sign = if s == 0 { -0.15 } else { 0.15 };
        [p[0] + sign * d[0], p[1] + sign * d[1], p[2] + sign * d[2]]
    })
}

/// The cluster's scene: its contacts as one `capsule-group` (members in `order`) or as every
/// pair written out; a joint between `c0` and `c1` at `c0`'s upper end, the floor under each
/// capsule, gravity, `dissipation` in every contact.
fn scene(group: bool, order: &[usize], dissipation: f64, end: f64) -> Scene {
    let capsules = cluster();
    let mut text = String::from("[scene]\ngravity = [0.0, 0.0, -9.81]\n");
    for (k, c) in capsules.iter().enumerate() {
        text += &format!(
            "[[bodies]]\nname = \"c{k}\"\nmass = 0.3\ninertia = [0.0003, 0.0025, 0.0025]\nposition = {:?}\n",
            [c.0[0], c.0[1], c.0[2] + 0.3]
        );
    }
    let lifted = |c: &([f64; 3], [f64; 3])| ends(c).map(|p| [p[0], p[1], p[2] + 0.3]);
    text += &format!(
        "[[joints]]\nname = \"hinge\"\ntype = \"spherical\"\nbodies = [\"c0\", \"c1\"]\nat = {:?}\n",
        lifted(&capsules[0])[1]
    );
    let law = format!("stiffness = 1e5\ndissipation = {dissipation}\n");
    for (k, c) in capsules.iter().enumerate() {
        text += &format!(
            "[[forces]]\nname = \"floor{k}\"\ntype = \"capsule-plane\"\nbody = \"c{k}\"\nradius = 0.04\nat = {:?}\n\
             plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n{law}",
            lifted(c)
        );
    }
    if group {
        let members: Vec<String> = order
            .iter()
            .map(|&k| format!("{{ body = \"c{k}\", at = {:?}, radius = 0.04 }}", lifted(&capsules[k])))
            .collect();
        text += &format!(
            "[[forces]]\nname = \"pile\"\ntype = \"capsule-group\"\nmembers = [{}]\n{law}",
            members.join(", ")
        );
    } else {
        for i in 0..8 {
            for j in i + 1..8 {
                if (i, j) == (0, 1) {
                    continue;
                }
                text += &format!(
                    "[[forces]]\nname = \"pair{i}{j}\"\ntype = \"capsule-capsule\"\nbodies = [\"c{i}\", \"c{j}\"]\n\
                     segments = [{:?}, {:?}]\nradii = [0.04, 0.04]\n{law}",
                    lifted(&capsules[i]),
                    lifted(&capsules[j])
                );
            }
        }
    }
    text += &format!(
        "[simulation]\nend = {end}\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.002\n"
    );
    Scene::from_toml(&text, "capsule pile").unwrap()
}

#[test]
fn a_groups_forces_are_its_pairs_forces() {
    // The stack squeezed (its spacing shrunk by a factor, from 10 cm to 7.5, 6 and 5: the
    // capsules, 8 cm thick, overlap) and moving, at three states where pairs overlap: the applied forces with the group equal those with the pairs
    // written out to round-off (1e-12 of the largest; measured 0 with the members in order, 1.1e-15
    // listed in another, the sums then running in another order).
    let pairs = scene(false, &[0, 1, 2, 3, 4, 5, 6, 7], 0.3, 1.0);
    let orders = [[0, 1, 2, 3, 4, 5, 6, 7], [7, 3, 5, 1, 0, 6, 2, 4]];
    for order in &orders {
        let group = scene(true, order, 0.3, 1.0);
        for squeeze in [0.75, 0.6, 0.5] {
            let mut q = pairs.q.clone();
            let mut v = pairs.qd.clone();
            for k in 0..8 {
                // Positions then Euler parameters, seven per body; velocities six per body.
                for c in 0..3 {
                    let x = &mut q[7 * k + c];
                    if c == 2 {
                        *x = 0.4 + squeeze * (*x - 0.4);
                    }
                }
                for c in 0..6 {
                    v[6 * k + c] = 0.1 * ((k * 6 + c) as f64).sin();
                }
            }
            let (mut a, mut b) = (vec![0.0; v.len()], vec![0.0; v.len()]);
            pairs.model.as_system().applied_forces(0.0, &q, &v, &mut a);
            group.model.as_system().applied_forces(0.0, &q, &v, &mut b);
            let largest = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let worst = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
            // Without gravity's 0.3 × 9.81 N the contacts must push: more than a few newtons.
            assert!(largest > 10.0, "squeeze {squeeze}: no contact ({largest} N)");
            assert!(
                worst <= 1e-12 * largest,
                "order {order:?}, squeeze {squeeze}: the group differs from its pairs by {worst:e} of {largest}"
            );
        }
    }
}

#[test]
fn a_pile_dropped_without_dissipation_keeps_its_energy() {
    // Eight capsules, two of them joined, dropped (the stack from 0.4 to 1 m) onto the floor and onto each other
    // without dissipation or friction: every contact force is the gradient of its potential
    // (counted in the energy column), so T + V is constant (a conservation law): within 1e-6 J of
    // 15.6 J over 0.6 s (dopri5 at 1e-11; measured 5.1e-8 J, the group's normal force peaking at
    // 410 N). The joined pair overlaps at its joint from the
    // start; the group skips it, so its normal force starts at zero.
    let table = run(&scene(true, &[0, 1, 2, 3, 4, 5, 6, 7], 0.0, 0.6));
    let (energy, normal) = (column(&table, "energy"), column(&table, "pile.normal"));
    assert_eq!(normal[0], 0.0, "the joined pair pushes");
    assert!(normal.iter().any(|&n| n > 1.0), "the capsules never touched each other");
    let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max);
    assert!(drift < 1e-6, "the energy moved {drift:e} J from {}", energy[0]);
}
