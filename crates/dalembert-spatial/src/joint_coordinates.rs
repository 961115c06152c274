//! A spatial model that is a tree of revolute and prismatic joints, in joint coordinates
//! ([`dalembert_system::JointSpace`]): one coordinate per joint instead of 7 positions and 6
//! velocities per body, no constraint equations, and the formulations' solve by the
//! articulated-body algorithm (`docs/joint-coordinates.md`).
//!
//! The tree's zero configuration is the model's initial one. Body `k`'s tree frame has its
//! origin at the joint that attaches it to its parent and the body's axes; the joint's axis is
//! the model's (fixed in both bodies). Initial rates are the joints' relative velocities along
//! their axes: the model's initial velocities projected onto the joints.

use crate::couplings::wrap_angle;
use crate::euler_parameters::{self, from_rotation};
use crate::forces::ForceData;
use crate::frame::{NQ, NV};
use crate::joints::JointKind;
use crate::Model;
use dalembert_system::tree::{self, KinematicTree, TreeBody, WorldFrame};
use dalembert_system::tree::{JointAxisLaw, TreeCoordinate};
use dalembert_system::{JointSpace, ModelError};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// A spatial model in joint coordinates, with the map back to its absolute coordinates.
#[derive(Debug, Clone)]
pub struct JointCoordinates {
    system: Arc<JointSpace>,
    /// The model's index of each tree body.
    bodies: Vec<usize>,
    q0: Vec<f64>,
    v0: Vec<f64>,
}

/// A body's centre of mass, axes, centre-of-mass velocity and angular velocity (global).
type BodyState = (Vector3<f64>, Matrix3<f64>, Vector3<f64>, Vector3<f64>);

fn refuse(element: String, what: &str) -> ModelError {
    ModelError::InvalidParameter {
        element,
        what: what.to_string(),
    }
}

impl Model {
    /// This model in joint coordinates, when it is a tree of revolute and prismatic joints
    /// rooted at the ground, with gravity, forces about the joints' axes only and no drivers
    /// (the forces' laws then read the joint coordinate: a spring's deflection is not measured
    /// within a turn); otherwise an error
    /// naming the first element that joint coordinates cannot take. The tree's zero
    /// configuration is the bodies' initial poses ([`Model::initial_state`]); see
    /// [`Model::joint_coordinates_at`].
    pub fn joint_coordinates(&self) -> Result<JointCoordinates, ModelError> {
        let (q, v) = self.initial_state();
        self.joint_coordinates_at(&q, &v)
    }

