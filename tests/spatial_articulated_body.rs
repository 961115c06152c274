//! The library's articulated-body algorithm (`dalembert_system::tree::Articulated`, 3 × 3 blocks,
//! on the tree that `Model::joint_coordinates` makes of the spatial model) against Featherstone's
//! algorithm written here from its textbook form (*Rigid Body Dynamics Algorithms*, 2008, table
//! 7.1) with dense 6 × 6 transforms, from the definition of the anchors' spatial chain (`chain3d`:
//! boxes joined by revolute joints about alternating y and z axes) alone: link length, mass,
//! inertia, joint axes. At states where every joint has a random angle and rate, the two `q̈`
//! agree to 1e-12 of the largest: two O(n) recursions in different arithmetic (measured
//! 2026-11-25: 1.3e-14). This checks the conversion of the model to joint coordinates
//! and the library's recursion together; `tests/joint_coordinates.rs` checks both against the
//! formulations in absolute coordinates.

use dalembert::system::tree::Articulated;
use dalembert_testkit::fuzz::Rng;
use nalgebra::{Matrix3, Matrix6, Rotation3, Unit, Vector3, Vector6};

type V3 = Vector3<f64>;
type V6 = Vector6<f64>;

/// Gravity of the anchors' spatial scenes (−z).
const G: f64 = 9.81;

fn split(v: &V6) -> (V3, V3) {
    (v.fixed_rows::<3>(0).into_owned(), v.fixed_rows::<3>(3).into_owned())
}

