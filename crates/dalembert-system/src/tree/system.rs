//! [`JointSpace`]: a kinematic tree in joint coordinates as a [`MultibodySystem`], so that every
//! formulation and integrator runs it unchanged.

use super::recursion::{Pass, WorldFrame};
use super::{JointKind, KinematicTree};
use crate::{
    AxisLaw, BlockDiagonal, ConstraintPattern, ConstraintSet, ConstraintValues, DynamicsError, EquationRef,
    JointFriction, JointLimit, Layout, ModelError, MultibodySystem, SlipRow,
};
use std::sync::Mutex;

/// A [`KinematicTree`] on the seam: positions the joint coordinates, velocities their rates (one
/// layout block per body, named after it), no constraint equations, `M(q)` as one dense block
/// (the joint coordinates couple every body with its ancestors), `Q` by the recursive
/// Newton–Euler algorithm. Formulations solve it by [`super::Articulated`].
#[derive(Debug)]
pub struct JointSpace {
    tree: KinematicTree,
    layout: Layout,
    pattern: ConstraintPattern,
    /// Scratch of the recursions behind `&self` (allocated once; the lock is uncontended in a run).
    scratch: Mutex<Scratch>,
    /// Limits on some joints ([`JointSpace::with_limits`]).
    limits: Vec<JointLimit>,
    /// Each limit's coordinate on the tree ([`JointSpace::with_limits`]).
    limited: Vec<TreeCoordinate>,
    /// Torque laws about joints' axes ([`JointSpace::with_axis_laws`]).
    laws: Vec<JointAxisLaw>,
    /// Friction in some joints ([`JointSpace::with_frictions`]), and each one's coordinate.
    frictions: Vec<JointFriction>,
    friction_joints: Vec<TreeCoordinate>,
}

/// An [`AxisLaw`] on a joint of the tree: the law's angle (a prismatic joint's displacement) is
/// `offset + sign q` and its
/// rate `sign q̇`, and it adds `sign τ` to the joint's generalized force. `sign` is −1 where the
/// law measures the joint's parent turning relative to its child.
#[derive(Debug, Clone)]
pub struct JointAxisLaw {
    /// The law's angle on the tree: its joint, sign, and its angle at the tree's zero
    /// configuration (rad).
    pub coordinate: TreeCoordinate,
    /// The law.
    pub law: AxisLaw,
}

impl JointAxisLaw {
    /// The deflection `θ − θ₀ − θ*(t)` and the rate at joint coordinates `q`, `q̇` (the angle is
    /// the coordinate: no turn is lost).
    fn state(&self, t: f64, q: &[f64], v: &[f64]) -> (f64, f64) {
        (self.deflection(t, q), self.coordinate.rate(v))
    }

    fn deflection(&self, t: f64, q: &[f64]) -> f64 {
        self.coordinate.value(q) - self.law.free(t)
    }
}

/// A joint's coordinate as a model reads it, on a joint of the tree: `offset + sign q` and its
/// rate `sign q̇` (a limit's or a friction element's). `sign` is −1 where the model measures the
/// joint's parent moving relative to its child (its two bodies listed the other way round).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeCoordinate {
    /// The joint (tree index).
    pub joint: usize,
    /// ±1.
    pub sign: f64,
    /// The model's coordinate at the tree's zero configuration (rad or m).
    pub offset: f64,
}

impl TreeCoordinate {
    /// The model's coordinate at joint coordinates `q`: `offset + sign q`.
    fn value(&self, q: &[f64]) -> f64 {
        self.offset + self.sign * q[self.joint]
    }

    /// Its rate at joint rates `q̇`.
    fn rate(&self, v: &[f64]) -> f64 {
        self.sign * v[self.joint]
    }

    /// Its row (`sign` on the joint's rate, no bias) into `row`.
    fn row_into(&self, row: &mut SlipRow) {
        row.clear();
        row.push(self.joint, self.sign);
    }
}

