//! URDF model files (`docs/import.md`): a reader that turns a robot description into the
//! elements of a spatial scene ([`crate::builder::ModelBuilder`]), which the one spatial scene
//! builder then makes a model of, as it does a TOML file's.
//!
//! - Each link that moves becomes a body named after the link. Its centre of mass and inertia
//!   come from `<inertial>` (origin with `rpy`, full tensor); its axes are the link's frame.
//! - A `fixed` joint merges its child into its parent: combined mass, centre of mass and inertia
//!   (parallel-axis theorem). The root link, and every link fixed to it, is the ground.
//! - `revolute` and `continuous` joints become revolute joints and `prismatic` joints prismatic
//!   ones, at the joint frame's origin along its `axis` (any direction, joint frame); a
//!   `floating` joint leaves its child free.
//! - `<dynamics damping>` becomes a damper on the joint: a rotational spring–damper of zero
//!   stiffness (revolute) or a spring–damper of zero stiffness along the axis (prismatic);
//!   `<dynamics friction>` the joint's constant friction (`friction = { constant }`,
//!   `docs/friction.md`).
//! - The model loads at rest with every joint at 0 (the file's configuration) under gravity
//!   `(0, 0, −9.81)`.
//!
//! - A `<mimic>` joint's value is `multiplier` times its leader's plus `offset`: a coupling
//!   named `<joint>-mimic` (`docs/couplings.md`), its effort the torque or force it takes.
//!
//! What the reader cannot model yet is refused in one line naming the element and its line: a
//! `planar` joint. `<visual>`
//! geometries (box, cylinder, sphere, mesh) are kept for the 3D viewer only; `<collision>` is
//! skipped (nothing collides yet), as are the elements that carry no dynamics (`material`,
//! `gazebo`, `transmission`, `ros2_control`).

use super::tree::{scene_of, Inertial, Kind, Link, LinkVisual, Pose, Read, Shape, Skipped, Tree, TreeJoint, V3};
use super::xml::{self, Source};
use super::{Scene, SceneError};
use crate::builder::coupling;
use nalgebra::{Matrix3, Rotation3};
use roxmltree::Node;
use std::collections::HashMap;

/// `<origin xyz rpy>` (absent: the identity): `rpy` are fixed-axis rotations about x, then y,
/// then z, `R = R_z(yaw) R_y(pitch) R_x(roll)`.
fn origin(src: &Source<'_>, parent: Node<'_, '_>) -> Result<Pose, SceneError> {
    let Some(o) = src.child(parent, "origin")? else {
        return Ok(Pose::IDENTITY);
    };
    let [roll, pitch, yaw] = src.vector(o, "rpy", [0.0; 3])?.into();
    Ok(Pose {
        p: src.vector(o, "xyz", [0.0; 3])?,
        r: *Rotation3::from_euler_angles(roll, pitch, yaw).matrix(),
    })
}

fn inertial(src: &Source<'_>, link: Node<'_, '_>) -> Result<Option<Inertial>, SceneError> {
    let Some(node) = src.child(link, "inertial")? else {
        return Ok(None);
    };
    src.only(node, &["origin", "mass", "inertia"], &[])?;
    let frame = origin(src, node)?;
    let m = src
        .child(node, "mass")?
        .ok_or_else(|| src.err(node, format!("{} needs <mass value=\"…\"/>", Source::describe(link))))?;
    let mass = src.number(m, "value", None)?;
    if mass < 0.0 {
        return Err(src.err(m, format!("{}: mass {mass} is negative", Source::describe(link))));
    }
    let i = src.child(node, "inertia")?.ok_or_else(|| {
        src.err(
            node,
            format!("{} needs <inertia ixx ixy ixz iyy iyz izz/>", Source::describe(link)),
        )
    })?;
    let c = |k: &str| src.number(i, k, None);
    let (xx, xy, xz, yy, yz, zz) = (c("ixx")?, c("ixy")?, c("ixz")?, c("iyy")?, c("iyz")?, c("izz")?);
    Ok(Some(Inertial {
        frame,
        mass,
        tensor: Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
    }))
}

