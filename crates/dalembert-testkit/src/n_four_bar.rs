//! The N-four-bar of the IFToMM multibody benchmark A02 (González, Dopico, Lugrís, Cuadrado,
//! "A benchmarking system for MBS simulation software", Multibody System Dynamics 16, 2006) and
//! its exact one-degree-of-freedom reduction.
//!
//! `N + 1` cranks pinned to the ground at `(i, 0)`, `i = 0 … N`, and `N` couplers joining the
//! crank tips: `2N + 1` uniform rods of 1 m and 1 kg, gravity 9.81 m/s² along −y. It starts with
//! the cranks vertical and the couplers horizontal at `y = 1`; the tip `B₀` of the first crank
//! moves at `ẋ = 1 m/s`. Whenever the cranks are horizontal every link lies on the x axis: the
//! constraint Jacobian loses `N` ranks and `N` more motions become instantaneously possible.
//!
//! On the motion that keeps every window a parallelogram all cranks share the angle `θ` (from +x),
//! each coupler translates on a unit circle, and Lagrange's equation in `θ` is (derived here: crank
//! kinetic energy `½ (mL²/3) θ̇²`, coupler `½ m (Lθ̇)²`; potential `m g (L/2) sin θ` per crank,
//! `m g L sin θ` per coupler)
//!
//! ```text
//! k θ̈ = −g c cos θ,   k = (N+1)/3 + N,   c = (N+1)/2 + N,   θ(0) = π/2,  θ̇(0) = −1 rad/s.
//! ```

use crate::mechanisms::G;
use std::f64::consts::FRAC_PI_2;

/// An N-four-bar with `n` windows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NFourBar {
    /// Number of four-bar windows (couplers); there are `n + 1` cranks.
    pub n: usize,
}

impl NFourBar {
    /// Index of the first crank (`B₀` is its tip) among the scene's bodies.
    pub const FIRST_CRANK: usize = 0;

    /// The scene as TOML: bodies `crank-0 … crank-N`, then `coupler-0 … coupler-(N−1)`; joints
    /// `O<i>` (ground–crank), `L<i>` (crank i – coupler i), `R<i>` (coupler i – crank i+1). Only
    /// the first crank's angular velocity is given (held); the others follow by least change.
    pub fn toml(&self, end: f64) -> String {
        let n = self.n;
        let mut s = format!("[scene]\nname = \"N-four-bar, N = {n} (IFToMM A02)\"\ngravity = [0.0, -{G}]\n\n");
        for i in 0..=n {
            s += &format!(
                "[[bodies]]\nname = \"crank-{i}\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\nposition = [{i}.0, 0.5]\nangle = {FRAC_PI_2:?}\n"
            );
            if i == 0 {
                s += "angular_velocity = -1.0\n";
            }
            s += "\n";
        }
        for i in 0..n {
            s += &format!(
                "[[bodies]]\nname = \"coupler-{i}\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\nposition = [{}, 1.0]\n\n",
                i as f64 + 0.5
            );
        }
        let joint = |name: String, a: String, b: String, x: usize, y: f64| {
            format!(
                "[[joints]]\nname = \"{name}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"{b}\"]\nat = [{x}.0, {y:?}]\n\n"
            )
        };
        for i in 0..=n {
            s += &joint(format!("O{i}"), "ground".into(), format!("crank-{i}"), i, 0.0);
        }
        for i in 0..n {
            s += &joint(format!("L{i}"), format!("crank-{i}"), format!("coupler-{i}"), i, 1.0);
            s += &joint(
                format!("R{i}"),
                format!("coupler-{i}"),
                format!("crank-{}", i + 1),
                i + 1,
                1.0,
            );
        }
        s += &format!("[simulation]\nend = {end:?}\noutput_every = 0.05\n");
        s
    }

    /// `(k, c)` of the reduced equation `k θ̈ = −g c cos θ`.
    pub fn reduced(&self) -> (f64, f64) {
        let n = self.n as f64;
        ((n + 1.0) / 3.0 + n, (n + 1.0) / 2.0 + n)
    }

