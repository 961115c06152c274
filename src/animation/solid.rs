//! What a spatial scene looks like: each body as a solid (its scene shape, or the box with its
//! mass and principal moments of inertia), the shapes the scene gives to draw it with (its
//! visuals: primitives and meshes), the points where its joints attach, and each joint's point and
//! axis. The 3D viewer (`viewer3d.js`) draws it at every frame from the bodies' poses.

use dalembert_spatial::Model;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::Serialize;

/// A body's solid, centred on its centre of mass, in its own axes (see [`SolidBody::rotation`]),
/// or a visual's shape in the visual's frame ([`Visual`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Solid {
    /// A box with these sides along its x, y, z axes (m).
    Box {
        /// Sides (m).
        size: [f64; 3],
    },
    /// A sphere.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// A cylinder along its z axis.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
    },
    /// A triangle mesh from a file (STL, OBJ or COLLADA), read only when a page is written
    /// ([`crate::animation::MeshSources`]).
    Mesh {
        /// The file as the scene names it: a path relative to the scene's folder, or
        /// `package://NAME/PATH`.
        file: String,
        /// Scale along the mesh's x, y, z (its file's units to metres).
        scale: [f64; 3],
    },
}

/// A shape a scene gives to draw a body with (a URDF `<visual>`, a TOML body's `visual`), in the
/// body's frame. A body with visuals is drawn with them instead of its box of inertia.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Visual {
    /// The shape, in the visual's frame.
    pub shape: Solid,
    /// The visual frame's origin in the body frame (m).
    pub position: [f64; 3],
    /// Its axes in the body frame (Euler parameters `[e0, e1, e2, e3]`).
    pub rotation: [f64; 4],
    /// Where the scene declares it (`ur5.urdf line 44`), for messages.
    pub declared: String,
}

/// One moving body as the 3D viewer draws it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolidBody {
    /// Name.
    pub name: String,
    /// The solid drawn.
    pub solid: Solid,
    /// The solid's axes in the body frame (Euler parameters `[e0, e1, e2, e3]`): the principal
    /// axes for an inertia box, the identity for a scene's shape.
    pub rotation: [f64; 4],
    /// True when the solid is the body's equivalent box of inertia (no shape was given).
    pub from_inertia: bool,
    /// Points of the body where its joints attach (body frame): the viewer draws bars to them
    /// from the centre of mass, so that a chain of links reads as one.
    pub points: Vec<[f64; 3]>,
    /// The shapes the scene gives to draw the body with (empty: its solid is drawn).
    pub visuals: Vec<Visual>,
}

/// One joint as the 3D viewer draws it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointMark {
    /// Name.
    pub name: String,
    /// Its kind (`revolute`, `spherical`, …).
    pub kind: &'static str,
    /// Its bodies (`None`: the ground).
    pub bodies: [Option<usize>; 2],
    /// The joint's point on each body (body frames; global for the ground).
    pub points: [[f64; 3]; 2],
    /// The joint axis on the first body (body frame).
    pub axis: [f64; 3],
}

/// Everything the 3D viewer draws of a spatial scene, apart from the motion itself.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SpatialDrawing {
    /// The moving bodies, in coordinate order.
    pub bodies: Vec<SolidBody>,
    /// The joints.
    pub joints: Vec<JointMark>,
    /// The ground's shapes (world frame; a robot's base).
    pub ground: Vec<Visual>,
    /// Gravity (the viewer's "up" is against it).
    pub gravity: [f64; 3],
    /// The contacts' names, rigid and compliant: each drawn as its force's arrow at the point
    /// where it acts (the columns `<name>.fx` … `<name>.pz`; its plane, if any, is a square of
    /// `ground`).
    pub contacts: Vec<String>,
}