/// A link's `<visual>` elements. A relative mesh path is made relative to the scene's folder by
/// `prefix` (the robot file's folder from it); `package://` and absolute paths are kept, for the
/// viewer to resolve or refuse (`animation::MeshSources`). A geometry this reader does not draw is
/// counted in `skipped`.
fn visuals(
    src: &Source<'_>,
    link: Node<'_, '_>,
    prefix: &str,
    skipped: &mut Skipped,
) -> Result<Vec<LinkVisual>, SceneError> {
    let mut out = Vec::new();
    for node in link.children().filter(|c| c.has_tag_name("visual")) {
        skipped.note(node, &["origin", "geometry"], &["material"]);
        let Some(geometry) = src.child(node, "geometry")? else {
            return Err(src.err(
                node,
                format!("{}: a <visual> needs a <geometry>", Source::describe(link)),
            ));
        };
        skipped.note(geometry, &["box", "cylinder", "sphere", "mesh"], &[]);
        let Some(g) = geometry
            .children()
            .find(|c| c.is_element() && ["box", "cylinder", "sphere", "mesh"].contains(&c.tag_name().name()))
        else {
            continue;
        };
        let positive = |key: &str| -> Result<f64, SceneError> {
            let v = src.number(g, key, None)?;
            if v > 0.0 {
                Ok(v)
            } else {
                Err(src.err(
                    g,
                    format!(
                        "{}: <{}> {key} {v} is not positive",
                        Source::describe(link),
                        g.tag_name().name()
                    ),
                ))
            }
        };
        let shape = match g.tag_name().name() {
            "box" => {
                let size = src.vector(g, "size", [f64::NAN; 3])?;
                if !size.iter().all(|&s| s > 0.0) {
                    return Err(src.err(
                        g,
                        format!(
                            "{}: <box> needs size=\"a b c\", three positive sides",
                            Source::describe(link)
                        ),
                    ));
                }
                Shape::Box(size.into())
            }
            "sphere" => Shape::Sphere(positive("radius")?),
            "cylinder" => Shape::Cylinder(positive("radius")?, positive("length")?),
            _ => {
                let file = src.required(g, "filename")?;
                let scale = src.vector(g, "scale", [1.0; 3])?;
                if scale.iter().any(|&s| s == 0.0) {
                    return Err(src.err(g, format!("{}: <mesh> scale has a zero", Source::describe(link))));
                }
                let relative = !(file.contains("://") || std::path::Path::new(file).is_absolute());
                let file = if relative && !prefix.is_empty() {
                    format!("{prefix}/{file}")
                } else {
                    file.to_string()
                };
                Shape::Mesh(file, scale.into())
            }
        };
        let line = super::error::line_col(src.text, node.range().start).0;
        out.push(LinkVisual {
            pose: origin(src, node)?,
            shape,
            declared: format!("{} line {line}", src.origin),
        });
    }
    Ok(out)
}

fn joint_kind(src: &Source<'_>, node: Node<'_, '_>) -> Result<Kind, SceneError> {
    let kind = src.required(node, "type")?;
    Ok(match kind {
        "revolute" | "continuous" => Kind::Revolute,
        "prismatic" => Kind::Prismatic,
        "fixed" => Kind::Fixed,
        "floating" => Kind::Floating,
        "planar" => {
            return Err(src.err(
                node,
                format!("{}: planar joints are not supported yet", Source::describe(node)),
            ))
        }
        other => {
            return Err(src.err(
                node,
                format!(
                    "{}: unknown joint type '{other}' (expected revolute, continuous, prismatic, fixed, floating)",
                    Source::describe(node)
                ),
            ))
        }
    })
}

