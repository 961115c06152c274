//! The articulated-body algorithm: `q̈ = M(q)⁻¹ Q(t, q, q̇)` for a tree in joint coordinates in
//! O(n), without forming `M` (Featherstone 2008, table 7.1).
//!
//! ```text
//! pass 1 (root → leaves)   Xᵢ = X_J(qᵢ) X_T,   vᵢ = Xᵢ v_λ + Sᵢ q̇ᵢ,   cᵢ = vᵢ ×ₘ Sᵢ q̇ᵢ,
//!                          I^Aᵢ = Iᵢ,   p^Aᵢ = vᵢ ×* Iᵢ vᵢ
//! pass 2 (leaves → root)   Uᵢ = I^Aᵢ Sᵢ,   Dᵢ = Sᵢᵀ Uᵢ,   uᵢ = τᵢ − Sᵢᵀ p^Aᵢ,
//!                          I^a = I^Aᵢ − Uᵢ Uᵢᵀ / Dᵢ,   p^a = p^Aᵢ + I^a cᵢ + Uᵢ uᵢ / Dᵢ,
//!                          I^A_λ += Xᵢᵀ I^a Xᵢ,   p^A_λ += Xᵢᵀ p^a
//! pass 3 (root → leaves)   a' = Xᵢ a_λ + cᵢ,   q̈ᵢ = (uᵢ − Uᵢᵀ a') / Dᵢ,   aᵢ = a' + Sᵢ q̈ᵢ
//! ```
//!
//! with the base acceleration `a₀ = [0; −g]` standing for gravity and `τᵢ` the joint's force
//! element. `Dᵢ` is the pivot of the tree's `L D Lᵀ` factorization of `M`: one that is not
//! positive (a body chain without inertia about its joint) is reported, not divided by.

use super::algebra::{Inertia, Sv};
use super::recursion::Pass;
use super::KinematicTree;
use crate::{DynamicsError, MultibodySystem};

/// The workspace of the articulated-body algorithm for one tree, allocated once; solving
/// allocates nothing.
#[derive(Debug, Clone)]
pub struct Articulated {
    pass: Pass,
    ia: Vec<Inertia>,
    pa: Vec<Sv>,
    u: Vec<Sv>,
    d: Vec<f64>,
    tau: Vec<f64>,
    /// The generalized forces added to the tree's own (the caller's and the system's).
    added: Vec<f64>,
    /// [`Articulated::response`]'s bias forces, joint forces and accelerations.
    response_pa: Vec<Sv>,
    response_tau: Vec<f64>,
    response_a: Vec<Sv>,
}

impl Articulated {
    /// A workspace for `tree`.
    pub fn new(tree: &KinematicTree) -> Self {
        let n = tree.len();
        Articulated {
            pass: Pass::new(n),
            ia: vec![Inertia::zeros(); n],
            pa: vec![Sv::ZERO; n],
            u: vec![Sv::ZERO; n],
            d: vec![0.0; n],
            tau: vec![0.0; n],
            added: vec![0.0; n],
            response_pa: vec![Sv::ZERO; n],
            response_tau: vec![0.0; n],
            response_a: vec![Sv::ZERO; n],
        }
    }

    /// `x = M⁻¹ g` at the state of the last solve (its articulated inertias `I^A`, `Uᵢ`, `Dᵢ`
    /// and transforms kept): passes 2 and 3 again with the generalized force `g` alone, no
    /// velocities (`cᵢ = 0`, `p^Aᵢ = 0`) and no gravity (`a₀ = 0`), `O(n)`. It is the response of
    /// the accelerations to a force `g` ([`crate::Formulation::force_response`]), and to an impulse
    /// `g` of the velocities. `false` when no solve has been made (a pivot `Dᵢ` is still 0).
    pub fn response(&mut self, tree: &KinematicTree, g: &[f64], x: &mut [f64]) -> bool {
        let n = tree.len();
        if self.d.iter().any(|&d| d <= 0.0) || g.len() != n || x.len() != n {
            return false;
        }
        let p = &self.pass;
        self.response_pa.iter_mut().for_each(|v| *v = Sv::ZERO);
        for i in (0..n).rev() {
            let s = tree.subspace(i);
            let tau = g[i] - s.dot(&self.response_pa[i]);
            self.response_tau[i] = tau;
            if let Some(k) = tree.links[i].parent {
                let pa = self.response_pa[i] + self.u[i].scale(tau / self.d[i]);
                let back = p.x[i].force_back(&pa);
                self.response_pa[k] += back;
            }
        }
        for i in 0..n {
            let a_parent = tree.links[i].parent.map_or(Sv::ZERO, |k| self.response_a[k]);
            let a = p.x[i].motion(&a_parent);
            let xi = (self.response_tau[i] - self.u[i].dot(&a)) / self.d[i];
            x[i] = xi;
            self.response_a[i] = a + tree.subspace(i).scale(xi);
        }
        crate::all_finite(x)
    }