    /// [`Model::joint_coordinates`] with the tree's zero configuration at the absolute state
    /// `(q, v)` (an assembled state: the joints hold there), and the initial rates the joints'
    /// relative velocities along their axes at `v`.
    pub fn joint_coordinates_at(&self, q: &[f64], v: &[f64]) -> Result<JointCoordinates, ModelError> {
        if let Some(d) = self.driver_names().next() {
            return Err(refuse(format!("driver '{d}'"), "joint coordinates take no drivers yet"));
        }
        if let Some(c) = self.limits.get(self.limited_joints.len()) {
            return Err(refuse(
                format!("contact '{}'", c.name),
                "rigid contact is solved in absolute coordinates only",
            ));
        }
        if let Some(c) = self.coupling_names().next() {
            return Err(refuse(
                format!("coupling '{c}'"),
                "is a constraint between joints, solved in absolute coordinates only",
            ));
        }
        if let Some((_, f)) = self
            .force_data()
            .iter()
            .zip(self.force_names())
            .find(|(f, _)| !matches!(f, ForceData::AboutAxis(_) | ForceData::AlongAxis(_)))
        {
            return Err(refuse(
                format!("force '{f}'"),
                "joint coordinates take gravity and the forces about and along joint axes (joint torques, rotational springs, servos) only",
            ));
        }
        let n = self.bodies().len();
        let joints = self.joints();
        if joints.len() < n {
            // Bodies no chain of joints joins to the ground (a free body, a robot's floating
            // base): the first of them named.
            let mut grounded = vec![false; n];
            let mut grew = true;
            while grew {
                grew = false;
                for j in joints {
                    for (a, b) in [(j.body_i, j.body_j), (j.body_j, j.body_i)] {
                        if let Some(k) = b {
                            if a.is_none_or(|i| grounded[i]) && !grounded[k] {
                                grounded[k] = true;
                                grew = true;
                            }
                        }
                    }
                }
            }
            let free = (0..n)
                .find(|&k| !grounded[k])
                .map_or(String::from("model"), |k| format!("body '{}'", self.bodies()[k].name));
            return Err(refuse(
                free,
                "moves freely (no joint holds it: a free body or a floating base); joint coordinates take revolute and prismatic joints only, so run it in absolute coordinates",
            ));
        }
        if joints.len() != n {
            return Err(refuse(
                "model".into(),
                &format!(
                    "joint coordinates need a tree: one joint per body ({} joints for {n} bodies)",
                    joints.len()
                ),
            ));
        }
        if q.len() != NQ * n || v.len() != NV * n {
            return Err(refuse(
                "state".into(),
                &format!(
                    "needs {} positions and {} velocities, got {} and {}",
                    NQ * n,
                    NV * n,
                    q.len(),
                    v.len()
                ),
            ));
        }
        // Per body: centre of mass, axes, centre-of-mass velocity and angular velocity (global).
        let frames: Vec<BodyState> = (0..n)
            .map(|k| {
                let (qk, vk) = (&q[NQ * k..NQ * (k + 1)], &v[NV * k..NV * (k + 1)]);
                let p = euler_parameters::normalized(&[qk[3], qk[4], qk[5], qk[6]]);
                let a = euler_parameters::rotation(&p);
                let w = a * Vector3::new(vk[3], vk[4], vk[5]);
                (
                    Vector3::new(qk[0], qk[1], qk[2]),
                    a,
                    Vector3::new(vk[0], vk[1], vk[2]),
                    w,
                )
            })
            .collect();
        // The joints at each body (the ground is slot n), then depth first from the ground: each
        // joint attaches the body it reaches to its parent. O(bodies + joints).
        let slot = |b: Option<usize>| b.unwrap_or(n);
        let mut at: Vec<Vec<usize>> = vec![Vec::new(); n + 1];
        for (k, j) in joints.iter().enumerate() {
            at[slot(j.body_i)].push(k);
            at[slot(j.body_j)].push(k);
        }
        let mut order: Vec<(usize, Option<usize>, usize)> = Vec::with_capacity(n); // (body, parent, joint)
        let mut tree_index = vec![usize::MAX; n];
        let mut used = vec![false; joints.len()];
        let mut frontier: Vec<Option<usize>> = vec![None];
        while let Some(parent) = frontier.pop() {
            for &k in &at[slot(parent)] {
                if std::mem::replace(&mut used[k], true) {
                    continue;
                }
                let j = &joints[k];
                let loop_error = || {
                    refuse(
                        format!("joint '{}'", j.name),
                        "closes a loop: joint coordinates need a tree (use the absolute coordinates)",
                    )
                };
                // The other end; the ground reached again closes a loop.
                let child = if j.body_i == parent { j.body_j } else { j.body_i };
                let Some(child) = child else {
                    return Err(loop_error());
                };
                if tree_index[child] != usize::MAX {
                    return Err(loop_error());
                }
                match j.kind {
                    Some(JointKind::Revolute | JointKind::Prismatic) => {}
                    other => {
                        let kind = other.map_or("a driver", |k| k.name());
                        return Err(refuse(
                            format!("joint '{}'", j.name),
                            &format!("joint coordinates take revolute and prismatic joints, not {kind}"),
                        ));
                    }
                }
                tree_index[child] = order.len();
                order.push((child, parent, k));
                frontier.push(Some(child));
            }
        }
        if let Some(k) = tree_index.iter().position(|&t| t == usize::MAX) {
            return Err(refuse(
                format!("body '{}'", self.bodies()[k].name),
                "is not joined to the ground through the tree",
            ));
        }
        // Each tree body's frame: origin at its joint (global), the body's axes.
        let mut origin = vec![Vector3::zeros(); n];
        let mut bodies = Vec::with_capacity(n);
        // Zero joint coordinates: the tree is built at this state.
        let (q0, mut v0) = (vec![0.0; n], vec![0.0; n]);
        for (t, &(child, parent, k)) in order.iter().enumerate() {
            let j = &joints[k];
            let (r, a, vel, w) = frames[child];
            let (point, axes) = if j.body_j == Some(child) {
                (j.point_j, j.axes_j)
            } else {
                (j.point_i, j.axes_i)
            };
            let axis = axes.column(2).into_owned();
            origin[t] = r + a * point;
            let (location, rotation) = match parent {
                None => (origin[t], a),
                Some(p) => {
                    let (tp, ap) = (tree_index[p], frames[p].1);
                    (ap.transpose() * (origin[t] - origin[tp]), ap.transpose() * a)
                }
            };
            let body = &self.bodies()[child];
            let kind = if j.kind == Some(JointKind::Revolute) {
                tree::JointKind::Revolute
            } else {
                tree::JointKind::Prismatic
            };
            // Initial rate: the relative motion along the axis.
            let axis_global = a * axis;
            let (w_parent, v_parent) = parent.map_or((Vector3::zeros(), Vector3::zeros()), |p| {
                let (rp, _, vp, wp) = frames[p];
                (wp, vp + wp.cross(&(origin[t] - rp)))
            });
            v0[t] = match kind {
                tree::JointKind::Revolute => axis_global.dot(&(w - w_parent)),
                _ => axis_global.dot(&(vel + w.cross(&(origin[t] - r)) - v_parent)),
            };
            let rows = |m: &Matrix3<f64>| [0, 1, 2].map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]]);
            bodies.push(TreeBody {
                name: body.name.clone(),
                parent: parent.map(|p| tree_index[p]),
                kind,
                axis: axis.into(),
                location: location.into(),
                rotation: rows(&rotation),
                mass: body.mass,
                com: (-point).into(),
                inertia: rows(&body.inertia),
                force: None,
            });
        }
        let tree = KinematicTree::new(self.gravity().into(), bodies)?;
        // Each limit on its joint's coordinate, which is zero here: the joint's value here added.
        let mut tree_joint = vec![0; joints.len()];
        for (t, &(_, _, k)) in order.iter().enumerate() {
            tree_joint[k] = t;
        }
        // A model's joint value turns sign on the tree's coordinate where the joint's first body
        // is the child (the model measures the second body relative to the first).
        let sign = |k: usize| {
            if joints[k].body_j == Some(order[tree_joint[k]].0) {
                1.0
            } else {
                -1.0
            }
        };
        let mut row = dalembert_system::SlipRow::default();
        let limited = self
            .limited_joints
            .iter()
            .map(|&k| TreeCoordinate {
                joint: tree_joint[k],
                sign: sign(k),
                offset: self.joint_row_into(k, q, v, &mut row),
            })
            .collect();
        // Each law about or along a joint's axis on its joint's coordinate: the law's angle or
        // displacement here added,
        // its sign turned where the law's second body is the joint's parent in the tree.
        let frame = |b: Option<usize>| self.frame(b, q, v);
        let laws = self
            .force_data()
            .iter()
            .filter_map(|f| match f {
                // The angle taken within a half turn of the free angle, as the model measures
                // its deflection (a spring whose free angle is near ±π starts where it should).
                ForceData::AboutAxis(a) => {
                    let (k, law) = a.joint_law();
                    let free = law.free_angle;
                    Some(((k, law), free + wrap_angle(a.angle_at(&frame) - free)))
                }
                ForceData::AlongAxis(a) => Some((a.joint_law(), a.displacement_at(&frame))),
                _ => None,
            })
            .map(|((k, law), offset)| JointAxisLaw {
                coordinate: TreeCoordinate {
                    joint: tree_joint[k],
                    sign: sign(k),
                    offset,
                },
                law: law.clone(),
            })
            .collect();
        // Each friction element on its joint's coordinate (its slip rate the joint's rate as the
        // model reads it); its load the force the joint transmits, from the tree.
        let friction_joints = self
            .friction_joints
            .iter()
            .map(|&k| TreeCoordinate {
                joint: tree_joint[k],
                sign: sign(k),
                offset: 0.0,
            })
            .collect();
        let system = JointSpace::new(tree)
            .with_limits(self.limits.clone(), limited)?
            .with_frictions(self.frictions.clone(), friction_joints)?
            .with_axis_laws(laws)?;
        Ok(JointCoordinates {
            system: Arc::new(system),
            bodies: order.iter().map(|o| o.0).collect(),
            q0,
            v0,
        })
    }
}

