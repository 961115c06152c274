//! A box thrown tumbling on a floor, its corners rigid spheres with friction cones (eight
//! `sphere-plane` contacts on one body): it lands, rocks on an edge, slips and sticks, and comes
//! to rest on a face, in every formulation.
//!
//! The three throws are from a generated probe (Python's `random.Random(seed)`: axis U[−1, 1]³,
//! angle U[0, π], velocity U[−1, 1]² × U[−1, 0], spin U[−5, 5]³, μ from {0.2, 0.4, 0.7}):
//! seeds 1 and 23 with restitution 0.3, seed 69 with none. Each stopped before the guards of
//! `solve_friction`'s iteration for cones of one body ((L14) in `docs/limits.md`), with "the
//! friction and limit forces did not settle in 60 iterations":
//! - seed 1 (augmented and embedding): two cones of an edge cycled between the same two Newton
//!   iterates, each law's full step landing on the other's side (now: such steps are halved);
//! - seed 23 (embedding): a cone on its bound with no slip acceleration flipped to holding by
//!   round-off, and the least-norm step threw three corners' cones far off their bounds (now: a
//!   cone that followed (L14) holds again only inside its bound by 1e-9 of it);
//! - seed 69 (amalgamated): the four cones of a face, whose least-norm forces moved with each
//!   linearization along the redundant forces (now: after 12 iterations with the laws kept, the
//!   step of least norm).
//!
//! A fourth throw (seed 107, no rebound) closed its energy balance only to 1.1e-4 J in
//! amalgamated: the work's quadrature went on across a second impact at the instant of the first.
//! And seed 69's balance checks the impulses that stop slips: their kinetic energy counts in the
//! balance, and the LU's impulses of an edge's two corners, level to round-off, had taken 8e4 N·s
//! along the direction the corners hold together (`E − W` then 2.1e-6 J, augmented; now the
//! least-norm split decides where `|P| |G|` exceeds 1e8 of the rates it sets). A fifth (seed 93,
//! no rebound) stopped in embedding with "did not settle in 60 iterations", a corner's cone
//! slipping on a held normal force near zero. A sixth (seed 85, no rebound) never finished: its
//! steps collapsed where the evaluations changed between two ways of splitting a face's forces.
//!
//! What is checked, against numbers that come from elsewhere:
//! - the run ends, in all three formulations;
//! - no sphere is ever below the floor by more than 1e-9 m (held contacts are kept at the
//!   acceleration level, so their gap is the integration's error at 1e-10; measured at most
//!   1.8e-12 m);
//! - the box ends at rest (but for seed 93, below), speeds below 1e-9 (measured at most
//!   4.6e-13), with its centre half a side above the floor within 1e-9 m (the spheres are inset
//!   by their radius, so that is the rest height exactly; measured at most 1.2e-13 m);
//! - the energy balance `E − W` (the impacts' and the friction's losses in `W`) stays within
//!   1e-6 J of its start, 12.4 to 13.3 J (dopri5 at 1e-10 over 1.5 s with several impacts, each
//!   located to the integration's tolerance; measured at most 1.4e-7 J, seed 107 in embedding);
//! - the first and fifth throws' three runs end within 1e-9 m of each other (measured 6e-15 m
//!   and 1e-11 m). The others' are not compared: a tumbling box's landings branch on which
//!   corner strikes first, which the integration's error decides where two are level (they end
//!   5.1e-7 m and 4e-9 m apart, measured, each at rest on one face in every formulation).
mod common;

use common::{balance_drift, column, run};
use dalembert::Scene;

const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];
const HALF: [f64; 3] = [0.2, 0.15, 0.1];
const RADIUS: f64 = 1e-3;
const HEIGHT: f64 = 0.6;

/// A throw: the rotation's axis and angle (degrees), the velocity, the spin, μ, the restitution.
struct Throw {
    axis: [f64; 3],
    degrees: f64,
    velocity: [f64; 3],
    spin: [f64; 3],
    mu: f64,
    restitution: f64,
}

