//! What a viewer needs to draw a spatial model's joints: where each joint sits on its bodies and
//! which way its axis points, in body frames (the model keeps them as markers built from the
//! initial configuration, `joints/mod.rs`).

use crate::joints::JointKind;
use crate::Model;

/// One joint's placement on its two bodies (body frames; global for the ground).
#[derive(Debug, Clone, PartialEq)]
pub struct JointGeometry {
    /// The joint's name.
    pub name: String,
    /// Its kind.
    pub kind: JointKind,
    /// The index of its first body (`None`: the ground).
    pub body_i: Option<usize>,
    /// The index of its second body (`None`: the ground).
    pub body_j: Option<usize>,
    /// The joint's point on body `i` (body frame).
    pub point_i: [f64; 3],
    /// The joint's point on body `j` (body frame; for a distance joint, its other end).
    pub point_j: [f64; 3],
    /// The joint axis on body `i` (body frame, unit): hinge or sliding axis, line, plane normal.
    pub axis_i: [f64; 3],
}

impl Model {
    /// Every joint's placement on its bodies, in the model's joint order.
    pub fn joint_geometry(&self) -> Vec<JointGeometry> {
        self.joints()
            .iter()
            .filter_map(|j| {
                Some(JointGeometry {
                    name: j.name.clone(),
                    kind: j.kind?,
                    body_i: j.body_i,
                    body_j: j.body_j,
                    point_i: j.point_i.into(),
                    point_j: j.point_j.into(),
                    axis_i: j.axes_i.column(2).into(),
                })
            })
            .collect()
    }
}