impl JointCoordinates {
    /// The system in joint coordinates.
    pub fn system(&self) -> Arc<JointSpace> {
        self.system.clone()
    }

    /// The initial joint coordinates (zero: the model's initial configuration) and rates.
    pub fn initial_state(&self) -> (Vec<f64>, Vec<f64>) {
        (self.q0.clone(), self.v0.clone())
    }

    /// The model's index of each tree body (the tree lists parents first).
    pub fn model_bodies(&self) -> &[usize] {
        &self.bodies
    }

    /// Storage for [`JointCoordinates::absolute`].
    pub fn frames(&self) -> Vec<WorldFrame> {
        let tree = self.system.tree();
        let mut out = vec![
            WorldFrame {
                rotation: Matrix3::identity(),
                origin: Vector3::zeros(),
                velocity: Default::default(),
            };
            tree.len()
        ];
        tree.world_frames(&self.q0, Some(&self.v0), &mut out);
        out
    }

    /// The model's absolute coordinates at joint state `(q, q̇)`: per body (in the model's order)
    /// centre of mass and Euler parameters into `q_abs` (7 each), centre-of-mass velocity (global)
    /// and body-frame angular velocity into `v_abs` (6 each). `frames` from
    /// [`JointCoordinates::frames`].
    pub fn absolute(&self, q: &[f64], qd: &[f64], frames: &mut [WorldFrame], q_abs: &mut [f64], v_abs: &mut [f64]) {
        let tree = self.system.tree();
        tree.world_frames(q, Some(qd), frames);
        for (t, (&k, f)) in self.bodies.iter().zip(frames.iter()).enumerate() {
            let com = Vector3::from(tree.bodies()[t].com);
            let r = f.origin + f.rotation * com;
            let p = from_rotation(&f.rotation);
            q_abs[NQ * k..NQ * k + 3].copy_from_slice(r.as_slice());
            q_abs[NQ * k + 3..NQ * k + 7].copy_from_slice(&p);
            let (w, v_o) = (f.velocity.w, f.velocity.v);
            let v = f.rotation * (v_o + w.cross(&com));
            v_abs[NV * k..NV * k + 3].copy_from_slice(v.as_slice());
            v_abs[NV * k + 3..NV * k + 6].copy_from_slice(w.as_slice());
        }
    }
}