fn join(a: V3, b: V3) -> V6 {
    V6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

/// Motion cross product `v ×ₘ m` of spatial vectors `[ω; v_O]`.
fn crm(v: &V6, m: &V6) -> V6 {
    let ((w, vo), (mw, mv)) = (split(v), split(m));
    join(w.cross(&mw), w.cross(&mv) + vo.cross(&mw))
}

/// Force cross product `v ×* f` of a motion `[ω; v_O]` and a force `[n_O; f]`.
fn crf(v: &V6, f: &V6) -> V6 {
    let ((w, vo), (n, ff)) = (split(v), split(f));
    join(w.cross(&n) + vo.cross(&ff), w.cross(&ff))
}

/// chain3d-N from its definition in `shared/anchors/README.md`: link i's frame has its origin at
/// joint i and coincides with the world frame at zero angles; joint 0 at the origin, joint i ≥ 1
/// at (1, 0, 0) of link i − 1; joint i about y (even i) or z (odd i); each link 1 kg, centre of
/// mass (0.5, 0, 0), inertia diag(1/600, 1.01/12, 1.01/12) about it.
struct Chain {
    n: usize,
    /// Spatial inertia of a link about its frame origin.
    inertia: Matrix6<f64>,
}

/// Per link, in its own frame: `X` (parent to link), the velocity, and the velocity-product
/// acceleration `c = v ×ₘ S θ̇`.
struct Pass {
    x: Vec<Matrix6<f64>>,
    v: Vec<V6>,
    c: Vec<V6>,
}

impl Chain {
    fn new(n: usize) -> Self {
        let com = V3::new(0.5, 0.0, 0.0);
        let ic = Matrix3::from_diagonal(&V3::new(1.0 / 600.0, 1.01 / 12.0, 1.01 / 12.0));
        let cx = com.cross_matrix();
        let mut inertia = Matrix6::zeros();
        inertia
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(ic + cx * cx.transpose()));
        inertia.fixed_view_mut::<3, 3>(0, 3).copy_from(&cx);
        inertia.fixed_view_mut::<3, 3>(3, 0).copy_from(&cx.transpose());
        inertia.fixed_view_mut::<3, 3>(3, 3).copy_from(&Matrix3::identity());
        Chain { n, inertia }
    }

    fn axis(i: usize) -> V3 {
        if i.is_multiple_of(2) {
            V3::y()
        } else {
            V3::z()
        }
    }

    /// Motion subspace of joint i in link i's frame.
    fn s(i: usize) -> V6 {
        join(Self::axis(i), V3::zeros())
    }

    /// Rotation of link i relative to its parent (link frame to parent frame).
    fn rotation(i: usize, angle: f64) -> Matrix3<f64> {
        Rotation3::from_axis_angle(&Unit::new_normalize(Self::axis(i)), angle).into_inner()
    }

    /// Joint i's position in the parent's frame.
    fn offset(i: usize) -> V3 {
        if i == 0 {
            V3::zeros()
        } else {
            V3::x()
        }
    }

    /// Plücker transform from the parent's frame to link i's: `[[E, 0], [−E [r]×, E]]`.
    fn transform(i: usize, angle: f64) -> Matrix6<f64> {
        let e = Self::rotation(i, angle).transpose();
        let mut x = Matrix6::zeros();
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&e);
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&e);
        x.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(-e * Self::offset(i).cross_matrix()));
        x
    }

    /// Pass 1: transforms, velocities and velocity-product accelerations.
    fn velocities(&self, th: &[f64], thd: &[f64]) -> Pass {
        let mut p = Pass {
            x: Vec::new(),
            v: Vec::new(),
            c: Vec::new(),
        };
        for i in 0..self.n {
            let x = Self::transform(i, th[i]);
            let vj = Self::s(i) * thd[i];
            let v = if i == 0 { vj } else { x * p.v[i - 1] + vj };
            p.c.push(crm(&v, &vj));
            p.x.push(x);
            p.v.push(v);
        }
        p
    }

    /// Joint accelerations from pass 1 `p` (table 7.1), gravity as a base acceleration `−g`.
    fn joint_accelerations(&self, p: &Pass) -> Vec<f64> {
        let n = self.n;
        let mut ia: Vec<Matrix6<f64>> = vec![self.inertia; n];
        let mut pa: Vec<V6> = (0..n).map(|i| crf(&p.v[i], &(self.inertia * p.v[i]))).collect();
        let (mut uu, mut dd, mut tau) = (vec![V6::zeros(); n], vec![0.0; n], vec![0.0; n]);
        for i in (0..n).rev() {
            let s = Self::s(i);
            uu[i] = ia[i] * s;
            dd[i] = s.dot(&uu[i]);
            tau[i] = -s.dot(&pa[i]);
            if i > 0 {
                let ia_i = ia[i] - uu[i] * uu[i].transpose() / dd[i];
                let pa_i = pa[i] + ia_i * p.c[i] + uu[i] * (tau[i] / dd[i]);
                ia[i - 1] += p.x[i].transpose() * ia_i * p.x[i];
                pa[i - 1] += p.x[i].transpose() * pa_i;
            }
        }
        let mut a_parent = join(V3::zeros(), V3::new(0.0, 0.0, G));
        let mut thdd = vec![0.0; n];
        for i in 0..n {
            let a = p.x[i] * a_parent + p.c[i];
            thdd[i] = (tau[i] - uu[i].dot(&a)) / dd[i];
            a_parent = a + Self::s(i) * thdd[i];
        }
        thdd
    }
}

/// Uniform in `[lo, hi)` from the test kit's generator.
fn uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
}

#[test]
fn the_library_recursion_gives_the_textbook_accelerations() {
    let mut worst = 0.0f64;
    for (n, seeds) in [(1usize, 0..3u64), (3, 3..6), (8, 6..9), (16, 9..11)] {
        let chain = Chain::new(n);
        let jc = dalembert_testkit::spatial::chain3d(n)
            .joint_coordinates()
            .expect("chain3d is a tree");
        let sys = jc.system();
        let mut aba = Articulated::new(sys.tree());
        for seed in seeds {
            let mut rng = Rng::new(seed);
            let th: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -1.5, 1.5)).collect();
            let thd: Vec<f64> = (0..n).map(|_| uniform(&mut rng, -3.0, 3.0)).collect();
            let expected = chain.joint_accelerations(&chain.velocities(&th, &thd));
            let mut qdd = vec![0.0; n];
            aba.solve(sys.as_ref(), (0.0, &th, &thd), &[], &mut qdd)
                .expect("evaluation");
            let scale = expected.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            let diff = qdd.iter().zip(&expected).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            worst = worst.max(diff / scale);
            assert!(
                diff <= 1e-12 * scale,
                "N = {n}, seed {seed}: max |Δq̈| {diff:e} of {scale:e}"
            );
        }
    }
    println!("largest difference from the textbook recursion, relative to the largest acceleration: {worst:e}");
}