/// `p` turned by `angle` about the unit `axis` (Rodrigues).
fn rotate(axis: [f64; 3], angle: f64, p: [f64; 3]) -> [f64; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let k = [axis[0] / n, axis[1] / n, axis[2] / n];
    let (c, s) = (angle.cos(), angle.sin());
    let cross = [
        k[1] * p[2] - k[2] * p[1],
        k[2] * p[0] - k[0] * p[2],
        k[0] * p[1] - k[1] * p[0],
    ];
    let dot = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
    [0, 1, 2].map(|i| p[i] * c + cross[i] * s + k[i] * dot * (1.0 - c))
}

fn scene(throw: &Throw, formulation: &str) -> Scene {
    let mut text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"block\"\nmass = 2.0\nshape = {{ box = [0.4, 0.3, 0.2] }}\n\
         position = [0.0, 0.0, {HEIGHT:?}]\norientation = {{ axis = {:?}, degrees = {:?} }}\n\
         velocity = {:?}\nangular_velocity = {:?}\n",
        throw.axis, throw.degrees, throw.velocity, throw.spin
    );
    let mut corner = 0;
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let local = [
                    sx * (HALF[0] - RADIUS),
                    sy * (HALF[1] - RADIUS),
                    sz * (HALF[2] - RADIUS),
                ];
                let p = rotate(throw.axis, throw.degrees.to_radians(), local);
                text += &format!(
                    "[[forces]]\nname = \"floor{corner}\"\ntype = \"sphere-plane\"\nbody = \"block\"\n\
                     radius = {RADIUS:?}\nat = [{:?}, {:?}, {:?}]\n\
                     plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\n\
                     rigid = true\nfriction = {:?}\nrestitution = {:?}\n",
                    p[0],
                    p[1],
                    HEIGHT + p[2],
                    throw.mu,
                    throw.restitution
                );
                corner += 1;
            }
        }
    }
    text += &format!(
        "[simulation]\nend = 1.5\nformulation = \"{formulation}\"\nintegrator = \"dopri5\"\n\
         rtol = 1e-10\natol = 1e-10\noutput_every = 0.01\n"
    );
    Scene::from_toml(&text, "box on corner spheres").unwrap()
}

/// Runs `throw` in every formulation and checks each run; where `agree` is given, the three
/// runs' final positions agree within it (m); where `rests`, the box is at rest on a face at the
/// end.
fn check(throw: &Throw, agree: Option<f64>, rests: bool) {
    let mut ends: Vec<[f64; 3]> = Vec::new();
    for formulation in FORMULATIONS {
        let scene = scene(throw, formulation);
        let table = run(&scene);
        let col = |name: &str| column(&table, name);
        for corner in 0..8 {
            let gap = col(&format!("floor{corner}.gap"));
            let lowest = gap.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(
                lowest > -1e-9,
                "{formulation}: corner {corner} went {lowest:e} m into the floor"
            );
        }
        let last = |name: &str| *col(name).last().unwrap();
        let z = last("block.z");
        if rests {
            for name in ["block.vx", "block.vy", "block.vz", "block.wx", "block.wy", "block.wz"] {
                assert!(
                    last(name).abs() < 1e-9,
                    "{formulation}: {name} = {:e} at the end",
                    last(name)
                );
            }
            let off = HALF.iter().map(|h| (z - h).abs()).fold(f64::INFINITY, f64::min);
            assert!(
                off < 1e-9,
                "{formulation}: at rest at z = {z}, not on a face ({off:e} off)"
            );
        }
        let drift = balance_drift(&scene);
        assert!(drift < 1e-6, "{formulation}: E − W changed by {drift:e} J");
        ends.push([last("block.x"), last("block.y"), z]);
    }
    if let Some(bar) = agree {
        for end in &ends[1..] {
            let apart = (0..3).map(|i| (end[i] - ends[0][i]).abs()).fold(0.0, f64::max);
            assert!(apart < bar, "the formulations ended {apart:e} m apart");
        }
    }
}

#[test]
fn a_box_on_corner_spheres_whose_edge_cones_begin_to_slip_together_comes_to_rest() {
    check(
        &Throw {
            axis: [-0.7312715117751976, 0.6948674738744653, 0.5275492379532281],
            degrees: 45.9124246330959,
            velocity: [-0.009129825816118098, -0.10101787042252375, -0.34840702727723705],
            spin: [2.8872335113551317, -4.0614041322576515, -4.716525234779937],
            mu: 0.4,
            restitution: 0.3,
        },
        Some(1e-9),
        true,
    );
}

