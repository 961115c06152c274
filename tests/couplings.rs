//! Couplings between joint values (`docs/couplings.md`), against an independent derivation: two
//! rods on parallel hinges, the second's angle a polynomial `p` of the first's, move as one
//! degree of freedom whose Lagrange equation is
//!
//! ```text
//! (J_a + J_b p′²) θ̈ + J_b p′ p″ θ̇² = −m_a g d_a sin θ − p′ m_b g d_b sin p(θ)
//! ```
//!
//! (`J` about each pivot, `d` pivot to centre of mass), integrated here by RK4 at a step small
//! enough to be exact to round-off. The coupling's effort is the torque that moves the second
//! rod as it does: `τ_b = J_b θ̈_b + m_b g d_b sin θ_b`. Every formulation, linear (a URDF
//! `mimic`) and quadratic (an MJCF `polycoef`) couplings.

use dalembert::Scene;
use std::sync::atomic::AtomicBool;

const G: f64 = 9.81;
const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];

/// Rod `a` (2 kg, 1 m) and rod `b` (1 kg, 0.6 m) hanging from pivots 1 m apart on hinges about
/// `y`; `b`'s angle is `p(a's)`; `a` starts at 0.5 rad turning at 1 rad/s.
const ROD_A: (f64, f64) = (2.0, 1.0);
const ROD_B: (f64, f64) = (1.0, 0.6);
const WIDTH: f64 = 0.04;

fn scene(polynomial: &[f64], formulation: &str) -> Scene {
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"a\"\nmass = {ma}\nshape = {{ box = [{WIDTH}, {WIDTH}, {la}] }}\nposition = [0.0, 0.0, {za}]\n\
         [[bodies]]\nname = \"b\"\nmass = {mb}\nshape = {{ box = [{WIDTH}, {WIDTH}, {lb}] }}\nposition = [1.0, 0.0, {zb}]\n\
         [[joints]]\nname = \"pa\"\ntype = \"revolute\"\nbodies = [\"ground\", \"a\"]\nat = [0.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n\
         [[joints]]\nname = \"pb\"\ntype = \"revolute\"\nbodies = [\"ground\", \"b\"]\nat = [1.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n\
         [[couplings]]\nname = \"gear\"\nleader = \"pa\"\nfollower = \"pb\"\npolynomial = {polynomial:?}\n\
         [initial]\njoints = {{ pa = 0.5 }}\nrates = {{ pa = 1.0 }}\n\
         [simulation]\nend = 2.0\nformulation = \"{formulation}\"\nintegrator = \"dopri5\"\n\
         rtol = 1e-11\natol = 1e-11\noutput_every = 0.05\n",
        ma = ROD_A.0,
        la = ROD_A.1,
        za = -ROD_A.1 / 2.0,
        mb = ROD_B.0,
        lb = ROD_B.1,
        zb = -ROD_B.1 / 2.0,
    );
    Scene::from_toml(&text, "coupled rods").unwrap()
}

/// Mass, inertia about the pivot and pivot-to-centre distance of a box rod of `(m, L)`.
fn rod((m, l): (f64, f64)) -> (f64, f64, f64) {
    (m, m * (WIDTH * WIDTH + l * l) / 12.0 + m * l * l / 4.0, l / 2.0)
}

fn p(c: &[f64], x: f64) -> [f64; 3] {
    let (mut v, mut d1, mut d2) = (0.0, 0.0, 0.0);
    for &a in c.iter().rev() {
        d2 = d2 * x + 2.0 * d1;
        d1 = d1 * x + v;
        v = v * x + a;
    }
    [v, d1, d2]
}

/// `θ̈` of the reduced equation.
fn acceleration(c: &[f64], th: f64, w: f64) -> f64 {
    let ((ma, ja, da), (mb, jb, db)) = (rod(ROD_A), rod(ROD_B));
    let [pv, p1, p2] = p(c, th);
    (-ma * G * da * th.sin() - p1 * mb * G * db * pv.sin() - jb * p1 * p2 * w * w) / (ja + jb * p1 * p1)
}

/// `(θ, θ̇)` at each of `times` by RK4 at 1e-5 s.
fn reference(c: &[f64], times: &[f64]) -> Vec<(f64, f64)> {
    let h: f64 = 1e-5;
    let (mut t, mut x) = (0.0, [0.5, 1.0]);
    let f = |x: [f64; 2]| [x[1], acceleration(c, x[0], x[1])];
    let mut out = Vec::new();
    for &target in times {
        while t < target - 1e-12 {
            let s = h.min(target - t);
            let k1 = f(x);
            let k2 = f([x[0] + s / 2.0 * k1[0], x[1] + s / 2.0 * k1[1]]);
            let k3 = f([x[0] + s / 2.0 * k2[0], x[1] + s / 2.0 * k2[1]]);
            let k4 = f([x[0] + s * k3[0], x[1] + s * k3[1]]);
            for i in 0..2 {
                x[i] += s / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += s;
        }
        out.push((x[0], x[1]));
    }
    out
}

#[test]
fn coupled_rods_move_as_their_one_degree_of_freedom_and_the_coupling_carries_the_torque() {
    // Linear (a mimic: multiplier −0.7, offset 0.2) and quadratic couplings.
    for c in [vec![0.2, -0.7], vec![0.1, 0.8, -0.5]] {
        for formulation in FORMULATIONS {
            let rec = scene(&c, formulation).record(&AtomicBool::new(false));
            rec.outcome.unwrap();
            let col = |n: &str| rec.table.column(n).unwrap();
            let (t, qa, qb, effort, energy) = (col("t"), col("pa.q"), col("pb.q"), col("gear.effort"), col("energy"));
            let exact = reference(&c, &t);
            let (_, jb, db) = rod(ROD_B);
            let mb = ROD_B.0;
            for (k, &(th, w)) in exact.iter().enumerate() {
                // dopri5 at 1e-11 over 2 s: 1e-8 rad is a thousand times its local tolerance.
                assert!(
                    (qa[k] - th).abs() < 1e-8,
                    "{c:?} {formulation}: t = {}: θ_a {} vs {th}",
                    t[k],
                    qa[k]
                );
                // The coupling holds to the projection's round-off.
                assert!(
                    (qb[k] - p(&c, qa[k])[0]).abs() < 1e-10,
                    "{c:?} {formulation}: θ_b {}",
                    qb[k]
                );
                // The torque on rod b that its motion needs, from the exact state.
                let [pv, p1, p2] = p(&c, th);
                let thb_dd = p1 * acceleration(&c, th, w) + p2 * w * w;
                let tau = jb * thb_dd + mb * G * db * pv.sin();
                assert!(
                    (effort[k] - tau).abs() < 1e-7,
                    "{c:?} {formulation}: t = {}: effort {} vs {tau}",
                    t[k],
                    effort[k]
                );
            }
            // A coupling does no work: the energy stays (dopri5's error at 1e-11).
            let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max);
            assert!(drift < 1e-8, "{c:?} {formulation}: energy drifts {drift:.2e} J");
        }
    }
}

#[test]
fn a_coupling_is_refused_in_joint_coordinates_and_names_itself() {
    let s = scene(&[0.0, 1.0], "augmented");
    let err = s
        .with_values(&[("simulation.coordinates", "joint".into())])
        .map(|_| ())
        .unwrap_err();
    assert!(err.to_string().contains("coupling 'gear'"), "{err}");
}
