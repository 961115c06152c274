//! The recursions that need no factorization: joint transforms and velocities (pass 1 of every
//! algorithm), the recursive Newton–Euler bias forces, the composite-rigid-body mass matrix, world
//! frames and energies (Featherstone 2008, tables 5.1 and 6.2).

use super::algebra::{Inertia, Sv, Transform, M3, V3};
use super::{JointKind, KinematicTree};

/// Per-body scratch of the recursions, allocated once.
#[derive(Debug, Clone)]
pub(crate) struct Pass {
    /// Parent → body transforms.
    pub x: Vec<Transform>,
    /// Body velocities (body frame).
    pub v: Vec<Sv>,
    /// Velocity-product accelerations `c_i = v_i ×ₘ S_i q̇_i`.
    pub c: Vec<Sv>,
    /// Forces or accelerations, by use.
    pub f: Vec<Sv>,
    /// Composite inertias.
    pub ic: Vec<Inertia>,
}

impl Pass {
    pub fn new(n: usize) -> Self {
        Pass {
            x: vec![Transform::identity(); n],
            v: vec![Sv::ZERO; n],
            c: vec![Sv::ZERO; n],
            f: vec![Sv::ZERO; n],
            ic: vec![Inertia::zeros(); n],
        }
    }
}

/// A body's frame in the world: axes (body → world), origin, and its velocity `[ω; v_O]` in body
/// components.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldFrame {
    /// Body axes in world components (columns).
    pub rotation: M3,
    /// Origin (on the body's joint) in the world.
    pub origin: V3,
    /// Velocity of the body frame, body components: angular velocity and the origin's velocity.
    pub velocity: Sv,
}

impl KinematicTree {
    /// Motion subspace of joint `i` in body axes: `[a; 0]` (revolute) or `[0; a]` (prismatic).
    #[inline]
    pub(crate) fn subspace(&self, i: usize) -> Sv {
        let l = &self.links[i];
        match l.kind {
            JointKind::Revolute => Sv::new(l.axis, V3::zeros()),
            JointKind::Prismatic => Sv::new(V3::zeros(), l.axis),
        }
    }

    /// The transform from joint `i`'s parent frame to its body frame at coordinate `q`.
    #[inline]
    pub(crate) fn joint_transform(&self, i: usize, q: f64) -> Transform {
        let l = &self.links[i];
        match l.kind {
            JointKind::Revolute => {
                let (s, c) = q.sin_cos();
                let (p1, p2) = &l.rodrigues;
                Transform {
                    e: l.rotation_t - p1 * s + p2 * (1.0 - c),
                    r: l.location,
                }
            }
            JointKind::Prismatic => Transform {
                e: l.rotation_t,
                r: l.location + l.rotation_t.tr_mul(&(l.axis * q)),
            },
        }
    }

    /// Pass 1: transforms, velocities and velocity-product terms of every body.
    pub(crate) fn velocities(&self, q: &[f64], qd: &[f64], p: &mut Pass) {
        for i in 0..self.links.len() {
            let x = self.joint_transform(i, q[i]);
            let vj = self.subspace(i).scale(qd[i]);
            let v = match self.links[i].parent {
                Some(k) => x.motion(&p.v[k]) + vj,
                None => vj,
            };
            p.c[i] = v.cross_motion(&vj);
            p.x[i] = x;
            p.v[i] = v;
        }
    }

    /// The base acceleration that stands for gravity: `[0; −g]`.
    #[inline]
    pub(crate) fn base_acceleration(&self) -> Sv {
        Sv::new(V3::zeros(), -self.gravity)
    }

    /// `out = τ(q, q̇) − (C(q, q̇) q̇ + g(q))`: joint forces minus the recursive Newton–Euler
    /// inverse dynamics at `q̈ = 0` (Featherstone table 5.1): the seam's `Q`. Each joint's part
    /// of the force it transmits at `q̈ = 0` ([`KinematicTree::joint_wrenches`]).
    pub(crate) fn bias_forces(&self, q: &[f64], qd: &[f64], p: &mut Pass, out: &mut [f64]) {
        self.joint_wrenches((q, qd, None), false, false, p);
        for (i, o) in out.iter_mut().enumerate().take(self.links.len()) {
            *o = self.joint_force(i, q[i], qd[i]) - self.subspace(i).dot(&p.f[i]);
        }
    }

