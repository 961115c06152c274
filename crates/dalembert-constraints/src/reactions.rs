//! Joint reactions and driver efforts from the Lagrange multipliers.
//!
//! The generalized constraint force of constraint `k` on a moving body `b` is `Q_c,b = −C_q,bᵀ λ_k`
//! (`docs/equations.md` §2): its first two entries are the force on `b`, the third the torque about
//! `b`'s reference point. The reported **reaction** is the force the second body exerts on the
//! first, with its moment taken about the constraint's reaction point `P`:
//! `T_P = T_R − (P − R) × F`. When the first body is the ground, the reaction is computed on the
//! second body and negated (action and reaction are equal and opposite, with opposite moments about
//! the same point, for every constraint that depends only on the bodies' relative configuration).
//! A driver's effort is `−λ`.

use crate::{ConstraintRole, ConstraintSystem};
use dalembert_kinematics::rotation::cross;
use dalembert_kinematics::{BodyRef, BodyState, Vec2};
use dalembert_system::ConstraintValues;

/// The reaction of one constraint.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Reaction {
    /// Force on the first body from the second, global components (N).
    pub force: Vec2,
    /// Torque on the first body from the second about [`Reaction::point`] (N·m).
    pub torque: f64,
    /// The global point the torque is taken about.
    pub point: Vec2,
    /// For a driver, its effort `−λ`; `None` for a joint.
    pub effort: Option<f64>,
}

impl Reaction {
    /// The force in the frame of a body at angle `angle` (`Aᵀ F`).
    pub fn force_in_frame(&self, angle: f64) -> Vec2 {
        dalembert_kinematics::rotation(angle).transpose() * self.force
    }
}

impl ConstraintSystem {
    /// Reactions of every constraint for multipliers `lambda` at configuration `q`, into `out`
    /// (length: number of constraints). `values` must hold the Jacobian at `q`.
    pub fn reactions(&self, q: &[f64], values: &ConstraintValues, lambda: &[f64], out: &mut [Reaction]) {
        for (k, c) in self.constraints().iter().enumerate() {
            let [a, b] = c.bodies();
            let sa = BodyState::of(a, q, &[]);
            let sb = BodyState::of(b, q, &[]);
            let point = c.reaction_point(&sa, &sb);
            let r0 = self.row_offset(k);
            let ne = c.num_equations();
            let lam = &lambda[r0..r0 + ne];
            let blocks = self.blocks(k, values);
            // Generalized constraint force on one side: −J_sideᵀ λ.
            let on_side = |side: usize| -> [f64; 3] {
                let mut g = [0.0; 3];
                if let Some(jb) = blocks[side] {
                    for (e, l) in lam.iter().enumerate() {
                        for col in 0..3 {
                            g[col] -= jb[3 * e + col] * l;
                        }
                    }
                }
                g
            };
            let (force, torque) = if a != BodyRef::Ground {
                let g = on_side(0);
                let f = Vec2::new(g[0], g[1]);
                (f, g[2] - cross(point - sa.position, f))
            } else {
                let g = on_side(1);
                let f = Vec2::new(g[0], g[1]);
                (-f, -(g[2] - cross(point - sb.position, f)))
            };
            let effort = (c.role() == ConstraintRole::Driver).then(|| -lam[0]);
            out[k] = Reaction {
                force,
                torque,
                point,
                effort,
            };
        }
    }
}

impl ConstraintSystem {
    /// Every constraint's reaction at `(t, q)` for multipliers `lambda` (evaluates the constraints
    /// first; allocates: for analyses such as inverse dynamics, not for the stepping loop).
    pub fn reactions_at(&self, t: f64, q: &[f64], lambda: &[f64]) -> Vec<Reaction> {
        use dalembert_system::ConstraintSet;
        let mut values = self.values();
        self.evaluate(t, q, &[], &mut values);
        let mut out = vec![Reaction::default(); self.constraints().len()];
        self.reactions(q, &values, lambda, &mut out);
        out
    }
}
