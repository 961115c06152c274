//! What a scene looks like: each body's shape and attachment points, the ground's pivots and guides,
//! pins, massless links and springs. Built by the scene loader from what the file states; the viewer
//! draws it at every frame from the bodies' poses.

use dalembert_kinematics::Vec2;
use serde::Serialize;

/// The visible outline of a body, in its own frame (reference point at the origin, local x along
/// the body's angle 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Shape {
    /// A bar of this length along the local x axis, centred on the reference point.
    Rod {
        /// Length (m).
        length: f64,
    },
    /// A disk of this radius centred on the reference point.
    Disk {
        /// Radius (m).
        radius: f64,
    },
    /// A rectangle centred on the reference point, sides along the local axes.
    Rectangle {
        /// Side along local x (m).
        width: f64,
        /// Side along local y (m).
        height: f64,
    },
    /// No shape given: the viewer draws bars from the reference point to the attachment points, a
    /// block for a slider, a dot for a point mass.
    Unspecified,
}

/// One moving body as the viewer draws it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BodyDrawing {
    /// Name (shown on hover-free labels and in errors).
    pub name: String,
    /// Outline.
    pub shape: Shape,
    /// Points of the body where joints and springs attach (body frame).
    pub points: Vec<[f64; 2]>,
    /// The second body of a prismatic joint: drawn as a block when it has no shape.
    pub slider: bool,
    /// No rotational inertia and no shape: drawn as a dot.
    pub point_mass: bool,
}

/// A body reference in a drawing: the index of a moving body, or `None` for the ground.
pub type DrawBody = Option<usize>;

/// Joints, guides and force elements drawn between bodies.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Mark {
    /// A pin (revolute joint) at the point of the second body; a ground pivot is drawn where either
    /// body is the ground.
    Pin {
        /// Joint name.
        name: String,
        /// The joint's bodies.
        bodies: [DrawBody; 2],
        /// The joint point in each body's frame (global for the ground).
        points: [[f64; 2]; 2],
    },
    /// A straight guide fixed in `body` (prismatic joint, point on a line), drawn over the travel
    /// of `follower`'s point along it.
    Guide {
        /// Joint name.
        name: String,
        /// The body carrying the guide.
        body: DrawBody,
        /// A point of the guide in that body's frame.
        point: [f64; 2],
        /// The guide's direction in that body's frame.
        direction: [f64; 2],
        /// The body that slides along it.
        follower: DrawBody,
        /// The sliding point in the follower's frame.
        follower_point: [f64; 2],
    },
    /// A massless link (distance joint): a thin line between two points.
    Link {
        /// Joint name.
        name: String,
        /// The two bodies.
        bodies: [DrawBody; 2],
        /// The end points in each body's frame.
        points: [[f64; 2]; 2],
    },
    /// A contact between two bodies' shapes (`docs/contact.md`, `docs/limits.md`), drawn with its
    /// shapes where a body's own outline does not show them (a line, a cam's profile, a roller)
    /// and, where the frames carry its normal force (CSV `<name>.normal`), an arrow of that force
    /// on the first body at the contact point.
    Contact {
        /// Element name.
        name: String,
        /// `circle-line`, `circle-circle`, `circle-profile` or `line-profile`.
        form: &'static str,
        /// The first shape's body (the circle's, or the face's for `line-profile`) and the other
        /// shape's (the line's, the other circle's, the profile's).
        bodies: [DrawBody; 2],
        /// The circle's centre or the face's point (first body's frame), and the line's point or
        /// the other circle's centre (second body's frame; unused for a profile).
        points: [[f64; 2]; 2],
        /// The circles' radii (0 where there is none).
        radii: [f64; 2],
        /// The line's unit normal (second body's frame, towards the circle) or the face's (first
        /// body's frame, towards the profile); zero otherwise.
        normal: [f64; 2],
        /// The profile's knots (second body's frame; empty without a profile).
        profile: Vec<[f64; 2]>,
        /// True when the frames carry its normal force (a rigid contact's `<name>.normal`).
        force: bool,
    },
    /// A spring–damper between two points, drawn as a zig-zag.
    Spring {
        /// Force element name.
        name: String,
        /// The two bodies.
        bodies: [DrawBody; 2],
        /// The attachment points in each body's frame.
        points: [[f64; 2]; 2],
    },
}

/// Everything the viewer draws of a scene, apart from the motion itself.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Drawing {
    /// The moving bodies, in coordinate order (planar scenes).
    pub bodies: Vec<BodyDrawing>,
    /// Joints, guides, links and springs (planar scenes).
    pub marks: Vec<Mark>,
    /// The compliant contacts' names (planar scenes): each drawn as its force's arrow at the
    /// point where it acts (the columns `<name>.fx`, `.fy`, `.px`, `.py`; `docs/contact.md`,
    /// "Output").
    pub contacts: Vec<String>,
    /// A spatial scene's solids and joints, drawn by the 3D viewer (`None` for a planar scene).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spatial: Option<super::SpatialDrawing>,
}

impl Drawing {
    /// Records that `body` carries an attachment point `p` (body frame); the ground records none.
    pub fn attach(&mut self, body: DrawBody, p: Vec2) {
        if let Some(b) = body.and_then(|i| self.bodies.get_mut(i)) {
            let p = [p.x, p.y];
            if !b.points.contains(&p) {
                b.points.push(p);
            }
        }
    }

    /// Adds a mark and records its attachment points on its bodies.
    pub fn add(&mut self, mark: Mark) {
        let ends: Vec<(DrawBody, [f64; 2])> = match &mark {
            Mark::Pin { bodies, points, .. }
            | Mark::Link { bodies, points, .. }
            | Mark::Spring { bodies, points, .. } => {
                vec![(bodies[0], points[0]), (bodies[1], points[1])]
            }
            Mark::Guide {
                follower,
                follower_point,
                ..
            } => vec![(*follower, *follower_point)],
            Mark::Contact { .. } => Vec::new(),
        };
        for (b, p) in ends {
            self.attach(b, Vec2::new(p[0], p[1]));
        }
        self.marks.push(mark);
    }

    /// Index of the body called `name`.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.body_names().iter().position(|b| *b == name)
    }

    /// The moving bodies' names, in coordinate order (planar or spatial).
    pub fn body_names(&self) -> Vec<&str> {
        match &self.spatial {
            Some(s) => s.bodies.iter().map(|b| b.name.as_str()).collect(),
            None => self.bodies.iter().map(|b| b.name.as_str()).collect(),
        }
    }

    /// The numbers of a body's pose in a frame: `x, y, angle` (planar) or `x, y, z, e0, e1, e2,
    /// e3` (spatial), named as the output's columns.
    pub fn pose_columns(&self) -> &'static [&'static str] {
        match self.spatial {
            Some(_) => &["x", "y", "z", "e0", "e1", "e2", "e3"],
            None => &["x", "y", "angle"],
        }
    }
}

/// `[x, y]` of a vector.
pub(crate) fn xy(v: Vec2) -> [f64; 2] {
    [v.x, v.y]
}