/// The elements of the robot in `text`, and where each link and joint is in it (for errors the
/// scene builder finds).
fn read<'a>(
    src: &Source<'a>,
    doc: &'a roxmltree::Document<'a>,
    prefix: &str,
    floating: bool,
) -> Result<Read<'a>, SceneError> {
    let robot = doc.root_element();
    if robot.tag_name().name() != "robot" {
        return Err(src.err(
            robot,
            format!(
                "the root element is <{}>; a URDF file's is <robot>",
                robot.tag_name().name()
            ),
        ));
    }
    let stem = std::path::Path::new(src.origin).file_stem().and_then(|s| s.to_str());
    let name = robot.attribute("name").or(stem).unwrap_or("robot");
    let mut skipped = Skipped::default();
    skipped.note(
        robot,
        &["link", "joint"],
        &["material", "gazebo", "transmission", "ros2_control"],
    );
    let mut places: HashMap<String, Node<'a, 'a>> = HashMap::new();
    let mut links: Vec<Link<'a, 'a>> = Vec::new();
    let mut link_index: HashMap<&str, usize> = HashMap::new();
    for node in robot.children().filter(|c| c.has_tag_name("link")) {
        let link = src.required(node, "name")?;
        if link_index.insert(link, links.len()).is_some() {
            return Err(src.err(node, format!("a second link named '{link}'")));
        }
        skipped.note(node, &["inertial", "visual", "collision"], &[]);
        links.push(Link {
            name: link.to_string(),
            node,
            inertial: inertial(src, node)?,
            visuals: visuals(src, node, prefix, &mut skipped)?,
        });
        places.insert(link.to_string(), node);
    }
    let mut joints: Vec<TreeJoint> = Vec::new();
    let mut notes = Vec::new();
    // (follower, leader as the file names it, multiplier, offset, the <mimic> element)
    let mut mimics = Vec::new();
    let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
    for node in robot.children().filter(|c| c.has_tag_name("joint")) {
        let file_name = src.required(node, "name")?;
        let here = Source::describe(node);
        if joints.iter().any(|j| j.file_name == file_name) {
            return Err(src.err(node, format!("a second joint named '{file_name}'")));
        }
        // Links and joints have names of their own in a URDF; in a scene they share one.
        let joint_name = if link_index.contains_key(file_name) {
            let renamed = format!("{file_name}-joint");
            notes.push(format!(
                "joint '{file_name}' is named like a link: it is '{renamed}' in the scene and its columns"
            ));
            renamed
        } else {
            file_name.to_string()
        };
        skipped.note(
            node,
            &["parent", "child", "origin", "axis", "limit", "dynamics", "mimic"],
            &["calibration", "safety_controller"],
        );
        let kind = joint_kind(src, node)?;
        if let Some(m) = src.child(node, "mimic")? {
            if !matches!(kind, Kind::Revolute | Kind::Prismatic) {
                return Err(src.err(
                    m,
                    format!("{here}: <mimic> is for revolute, continuous and prismatic joints"),
                ));
            }
            let leader = src.required(m, "joint")?.to_string();
            let multiplier = src.number(m, "multiplier", Some(1.0))?;
            let offset = src.number(m, "offset", Some(0.0))?;
            mimics.push((joint_name.clone(), leader, multiplier, offset, m));
        }
        let link_of = |tag: &str| -> Result<usize, SceneError> {
            let e = src
                .child(node, tag)?
                .ok_or_else(|| src.err(node, format!("{here} needs <{tag} link=\"…\"/>")))?;
            let l = src.required(e, "link")?;
            link_index.get(l).copied().ok_or_else(|| {
                src.err(
                    e,
                    format!("{here}: <{tag}> names link '{l}', which the file does not have"),
                )
            })
        };
        let (parent, child) = (link_of("parent")?, link_of("child")?);
        if parent == child {
            return Err(src.err(node, format!("{here} joins link '{}' to itself", links[child].name)));
        }
        if let Some(j) = parent_joint[child] {
            return Err(src.err(
                node,
                format!(
                    "{here}: link '{}' already hangs from joint '{}' (a URDF is a tree: one parent joint per link)",
                    links[child].name, joints[j].name
                ),
            ));
        }
        let axis = match src.child(node, "axis")? {
            Some(a) => src.vector(a, "xyz", [1.0, 0.0, 0.0])?,
            None => V3::x(),
        };
        if axis.norm() < 1e-12 && matches!(kind, Kind::Revolute | Kind::Prismatic) {
            return Err(src.err(node, format!("{here}: its axis is zero")));
        }
        let mut limits = None;
        if let Some(l) = src.child(node, "limit")? {
            let (lo, hi) = (src.number(l, "lower", Some(0.0))?, src.number(l, "upper", Some(0.0))?);
            if lo > hi {
                return Err(src.err(l, format!("{here}: limit lower {lo} is above upper {hi}")));
            }
            // A continuous joint has none; a revolute or prismatic joint's are its stops.
            if matches!(src.required(node, "type")?, "revolute" | "prismatic") {
                match super::tree::stops(&joint_name, lo, hi) {
                    Ok(bounds) => limits = Some(bounds),
                    Err(note) => notes.push(note),
                }
            }
        }
        let (mut damping, mut friction) = (0.0, 0.0);
        if let Some(d) = src.child(node, "dynamics")? {
            damping = src.number(d, "damping", Some(0.0))?;
            friction = src.number(d, "friction", Some(0.0))?;
            if damping < 0.0 {
                return Err(src.err(d, format!("{here}: damping {damping} is negative")));
            }
            if friction.is_nan() || friction < 0.0 {
                return Err(src.err(d, format!("{here}: friction {friction} is negative")));
            }
            if friction > 0.0 && !matches!(kind, Kind::Revolute | Kind::Prismatic) {
                // A fixed or floating joint's <dynamics friction> has no motion to resist.
                friction = 0.0;
            }
        }
        parent_joint[child] = Some(joints.len());
        places.insert(joint_name.clone(), node);
        joints.push(TreeJoint {
            file_name: file_name.to_string(),
            name: joint_name,
            kind,
            parent,
            child,
            origin: origin(src, node)?,
            axis: axis.normalize(),
            damping,
            stiffness: 0.0,
            spring_rest: 0.0,
            friction,
            limits,
        });
    }
    let tree = Tree::of(src, robot, &links, &joints, &parent_joint, floating)?;
    if tree.principal.is_empty() {
        return Err(src.err(
            robot,
            "nothing moves: every link is fixed to the root link, which is fixed to the ground",
        ));
    }
    // A mimic joint's value is the multiplier times its leader's plus the offset: a coupling
    // (`docs/couplings.md`), named after the follower. The leader's stops hold both: the
    // follower's own would hold the same motion twice, and their forces would not be determined.
    let mut couplings = Vec::with_capacity(mimics.len());
    for (follower, leader, multiplier, offset, m) in mimics {
        let l = joints.iter().find(|j| j.file_name == leader).ok_or_else(|| {
            src.err(
                m,
                format!("joint '{follower}': <mimic joint=\"{leader}\"> names a joint the file does not have"),
            )
        })?;
        if !matches!(l.kind, Kind::Revolute | Kind::Prismatic) {
            return Err(src.err(
                m,
                format!("joint '{follower}': <mimic> follows joint '{leader}', which does not move on its own axis"),
            ));
        }
        let name = format!("{follower}-mimic");
        let leader_name = l.name.clone();
        places.insert(name.clone(), m);
        couplings.push(
            coupling(&name, &leader_name, &follower)
                .set("multiplier", multiplier)
                .set("offset", offset),
        );
        if let Some(f) = joints.iter_mut().find(|j| j.name == follower) {
            if f.limits.take().is_some() {
                notes.push(format!(
                    "joint '{follower}' follows joint '{leader_name}' (<mimic>): its limits are left out, the leader's hold both"
                ));
            }
        }
    }
    notes.extend(skipped.lines());
    let mut model = tree.elements(src, name, &links, &joints, "link")?;
    for c in couplings {
        model = model.coupling(c);
    }
    Ok((model, places, notes))
}