#[test]
fn a_box_on_corner_spheres_held_on_the_bounds_of_its_cones_comes_to_rest() {
    check(
        &Throw {
            axis: [0.8497305032518905, 0.8972115559863543, 0.7848666880971586],
            degrees: 15.039121829523054,
            velocity: [0.18405445377147056, -0.15250518353007725, -0.46991198988199356],
            spin: [-3.6969705875251946, -3.080028424607073, -0.5542642612698696],
            mu: 0.2,
            restitution: 0.3,
        },
        None,
        true,
    );
}

#[test]
fn a_box_on_corner_spheres_dropped_spinning_without_rebound_comes_to_rest_on_a_face() {
    check(
        &Throw {
            axis: [0.36848190482414656, -0.8083253830463917, -0.6661703874666143],
            degrees: 108.92229439341385,
            velocity: [-0.34392793595973714, 0.8292446415583807, -0.21194888059228445],
            spin: [3.6469595543448126, -0.8546732764827532, 3.288422184314298],
            mu: 0.7,
            restitution: 0.0,
        },
        None,
        true,
    );
}

/// Seed 107 without rebound: a face lands level while its far edge slides on the floor. Its two
/// near corners strike at one instant (their gaps equal to 5e-17 m); in amalgamated the first
/// impact lets one of them go with an impulse that would pull, and the second strikes it at the
/// same instant, settled at the start of the step after the event. The work's quadrature had gone
/// on across that second impulse, on the power from before it: `E − W` jumped by 1.1e-4 J there
/// (now 3.2e-11 J over the run, measured).
#[test]
fn a_box_on_corner_spheres_whose_face_lands_level_while_sliding_keeps_its_energy_balance() {
    check(
        &Throw {
            axis: [-0.5070360806612837, 0.1625798607815594, 0.9445620138513022],
            degrees: 118.40266150646156,
            velocity: [-0.03495952839853622, -0.3820323205447631, -0.8621834037858714],
            spin: [4.987396936415255, 2.5432977917736466, -2.498846181063916],
            mu: 0.7,
            restitution: 0.0,
        },
        None,
        true,
    );
}

/// Seed 93 without rebound: in embedding a corner's cone slips on a held normal force that
/// Newton's iterates put at 1.7e-8 N and −6.7e-10 N by turns (17 N on another corner), across
/// the kink of its bound `μ |N|`, and the iteration stopped with "did not settle in 60
/// iterations" at 0.7255 s (an iterate-by-iterate trace: the held contact's force never left
/// the band of round-off it may pull with, so the contact was not let go). Now a held contact
/// whose force changes sign on a step that did not shrink lets go, after 12 iterations. The box
/// then rocks on an edge past the end of the run (at rest on a face by 3 s), so it is not
/// checked at rest; the three formulations end within 1e-9 m of each other (measured 1e-11 m).
#[test]
fn a_box_on_corner_spheres_sliding_on_a_corner_that_barely_touches_runs_on() {
    check(
        &Throw {
            axis: [0.8246867187194984, -0.011300505399674421, 0.13160290901296068],
            degrees: 63.593082122237774,
            velocity: [-0.7727670059828655, -0.28923988122014976, -0.8271573007746045],
            spin: [-3.7810822734349827, -3.3892533494784316, -4.670299468931987],
            mu: 0.7,
            restitution: 0.0,
        },
        Some(1e-9),
        false,
    );
}

/// Seed 85 without rebound: a face slides and spins on its four corners, one of whose normal
/// forces falls towards zero. The iteration on the slipping forces gave up at some evaluations
/// and not at others, and Newton's method on every element splits the face's redundant normal
/// forces otherwise: the right-hand side changed from one evaluation to the next, and dopri5's
/// steps fell below 1e-8 s (0.326 s reached in 90 s). Now Newton's method decides from the first
/// give-up until the next event.
#[test]
fn a_box_on_corner_spheres_sliding_and_spinning_on_a_face_comes_to_rest() {
    check(
        &Throw {
            axis: [-0.6008225872917998, 0.23010520368993959, -0.7857793521751026],
            degrees: 162.9320203527485,
            velocity: [-0.6158465411883403, -0.07755771611098128, -0.22876301522053877],
            spin: [4.079002465766733, 0.8221826123063538, 1.8122207653938567],
            mu: 0.7,
            restitution: 0.0,
        },
        None,
        true,
    );
}