    /// The force each joint transmits to its body's subtree at `(q, q̇)` under the
    /// accelerations `q̈` (`None`: zero), `[n; f]` in the body's axes at its origin (on the joint), into `p.f`:
    /// the recursive Newton–Euler algorithm's backward pass (Featherstone table 5.1), gravity as
    /// the base's acceleration `[0; −g]`. It holds the joint's reaction and its own force along
    /// its motion subspace. With `response`, only the part linear in `q̈` (no velocities, no
    /// gravity): the forces' change under a change `q̈` of the accelerations; `p.x` is then
    /// taken as it is where `transforms` says it holds `q`'s transforms already.
    pub(crate) fn joint_wrenches(
        &self,
        (q, qd, qdd): (&[f64], &[f64], Option<&[f64]>),
        response: bool,
        transforms: bool,
        p: &mut Pass,
    ) {
        let n = self.links.len();
        if !response {
            self.velocities(q, qd, p);
        } else if !transforms {
            for i in 0..n {
                p.x[i] = self.joint_transform(i, q[i]);
            }
        }
        let a0 = if response { Sv::ZERO } else { self.base_acceleration() };
        for i in 0..n {
            let a_parent = self.links[i].parent.map_or(a0, |k| p.f[k]);
            let mut a = p.x[i].motion(&a_parent);
            if let Some(qdd) = qdd {
                a += self.subspace(i).scale(qdd[i]);
            }
            if !response {
                a += p.c[i];
            }
            p.f[i] = a;
        }
        for i in 0..n {
            let inertia = &self.links[i].inertia;
            let a = p.f[i];
            p.f[i] = inertia.mul(&a);
            if !response {
                p.f[i] += p.v[i].cross_force(&inertia.mul(&p.v[i]));
            }
        }
        for i in (0..n).rev() {
            if let Some(k) = self.links[i].parent {
                let back = p.x[i].force_back(&p.f[i]);
                p.f[k] += back;
            }
        }
    }

    /// The joint-space mass matrix `M(q)` into `m` (row-major, n × n) by the composite-rigid-body
    /// algorithm (Featherstone table 6.2).
    pub(crate) fn mass_matrix(&self, q: &[f64], p: &mut Pass, m: &mut [f64]) {
        let n = self.links.len();
        for i in 0..n {
            p.x[i] = self.joint_transform(i, q[i]);
            p.ic[i] = self.links[i].inertia;
        }
        for i in (0..n).rev() {
            if let Some(k) = self.links[i].parent {
                let back = p.ic[i].transform_back(&p.x[i]);
                p.ic[k].add(&back);
            }
        }
        m.iter_mut().for_each(|x| *x = 0.0);
        for i in 0..n {
            let mut f = p.ic[i].mul(&self.subspace(i));
            m[i * n + i] = self.subspace(i).dot(&f);
            let mut j = i;
            while let Some(k) = self.links[j].parent {
                f = p.x[j].force_back(&f);
                j = k;
                let h = self.subspace(j).dot(&f);
                m[i * n + j] = h;
                m[j * n + i] = h;
            }
        }
    }

    /// Every body's frame in the world at `(q, q̇)` into `out` (one per body); without `qd` the
    /// velocities are zero.
    pub fn world_frames(&self, q: &[f64], qd: Option<&[f64]>, out: &mut [WorldFrame]) {
        for i in 0..self.links.len() {
            let x = self.joint_transform(i, q[i]);
            let (rotation, origin, v_parent) = match self.links[i].parent {
                Some(k) => (
                    out[k].rotation * x.e.transpose(),
                    out[k].origin + out[k].rotation * x.r,
                    out[k].velocity,
                ),
                None => (x.e.transpose(), x.r, Sv::ZERO),
            };
            let velocity = x.motion(&v_parent) + self.subspace(i).scale(qd.map_or(0.0, |r| r[i]));
            out[i] = WorldFrame {
                rotation,
                origin,
                velocity,
            };
        }
    }

    /// Kinetic energy `½ Σ vᵢᵀ Iᵢ vᵢ` from pass 1's velocities.
    pub(crate) fn kinetic(&self, p: &Pass) -> f64 {
        (0..self.links.len())
            .map(|i| 0.5 * p.v[i].dot(&self.links[i].inertia.mul(&p.v[i])))
            .sum()
    }

    /// Potential energy of gravity (`−m g · r_c`) and of the joint springs, with `frames` from
    /// [`KinematicTree::world_frames`].
    pub(crate) fn potential(&self, q: &[f64], frames: &[WorldFrame]) -> f64 {
        let mut v = 0.0;
        for (i, l) in self.links.iter().enumerate() {
            let com = frames[i].origin + frames[i].rotation * l.com;
            v -= l.mass * self.gravity.dot(&com);
            if let Some(f) = &l.force {
                let d = q[i] - f.rest;
                v += 0.5 * f.stiffness * d * d - f.effort * q[i];
            }
        }
        v
    }
}