/// The scene a URDF file describes (see the module documentation); `origin` names the file in
/// errors, which name the element and its line.
pub(crate) fn scene(text: &str, origin: &str) -> Result<Scene, SceneError> {
    with_scene(text, origin, None, "", false)
}

/// `prefix`: the robot file's folder from the scene's (empty when the robot file is the scene);
/// `floating`: the root link moves freely instead of being fixed to the ground.
fn with_scene(
    text: &str,
    origin: &str,
    around: Option<(toml::Table, &str, &str)>,
    prefix: &str,
    floating: bool,
) -> Result<Scene, SceneError> {
    let doc = xml::parse(text, origin)?;
    let src = Source { text, origin };
    let read = read(&src, &doc, prefix, floating)?;
    scene_of(&src, read, around)
}

/// The `[scene] urdf = "PATH"` of a TOML scene's tables, if it has one.
pub(crate) fn reference(tables: &toml::Table) -> Option<&toml::Value> {
    tables.get("scene")?.get("urdf")
}

/// The scene of a TOML file whose `[scene] urdf` names a robot (`docs/import.md`, "A scene around
/// a robot"). The path is relative to the scene's folder (`origin`'s) and may not leave it.
pub(crate) fn around(tables: toml::Table, text: &str, origin: &str) -> Result<Scene, SceneError> {
    let at = |m: String| {
        // The key at the start of its line (the word may also be in a comment before it).
        let key = text.match_indices("urdf").map(|(a, _)| a);
        let mut keys = key.filter(|&a| text[..a].rsplit('\n').next().is_some_and(|l| l.trim().is_empty()));
        let span = keys.next().map(|a| a..a);
        SceneError::at(origin, text, span, m)
    };
    let Some(toml::Value::String(relative)) = reference(&tables) else {
        return Err(at("[scene] urdf is the path of a URDF file, a string".into()));
    };
    // Every key the scene adds is checked here, placed in its own text.
    toml::from_str::<super::spatial::AroundFile>(text).map_err(|e| SceneError::parse(origin, text, &e))?;
    let path = std::path::Path::new(relative);
    let inside = path
        .components()
        .all(|c| matches!(c, std::path::Component::Normal(_) | std::path::Component::CurDir));
    if !inside {
        return Err(at(format!(
            "[scene] urdf = \"{relative}\": give a path inside the scene's folder (no absolute path, no '..')"
        )));
    }
    let folder = std::path::Path::new(origin)
        .parent()
        .unwrap_or(std::path::Path::new(""));
    let file = folder.join(path);
    let shown = file.display().to_string();
    let cannot = |e: std::io::Error| at(format!("[scene] urdf = \"{relative}\": cannot read: {e}"));
    let size = std::fs::metadata(&file).map_err(cannot)?.len();
    if size > xml::MAX_BYTES as u64 {
        return Err(at(format!(
            "[scene] urdf = \"{relative}\": {size} bytes is more than a model file may hold ({})",
            xml::MAX_BYTES
        )));
    }
    let urdf = std::fs::read_to_string(&file).map_err(cannot)?;
    let prefix = path
        .parent()
        .map(|p| p.to_string_lossy().replace('\\', "/"))
        .unwrap_or_default();
    let floating = matches!(
        tables.get("scene").and_then(|s| s.get("floating_base")),
        Some(toml::Value::Boolean(true))
    );
    with_scene(&urdf, &shown, Some((tables, text, origin)), &prefix, floating)
}