#[derive(Debug)]
struct Scratch {
    pass: Pass,
    frames: Vec<WorldFrame>,
    /// The reaction loads' pass ([`MultibodySystem::reaction_loads`]) and the coordinates its
    /// transforms are at (NaN before the first): the responses at a state reuse the transforms
    /// of its evaluation.
    loads: Pass,
    loads_q: Vec<f64>,
}

const ANGLE: &[&str] = &["angle"];
const RATE: &[&str] = &["rate"];
const DISPLACEMENT: &[&str] = &["displacement"];
const SPEED: &[&str] = &["speed"];

impl JointSpace {
    /// The seam's view of `tree`.
    pub fn new(tree: KinematicTree) -> Self {
        let layout = Layout::new(tree.bodies().iter().map(|b| match b.kind {
            JointKind::Revolute => (b.name.as_str(), ANGLE, RATE),
            JointKind::Prismatic => (b.name.as_str(), DISPLACEMENT, SPEED),
        }));
        let pattern = ConstraintPattern::from_segments(0, &layout, []);
        let n = tree.len();
        let frame = WorldFrame {
            rotation: super::algebra::M3::identity(),
            origin: super::algebra::V3::zeros(),
            velocity: super::algebra::Sv::ZERO,
        };
        JointSpace {
            scratch: Mutex::new(Scratch {
                pass: Pass::new(n),
                frames: vec![frame; n],
                loads: Pass::new(n),
                loads_q: vec![f64::NAN; n],
            }),
            tree,
            layout,
            pattern,
            limits: Vec::new(),
            limited: Vec::new(),
            laws: Vec::new(),
            frictions: Vec::new(),
            friction_joints: Vec::new(),
        }
    }

    /// The system with laws about or along some of its joints' axes (a model's joint torques,
    /// rotational springs and servos; on a prismatic joint the law's angle is its displacement
    /// and its torque a force). An error names a law whose joint the tree does not have, or whose
    /// sign is not ±1.
    pub fn with_axis_laws(mut self, laws: Vec<JointAxisLaw>) -> Result<Self, ModelError> {
        for l in &laws {
            if !self.holds(&l.coordinate) {
                return Err(ModelError::InvalidParameter {
                    element: format!("axis law on joint {}", l.coordinate.joint),
                    what: "needs a joint of the tree, a sign of ±1 and a finite offset".into(),
                });
            }
        }
        self.laws = laws;
        Ok(self)
    }

    /// The system with limits on some of its joints (`docs/limits.md`): limit `k` reads the
    /// coordinate `joints[k]` (the model's joint value at the tree's zero configuration, and its
    /// sign on the tree's coordinate). The joint coordinate is continuous, so a revolute joint's
    /// limit is not read within a turn. An error names a limit whose joint the tree does not
    /// have.
    pub fn with_limits(mut self, mut limits: Vec<JointLimit>, joints: Vec<TreeCoordinate>) -> Result<Self, ModelError> {
        if let Some((l, _)) = limits.iter().zip(&joints).find(|(_, c)| !self.holds(c)) {
            return Err(ModelError::InvalidParameter {
                element: format!("{} '{}'", l.element, l.name),
                what: "its joint is not in the tree (or its sign is not ±1)".into(),
            });
        }
        if limits.len() != joints.len() {
            return Err(ModelError::InvalidParameter {
                element: "limits".into(),
                what: format!("{} limits for {} joints", limits.len(), joints.len()),
            });
        }
        limits.iter_mut().for_each(|l| l.within_turn = false);
        self.limits = limits;
        self.limited = joints;
        Ok(self)
    }