/// The box with mass `m` and the principal moments `j` (ascending or not): sides
/// `a² = 6 (J_y + J_z − J_x) / m` and its cyclic permutations. A moment that no box has (a rod's
/// zero) gives a side of zero, which the viewer widens to be seen.
pub fn inertia_box(m: f64, j: [f64; 3]) -> [f64; 3] {
    let side = |a: f64, b: f64, c: f64| (6.0 * (b + c - a) / m).max(0.0).sqrt();
    if m.is_nan() || m <= 0.0 {
        return [0.0; 3];
    }
    [side(j[0], j[1], j[2]), side(j[1], j[2], j[0]), side(j[2], j[0], j[1])]
}

impl SpatialDrawing {
    /// The drawing of `model`, with the scene's shape of each body where it gives one
    /// (`shapes[i]`; `None` draws the body's box of inertia) and its visuals (`visuals[i]`).
    pub fn of(model: &Model, shapes: &[Option<Solid>], visuals: &[Vec<Visual>]) -> Self {
        let mut bodies: Vec<SolidBody> = model
            .bodies()
            .iter()
            .enumerate()
            .map(|(i, b)| match shapes.get(i).cloned().flatten() {
                Some(solid) => SolidBody {
                    name: b.name.clone(),
                    solid,
                    rotation: [1.0, 0.0, 0.0, 0.0],
                    from_inertia: false,
                    points: Vec::new(),
                    visuals: Vec::new(),
                },
                None => {
                    let (moments, axes) = principal(&b.inertia);
                    SolidBody {
                        name: b.name.clone(),
                        solid: Solid::Box {
                            size: inertia_box(b.mass, moments),
                        },
                        rotation: dalembert_spatial::euler_parameters::from_rotation(&axes),
                        from_inertia: true,
                        points: Vec::new(),
                        visuals: Vec::new(),
                    }
                }
            })
            .collect();
        for (body, v) in bodies.iter_mut().zip(visuals) {
            body.visuals.clone_from(v);
        }
        let joints: Vec<JointMark> = model
            .joint_geometry()
            .into_iter()
            .map(|g| JointMark {
                name: g.name,
                kind: g.kind.name(),
                bodies: [g.body_i, g.body_j],
                points: [g.point_i, g.point_j],
                axis: g.axis_i,
            })
            .collect();
        for j in &joints {
            for (b, p) in j.bodies.iter().zip(&j.points) {
                if let Some(body) = b.and_then(|b| bodies.get_mut(b)) {
                    if !body.points.contains(p) {
                        body.points.push(*p);
                    }
                }
            }
        }
        SpatialDrawing {
            bodies,
            joints,
            ground: Vec::new(),
            gravity: model.gravity().into(),
            // The rigid contacts (limits of the model) and the compliant ones (force elements).
            contacts: (model.limit_specs().iter())
                .filter(|l| l.element == "contact")
                .map(|l| l.name.clone())
                .chain(model.contact_names().map(String::from))
                .collect(),
        }
    }
}

/// Principal moments and axes (columns, a right-handed rotation) of an inertia tensor.
fn principal(j: &Matrix3<f64>) -> ([f64; 3], Matrix3<f64>) {
    let e = SymmetricEigen::new(*j);
    let mut axes = e.eigenvectors;
    if axes.determinant() < 0.0 {
        let flipped: Vector3<f64> = -axes.column(2);
        axes.set_column(2, &flipped);
    }
    (e.eigenvalues.into(), axes)
}

#[cfg(test)]
mod tests {
    use super::inertia_box;

    /// A 2 × 0.4 × 0.1 m box of 3 kg has moments m(b² + c²)/12, …; the box of those moments is
    /// that box (the inverse of the moments' formula).
    #[test]
    fn the_inertia_box_of_a_box_is_the_box() {
        let (m, [a, b, c]) = (3.0, [2.0, 0.4, 0.1]);
        let j = [
            m * (b * b + c * c) / 12.0,
            m * (a * a + c * c) / 12.0,
            m * (a * a + b * b) / 12.0,
        ];
        let size = inertia_box(m, j);
        for (s, e) in size.iter().zip([a, b, c]) {
            assert!((s - e).abs() < 1e-14, "{size:?}");
        }
        assert_eq!(inertia_box(0.0, j), [0.0; 3], "no mass, no box");
    }
}