    /// `θ(t)` and `θ̇(t)` on the grid `t = 0, every, 2·every, …, end` from the reduced equation
    /// (classic RK4 with 1000 substeps per grid interval of at most 0.05 s: step ≤ 5e-5 s, global
    /// error below 1e-13 rad over 20 s, measured by halving).
    pub fn reference(&self, every: f64, end: f64) -> Vec<(f64, f64, f64)> {
        self.reference_from((FRAC_PI_2, -1.0), every, end)
    }

    /// Position of `B₀` (tip of the first crank) from the planar coordinates `q` (3 per body).
    pub fn b0(q: &[f64]) -> (f64, f64) {
        let (x, y, a) = (q[0], q[1], q[2]);
        (x + 0.5 * a.cos(), y + 0.5 * a.sin())
    }

    /// The benchmark's error at one output: `max(|Δx|, |Δy|)` of `B₀` against the crank angle `θ`.
    pub fn b0_error(q: &[f64], theta: f64) -> f64 {
        let (x, y) = Self::b0(q);
        (x - theta.cos()).abs().max((y - theta.sin()).abs())
    }
}

/// `steps` classic RK4 steps of `h` of a crank under gravity, `k θ̈ = −g c cos θ` (any mechanism
/// whose one degree of freedom is such a crank angle: the N-four-bar, a parallelogram): `(θ, θ̇)`.
pub fn crank_rk4(theta: f64, omega: f64, k: f64, c: f64, h: f64, steps: usize) -> (f64, f64) {
    let f = |th: f64| -G * c * th.cos() / k;
    let (mut th, mut w) = (theta, omega);
    for _ in 0..steps {
        let (k1q, k1v) = (w, f(th));
        let (k2q, k2v) = (w + 0.5 * h * k1v, f(th + 0.5 * h * k1q));
        let (k3q, k3v) = (w + 0.5 * h * k2v, f(th + 0.5 * h * k2q));
        let (k4q, k4v) = (w + h * k3v, f(th + h * k3q));
        th += h / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
        w += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    (th, w)
}

/// One way of writing the benchmark's model ([`NFourBar::variant`]): the same bodies, masses,
/// joints and link lengths as [`NFourBar::toml`], listed and stated differently, from a start on
/// the same motion.
#[derive(Debug, Clone)]
pub struct Variant {
    /// The scene.
    pub toml: String,
    /// Index of the first crank (whose tip is `B₀`) among the scene's bodies.
    pub first_crank: usize,
    /// The start `(θ(0), θ̇(0))` on the reduction (the benchmark's `(π/2, −1)`, or moved by up
    /// to 1e-12): pass it to [`NFourBar::reference_from`].
    pub start: (f64, f64),
    /// What was varied, for messages.
    pub description: String,
}

impl NFourBar {
    /// `θ(t)` and `θ̇(t)` of the reduction on the grid of [`NFourBar::reference`], from the start
    /// `(θ(0), θ̇(0))`.
    pub fn reference_from(&self, start: (f64, f64), every: f64, end: f64) -> Vec<(f64, f64, f64)> {
        let (k, c) = self.reduced();
        let (mut th, mut w) = start;
        let count = (end / every).round() as usize;
        let sub = 1000.max((every / 5e-5).ceil() as usize);
        let mut out = vec![(0.0, th, w)];
        for j in 1..=count {
            (th, w) = crank_rk4(th, w, k, c, every / sub as f64, sub);
            out.push((j as f64 * every, th, w));
        }
        out
    }

    /// The model written the `seed`-th way: bodies and joints in shuffled orders, each joint's
    /// bodies in either order, each joint given by its global point (`at`) or by the two bodies'
    /// local points (`points`); for odd seeds the initial state is moved by up to 1e-12 (the
    /// crank angle along the motion by up to 1e-12 rad, the first crank's rate by up to
    /// 1e-12 rad/s; every body and every `at` point is placed at the moved start, so the link
    /// lengths stay those of the benchmark), seeds 3, 7, 11, … also move each body by its own up
    /// to 1e-12 and give every joint by its bodies' local points (the start is assembled again),
    /// and the run goes to 21 s. Seed 0 is [`NFourBar::toml`] as written.
    ///
    /// Moving each body by its own 1e-12 would not be a change of state alone: a joint given by
    /// `at` takes its local points from the bodies' written poses, so its links would come out up
    /// to 1e-12 longer or shorter. That is another mechanism, one with no passage
    /// ([`NFourBar::with_lengths_moved`]).
    pub fn variant(&self, end: f64, seed: u64) -> Variant {
        use crate::fuzz::Rng;
        if seed == 0 {
            return Variant {
                toml: self.toml(end),
                first_crank: Self::FIRST_CRANK,
                start: (FRAC_PI_2, -1.0),
                description: "as written".into(),
            };
        }
        let mut rng = Rng::new(seed);
        let moved = seed % 2 == 1;
        let mut tiny = || 1e-12 * (2.0 * (rng.next_u64() as f64 / u64::MAX as f64) - 1.0);
        let start = if moved {
            (FRAC_PI_2 + tiny(), -1.0 + tiny())
        } else {
            (FRAC_PI_2, -1.0)
        };
        let jostled: Option<Vec<f64>> = (seed % 4 == 3).then(|| (0..3 * (2 * self.n + 1)).map(|_| tiny()).collect());
        let (th, w) = start;
        // The crank tips relative to their pivots: exactly (0, 1) at the benchmark's start.
        let tip = if moved { [th.cos(), th.sin()] } else { [0.0, 1.0] };
        let stated = match &jostled {
            Some(noise) => Stated::BodiesMoved(noise),
            None => Stated::AsIs,
        };
        let mut written = self.written(end, &mut rng, tip, (th, w), stated);
        written.description = format!(
            "variant {seed}: {}{}",
            written.description,
            match (moved, jostled.is_some()) {
                (true, true) => ", the start moved by up to 1e-12 along the motion and each body by its own",
                (true, false) => ", the start moved by up to 1e-12 along the motion",
                _ => "",
            }
        );
        written.start = start;
        written
    }

    /// The benchmark at its start with every joint given by its global point `at`, each moved by
    /// up to 1e-12, shuffled as [`NFourBar::variant`]: every link is up to about 1e-12 longer or
    /// shorter than the benchmark's (the start is assembled again).
    ///
    /// That is no longer the benchmark's mechanism. Each window is a four-bar whose links meet
    /// Grashof's change-point condition `s + l = p + q` only to 1e-12; off it, the branch a window
    /// follows turns within about √1e-12 = 1e-6 rad of the flat position onto the folding motion
    /// (one crank held near the axis while the other swings), so its exact motion is not the
    /// reduction's. A step of 1 ms passes over that turn; what a method returns there is not the
    /// benchmark's answer and is not held to it.
    pub fn with_lengths_moved(&self, end: f64, seed: u64) -> Variant {
        let mut rng = crate::fuzz::Rng::new(seed);
        let noise: Vec<f64> = (0..2 * (3 * self.n + 1))
            .map(|_| 1e-12 * (2.0 * (rng.next_u64() as f64 / u64::MAX as f64) - 1.0))
            .collect();
        let stated = Stated::JointsMoved(&noise);
        let mut written = self.written(end, &mut rng, [0.0, 1.0], (FRAC_PI_2, -1.0), stated);
        written.description = format!("lengths moved, seed {seed}: {}", written.description);
        written
    }

    /// The scene, run to `end`, with the crank tips at `tip` from their pivots and the start
    /// `(th, w)` (crank angle, first crank's rate), bodies and joints shuffled by `rng`, the
    /// poses and joints `stated` so.
    fn written(
        &self,
        end: f64,
        rng: &mut crate::fuzz::Rng,
        tip: [f64; 2],
        (th, w): (f64, f64),
        stated: Stated,
    ) -> Variant {
        let n = self.n;
        // Bodies: (name, centre, angle); joints: (name, body a, body b, global point, local a, local b).
        let mut bodies: Vec<(String, [f64; 2], f64)> = (0..=n)
            .map(|i| (format!("crank-{i}"), [i as f64 + 0.5 * tip[0], 0.5 * tip[1]], th))
            .chain((0..n).map(|i| (format!("coupler-{i}"), [i as f64 + 0.5 + tip[0], tip[1]], 0.0)))
            .collect();
        if let Stated::BodiesMoved(noise) = stated {
            for (b, d) in bodies.iter_mut().zip(noise.chunks(3)) {
                b.1 = [b.1[0] + d[0], b.1[1] + d[1]];
                b.2 += d[2];
            }
        }
        type Joint = (String, String, String, [f64; 2], [f64; 2], [f64; 2]);
        let mut joints: Vec<Joint> = Vec::new();
        for i in 0..=n {
            let x = i as f64;
            let crank = format!("crank-{i}");
            joints.push((format!("O{i}"), "ground".into(), crank, [x, 0.0], [x, 0.0], [-0.5, 0.0]));
        }
        for i in 0..n {
            let x = i as f64;
            let (left, right, coupler) = (format!("crank-{i}"), format!("crank-{}", i + 1), format!("coupler-{i}"));
            let (l, r) = ([x + tip[0], tip[1]], [x + 1.0 + tip[0], tip[1]]);
            joints.push((format!("L{i}"), left, coupler.clone(), l, [0.5, 0.0], [-0.5, 0.0]));
            joints.push((format!("R{i}"), coupler, right, r, [0.5, 0.0], [0.5, 0.0]));
        }
        if let Stated::JointsMoved(noise) = stated {
            for (j, d) in joints.iter_mut().zip(noise.chunks(2)) {
                j.3 = [j.3[0] + d[0], j.3[1] + d[1]];
            }
        }
        shuffle(rng, &mut bodies);
        shuffle(rng, &mut joints);
        let mut s =
            format!("[scene]\nname = \"N-four-bar, N = {n} (IFToMM A02), a variant\"\ngravity = [0.0, -{G}]\n\n");
        for (name, c, angle) in &bodies {
            s += &format!(
                "[[bodies]]\nname = \"{name}\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\nposition = [{:?}, {:?}]\nangle = {angle:?}\n",
                c[0], c[1]
            );
            if name == "crank-0" {
                s += &format!("angular_velocity = {w:?}\n");
            }
            s += "\n";
        }
        let mut by_points = 0;
        for (name, a, b, at, la, lb) in &joints {
            let (a, b, la, lb) = if rng.below(2) == 1 {
                (b, a, lb, la)
            } else {
                (a, b, la, lb)
            };
            s += &format!("[[joints]]\nname = \"{name}\"\ntype = \"revolute\"\nbodies = [\"{a}\", \"{b}\"]\n");
            let local = match stated {
                Stated::AsIs => rng.below(2) == 1,
                Stated::BodiesMoved(_) => true,
                Stated::JointsMoved(_) => false,
            };
            if local {
                by_points += 1;
                s += &format!("points = [[{:?}, {:?}], [{:?}, {:?}]]\n\n", la[0], la[1], lb[0], lb[1]);
            } else {
                s += &format!("at = [{:?}, {:?}]\n\n", at[0], at[1]);
            }
        }
        s += &format!("[simulation]\nend = {end:?}\noutput_every = 0.05\n");
        let first_crank = bodies.iter().position(|b| b.0 == "crank-0").unwrap_or(0);
        Variant {
            toml: s,
            first_crank,
            start: (th, w),
            description: format!(
                "bodies and joints shuffled (crank-0 is body {first_crank}), {by_points} of {} joints by local points",
                joints.len()
            ),
        }
    }
}

/// How [`NFourBar::written`] states the bodies' poses and the joints.
#[derive(Clone, Copy)]
enum Stated<'a> {
    /// Poses at the start; each joint by `at` or `points` at random.
    AsIs,
    /// Each body's position and angle moved by its three numbers (in the unshuffled order); every
    /// joint by its bodies' local points, so the link lengths stay the benchmark's.
    BodiesMoved(&'a [f64]),
    /// Every joint by its global point `at`, moved by its two numbers (in the unshuffled order):
    /// the link lengths change.
    JointsMoved(&'a [f64]),
}

/// Fisher–Yates shuffle with `rng`.
fn shuffle<T>(rng: &mut crate::fuzz::Rng, items: &mut [T]) {
    for i in (1..items.len()).rev() {
        items.swap(i, rng.below(i + 1));
    }
}