    /// The system with friction in some of its joints (`docs/friction.md`, "In joint
    /// coordinates"): element `k` is `frictions[k]` (its coefficient, viscous and constant parts,
    /// stick speed) on the coordinate `joints[k]`, whose rate is its slip rate. Its load is the
    /// force the joint transmits ([`MultibodySystem::reaction_loads`]): the whole force for a
    /// revolute joint (the pin's), the part across the axis for a prismatic one (the guide's),
    /// as in absolute coordinates. An error names an element whose joint the tree does not
    /// have, or one loaded by a contact (rigid contact is solved in absolute coordinates only).
    pub fn with_frictions(
        mut self,
        mut frictions: Vec<JointFriction>,
        joints: Vec<TreeCoordinate>,
    ) -> Result<Self, ModelError> {
        if frictions.len() != joints.len() {
            return Err(ModelError::InvalidParameter {
                element: "frictions".into(),
                what: format!("{} friction elements for {} joints", frictions.len(), joints.len()),
            });
        }
        for (f, c) in frictions.iter_mut().zip(&joints) {
            let bad = |what: &str| ModelError::InvalidParameter {
                element: format!("{} '{}'", f.element, f.name),
                what: what.into(),
            };
            if !self.holds(c) {
                return Err(bad("its joint is not in the tree (or its sign is not ±1)"));
            }
            if f.load_limit.is_some() {
                return Err(bad("its load is a contact's, solved in absolute coordinates only"));
            }
            f.load_rows = (3 * c.joint..3 * c.joint + 3).collect();
        }
        self.frictions = frictions;
        self.friction_joints = joints;
        Ok(self)
    }

    /// True when `c` is on a joint of the tree, with a sign of ±1 and a finite offset.
    fn holds(&self, c: &TreeCoordinate) -> bool {
        c.joint < self.tree.len() && c.sign.abs() == 1.0 && c.offset.is_finite()
    }

    /// The tree.
    pub fn tree(&self) -> &KinematicTree {
        &self.tree
    }

    fn scratch(&self) -> std::sync::MutexGuard<'_, Scratch> {
        // A panic while the lock was held leaves no broken invariant: the scratch is overwritten
        // before it is read.
        self.scratch.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl ConstraintSet for JointSpace {
    fn pattern(&self) -> &ConstraintPattern {
        &self.pattern
    }
    fn equation(&self, row: usize) -> EquationRef {
        // There are no equations: no row can be asked for.
        EquationRef {
            constraint: row,
            name: "none".into(),
            equation: 0,
            label: "none",
        }
    }
    fn values(&self) -> ConstraintValues {
        ConstraintValues::new(&self.pattern, 0)
    }
    fn evaluate(&self, _t: f64, _q: &[f64], _v: &[f64], _out: &mut ConstraintValues) {}
}

impl MultibodySystem for JointSpace {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    fn constraints(&self) -> &dyn ConstraintSet {
        self
    }

    fn mass_storage(&self) -> BlockDiagonal {
        BlockDiagonal::zeros([self.layout.n_v()])
    }

    fn mass(&self, q: &[f64], out: &mut BlockDiagonal) {
        let mut s = self.scratch();
        self.tree.mass_matrix(q, &mut s.pass, out.block_mut(0));
    }

    fn mass_is_constant(&self) -> bool {
        false
    }

    fn applied_forces(&self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        let mut s = self.scratch();
        self.tree.bias_forces(q, v, &mut s.pass, out);
        drop(s);
        self.add_joint_forces(t, q, v, out);
    }

    fn add_joint_forces(&self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        for l in &self.laws {
            let (deflection, rate) = l.state(t, q, v);
            out[l.coordinate.joint] += l.coordinate.sign * l.law.torque(t, deflection, rate).0;
        }
    }

    fn check_forces(&self, t: f64, _q: &[f64], _v: &[f64], q_e: &[f64]) -> Result<(), DynamicsError> {
        match q_e.iter().position(|x| !x.is_finite()) {
            None => Ok(()),
            Some(i) => Err(DynamicsError::NonFinite {
                time: t,
                what: format!("generalized force on joint of body '{}'", self.tree.bodies()[i].name),
            }),
        }
    }

    fn force_coupling(&self) -> Option<Vec<Vec<usize>>> {
        // In joint coordinates every body's force depends on its ancestors' and descendants'
        // coordinates: one group of all bodies.
        Some(vec![(0..self.tree.len()).collect()])
    }

    fn kinematic_tree(&self) -> Option<&KinematicTree> {
        Some(&self.tree)
    }

    fn limits(&self) -> &[JointLimit] {
        &self.limits
    }

    /// One per friction element, then one per limit (the switching formulation writes them,
    /// [`crate::Frictional`]).
    fn num_events(&self) -> usize {
        self.frictions.len() + self.limits.len()
    }