    /// The workspace for `system` when the formulations should solve it by this algorithm: a
    /// tree in joint coordinates ([`MultibodySystem::kinematic_tree`]) with no constraint
    /// equations, where every formulation's equations are `M q̈ = Q`.
    pub fn for_system(system: &dyn MultibodySystem) -> Option<Self> {
        match system.kinematic_tree() {
            Some(tree) if system.num_equations() == 0 => Some(Articulated::new(tree)),
            _ => None,
        }
    }

    /// `q̈` of `system` (whose [`MultibodySystem::kinematic_tree`] this workspace was made for) at
    /// `(t, q, q̇)` into `qdd`, after checking the state, with the generalized force `extra` added
    /// to the joints' (empty: none; [`crate::Data::set_extra_force`]) and the system's
    /// ([`MultibodySystem::add_joint_forces`]): what a formulation calls.
    pub fn solve(
        &mut self,
        system: &dyn MultibodySystem,
        (t, q, qd): (f64, &[f64], &[f64]),
        extra: &[f64],
        qdd: &mut [f64],
    ) -> Result<(), DynamicsError> {
        system.check_state(t, q, qd)?;
        match system.kinematic_tree() {
            Some(tree) if tree.len() == self.d.len() => {
                // Moved out for the solve and back (no allocation).
                let mut added = std::mem::take(&mut self.added);
                for (k, a) in added.iter_mut().enumerate() {
                    *a = extra.get(k).copied().unwrap_or(0.0);
                }
                system.add_joint_forces(t, q, qd, &mut added);
                let solved = self.solve_tree(tree, (t, q, qd), &added, qdd);
                self.added = added;
                solved
            }
            _ => Err(DynamicsError::Singular {
                time: t,
                what: "the articulated-body workspace does not match the system's tree".into(),
            }),
        }
    }

    /// Each body's spatial acceleration `[α; a_O]` (body components, origin on its joint) from the
    /// last [`Articulated::accelerations`], and pass 1's velocities `[ω; v_O]`. The accelerations
    /// include the fictitious base acceleration `[0; −g]` that stands for gravity: the body's true
    /// acceleration is `[α; a_O + Rᵀ g]` with `R` its axes in the world
    /// ([`KinematicTree::world_frames`]).
    pub fn body_motion(&self) -> (&[Sv], &[Sv]) {
        (&self.pass.f, &self.pass.v)
    }

    /// `q̈` at `(q, q̇)` into `qdd` (lengths: the tree's joints).
    pub fn accelerations(
        &mut self,
        tree: &KinematicTree,
        t: f64,
        q: &[f64],
        qd: &[f64],
        qdd: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.solve_tree(tree, (t, q, qd), &[], qdd)
    }

    /// [`Articulated::accelerations`] with the generalized force `extra` (one per joint, or
    /// empty) added to the joints' forces.
    fn solve_tree(
        &mut self,
        tree: &KinematicTree,
        (t, q, qd): (f64, &[f64], &[f64]),
        extra: &[f64],
        qdd: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let n = tree.len();
        let p = &mut self.pass;
        tree.velocities(q, qd, p);
        for i in 0..n {
            let inertia = &tree.links[i].inertia;
            self.ia[i] = *inertia;
            self.pa[i] = p.v[i].cross_force(&inertia.mul(&p.v[i]));
        }
        for i in (0..n).rev() {
            let s = tree.subspace(i);
            let u = self.ia[i].mul(&s);
            let d = s.dot(&u);
            if d.is_nan() || d <= 0.0 {
                return Err(DynamicsError::SingularMass {
                    time: t,
                    bodies: vec![tree.bodies()[i].name.clone()],
                });
            }
            let tau = tree.joint_force(i, q[i], qd[i]) + extra.get(i).copied().unwrap_or(0.0) - s.dot(&self.pa[i]);
            (self.u[i], self.d[i], self.tau[i]) = (u, d, tau);
            if let Some(k) = tree.links[i].parent {
                let mut ia = self.ia[i];
                ia.sub_outer(&u, d);
                let pa = self.pa[i] + ia.mul(&p.c[i]) + u.scale(tau / d);
                let back = ia.transform_back(&p.x[i]);
                self.ia[k].add(&back);
                let back = p.x[i].force_back(&pa);
                self.pa[k] += back;
            }
        }
        // Pass 3: p.f holds the body accelerations.
        let a0 = tree.base_acceleration();
        for i in 0..n {
            let a_parent = tree.links[i].parent.map_or(a0, |k| p.f[k]);
            let a = p.x[i].motion(&a_parent) + p.c[i];
            let qdd_i = (self.tau[i] - self.u[i].dot(&a)) / self.d[i];
            qdd[i] = qdd_i;
            p.f[i] = a + tree.subspace(i).scale(qdd_i);
        }
        if !crate::all_finite(qdd) {
            let i = qdd.iter().position(|x| !x.is_finite()).unwrap_or(0);
            return Err(DynamicsError::NonFinite {
                time: t,
                what: format!("acceleration of body '{}'", tree.bodies()[i].name),
            });
        }
        Ok(())
    }
}