    fn frictions(&self) -> &[JointFriction] {
        &self.frictions
    }

    /// The joint's own rate as the model reads it: `±1` on its coordinate, with no bias.
    fn slip_row(&self, k: usize, _t: f64, _q: &[f64], _v: &[f64], row: &mut SlipRow) {
        match self.friction_joints.get(k) {
            Some(c) => c.row_into(row),
            None => row.clear(),
        }
    }

    /// Three per joint where some joint has friction (none otherwise): the force joint `i`
    /// transmits to its body's subtree ([`KinematicTree`]'s recursive Newton–Euler pass), in
    /// the body's axes, for a prismatic joint without its part along the axis; so its norm is
    /// the load of the joint's friction ([`JointSpace::with_frictions`]). The joint's own force
    /// along its axis (its friction, a torque law) is not in it: a revolute joint's is a moment,
    /// a prismatic joint's is taken out.
    fn num_reaction_loads(&self) -> usize {
        if self.frictions.is_empty() {
            0
        } else {
            3 * self.tree.len()
        }
    }

    fn reaction_loads(&self, _t: f64, q: &[f64], v: &[f64], qdd: &[f64], response: bool, out: &mut [f64]) {
        if out.len() != 3 * self.tree.len() {
            return;
        }
        let mut guard = self.scratch();
        let s = &mut *guard;
        let transforms = s.loads_q == q;
        self.tree
            .joint_wrenches((q, v, Some(qdd)), response, transforms, &mut s.loads);
        if !transforms {
            s.loads_q.copy_from_slice(q);
        }
        for (i, (load, link)) in out.chunks_exact_mut(3).zip(&self.tree.links).enumerate() {
            let mut f = s.loads.f[i].v;
            if link.kind == JointKind::Prismatic {
                f -= link.axis * link.axis.dot(&f);
            }
            load.copy_from_slice(f.as_slice());
        }
    }

    /// The joint's own coordinate as the model reads it: the row is `±1` on it, with no bias.
    fn limit_row(&self, k: usize, _t: f64, q: &[f64], _v: &[f64], row: &mut SlipRow) -> f64 {
        let Some(c) = self.limited.get(k) else {
            row.clear();
            return 0.0;
        };
        c.row_into(row);
        c.value(q)
    }

    fn kinetic_energy(&self, q: &[f64], v: &[f64]) -> f64 {
        let mut s = self.scratch();
        self.tree.velocities(q, v, &mut s.pass);
        self.tree.kinetic(&s.pass)
    }

    fn potential_energy(&self, t: f64, q: &[f64]) -> f64 {
        let mut s = self.scratch();
        self.tree.world_frames(q, None, &mut s.frames);
        let laws: f64 = self.laws.iter().map(|l| l.law.potential(l.deflection(t, q))).sum();
        self.tree.potential(q, &s.frames) + laws
    }

    /// As a model in absolute coordinates: not with friction, nor with limits (their impacts).
    fn is_conservative(&self) -> bool {
        self.tree.is_conservative()
            && self.laws.iter().all(|l| l.law.is_conservative())
            && self.frictions.is_empty()
            && self.limits.is_empty()
    }

    /// The joint dampers' `−c q̇²` (a joint's stiffness and constant effort are in its
    /// potential), and the power of the axis laws that their potential does not count.
    fn nonconservative_power(&self, t: f64, q: &[f64], v: &[f64], _scratch: &mut crate::PowerScratch) -> f64 {
        let laws: f64 = self
            .laws
            .iter()
            .map(|l| {
                let (deflection, rate) = l.state(t, q, v);
                l.law.nonconservative_power(t, deflection, rate)
            })
            .sum();
        self.tree.damping_power(v) + laws
    }

    fn bodies_without_inertia(&self) -> Vec<String> {
        self.tree
            .bodies()
            .iter()
            .filter(|b| b.mass == 0.0 && b.inertia.iter().flatten().all(|x| *x == 0.0))
            .map(|b| b.name.clone())
            .collect()
    }
}
