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
//!   stiffness (revolute) or a spring–damper of zero stiffness along the axis (prismatic).
//! - The model loads at rest with every joint at 0 (the file's configuration) under gravity
//!   `(0, 0, −9.81)`.
//!
//! What the reader cannot model yet is refused in one line naming the element and its line: a
//! `mimic` coupling, a `planar` joint, joint friction. `<visual>` and `<collision>` are skipped
//! (no shapes are drawn or collided yet), as are the elements that carry no dynamics
//! (`material`, `gazebo`, `transmission`, `ros2_control`).

use super::xml::{self, Source};
use super::{Scene, SceneError};
use crate::builder::{body, force, joint, KeyValue, ModelBuilder};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use roxmltree::Node;
use std::collections::HashMap;

type V3 = Vector3<f64>;

/// A rigid transform: `x ↦ r x + p`.
#[derive(Debug, Clone, Copy)]
struct Pose {
    p: V3,
    r: Matrix3<f64>,
}

impl Pose {
    const IDENTITY: Pose = Pose {
        p: Vector3::new(0.0, 0.0, 0.0),
        r: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    };

    /// `self ∘ other`: `other` given in `self`'s frame.
    fn then(&self, other: &Pose) -> Pose {
        Pose {
            p: self.p + self.r * other.p,
            r: self.r * other.r,
        }
    }
}

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

/// A link's `<inertial>`: frame, mass and tensor (about the centre of mass, inertial axes).
#[derive(Debug, Clone, Copy)]
struct Inertial {
    frame: Pose,
    mass: f64,
    tensor: Matrix3<f64>,
}

#[derive(Debug)]
struct Link<'a, 'i> {
    name: &'a str,
    node: Node<'a, 'i>,
    inertial: Option<Inertial>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Revolute,
    Prismatic,
    Fixed,
    Floating,
}

#[derive(Debug)]
struct UrdfJoint<'a> {
    /// The name in the file.
    file_name: &'a str,
    /// The name in the scene (the file's, unless a link has it).
    name: String,
    kind: Kind,
    parent: usize,
    child: usize,
    origin: Pose,
    axis: V3,
    damping: f64,
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

/// What [`read`] gives: the robot's scene elements, where each link and joint is in the file (for
/// errors the scene builder finds), and the notes on what the reader left out.
type Read<'a> = (ModelBuilder, HashMap<String, Node<'a, 'a>>, Vec<String>);

/// The elements of the robot in `text`, and where each link and joint is in it (for errors the
/// scene builder finds).
fn read<'a>(src: &Source<'a>, doc: &'a roxmltree::Document<'a>) -> Result<Read<'a>, SceneError> {
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
            name: link,
            node,
            inertial: inertial(src, node)?,
        });
        places.insert(link.to_string(), node);
    }
    let mut joints: Vec<UrdfJoint<'a>> = Vec::new();
    let mut notes = Vec::new();
    let mut with_friction = Vec::new();
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
            return Err(src.err(m, format!("{here}: <mimic> couplings are not supported yet")));
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
        if let Some(l) = src.child(node, "limit")? {
            let (lo, hi) = (src.number(l, "lower", Some(0.0))?, src.number(l, "upper", Some(0.0))?);
            if lo > hi {
                return Err(src.err(l, format!("{here}: limit lower {lo} is above upper {hi}")));
            }
        }
        let mut damping = 0.0;
        if let Some(d) = src.child(node, "dynamics")? {
            damping = src.number(d, "damping", Some(0.0))?;
            let friction = src.number(d, "friction", Some(0.0))?;
            if damping < 0.0 {
                return Err(src.err(d, format!("{here}: damping {damping} is negative")));
            }
            if friction != 0.0 {
                with_friction.push(joint_name.clone());
            }
        }
        parent_joint[child] = Some(joints.len());
        places.insert(joint_name.clone(), node);
        joints.push(UrdfJoint {
            file_name,
            name: joint_name,
            kind,
            parent,
            child,
            origin: origin(src, node)?,
            axis: axis.normalize(),
            damping,
        });
    }
    let tree = Tree::of(src, robot, &links, &joints, &parent_joint)?;
    if tree.principal.is_empty() {
        return Err(src.err(
            robot,
            "nothing moves: every link is fixed to the root link, which is fixed to the ground",
        ));
    }
    if !with_friction.is_empty() {
        notes.push(format!(
            "joint friction is not modelled yet; the model leaves out that of {}",
            quoted(&with_friction)
        ));
    }
    notes.extend(skipped.lines());
    Ok((tree.elements(src, name, &links, &joints)?, places, notes))
}

/// `'a', 'b' and 'c'`.
fn quoted(names: &[String]) -> String {
    let q: Vec<String> = names.iter().map(|n| format!("'{n}'")).collect();
    match q.as_slice() {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// The elements a URDF reader passes over without reading: extensions the format allows
/// (`<sensor>`, `<contact>`, …), counted by tag and parent, for one note each.
#[derive(Default)]
struct Skipped(Vec<(String, usize)>);

impl Skipped {
    /// Counts the children of `node` not in `known`, except the `quiet` ones (documented as
    /// carrying no dynamics).
    fn note(&mut self, node: Node<'_, '_>, known: &[&str], quiet: &[&str]) {
        for c in node.children().filter(Node::is_element) {
            let tag = c.tag_name().name();
            if known.contains(&tag) || quiet.contains(&tag) {
                continue;
            }
            let what = format!("<{tag}> in <{}>", node.tag_name().name());
            match self.0.iter_mut().find(|(w, _)| *w == what) {
                Some((_, n)) => *n += 1,
                None => self.0.push((what, 1)),
            }
        }
    }

    fn lines(&self) -> impl Iterator<Item = String> + '_ {
        self.0.iter().map(|(what, n)| {
            let times = if *n == 1 {
                String::new()
            } else {
                format!(" ({n} of them)")
            };
            format!("skipped {what}{times}: not an element of the dynamics this reader reads")
        })
    }
}

/// The links' placement in the file's configuration and the body each belongs to.
struct Tree {
    /// Each link's frame (world).
    world: Vec<Pose>,
    /// Each link's body: `None` for the ground (the root and the links fixed to it).
    body: Vec<Option<usize>>,
    /// Each body's principal link (the child of the joint that moves it).
    principal: Vec<usize>,
    /// The joints in the order the tree was walked (parents before children).
    order: Vec<usize>,
}

impl Tree {
    fn of(
        src: &Source<'_>,
        robot: Node<'_, '_>,
        links: &[Link<'_, '_>],
        joints: &[UrdfJoint<'_>],
        parent_joint: &[Option<usize>],
    ) -> Result<Tree, SceneError> {
        let roots: Vec<usize> = (0..links.len()).filter(|&l| parent_joint[l].is_none()).collect();
        let root = match roots.as_slice() {
            [r] => *r,
            [] if links.is_empty() => return Err(src.err(robot, "the robot has no links")),
            [] => {
                return Err(src.err(
                    robot,
                    "every link hangs from a joint: the joints form a loop (a URDF is a tree)",
                ))
            }
            [a, b, ..] => {
                return Err(src.err(
                    links[*b].node,
                    format!(
                        "links '{}' and '{}' both have no parent joint: a URDF is one tree with one root",
                        links[*a].name, links[*b].name
                    ),
                ))
            }
        };
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
        for (k, j) in joints.iter().enumerate() {
            children[j.parent].push(k);
        }
        let mut tree = Tree {
            world: vec![Pose::IDENTITY; links.len()],
            body: vec![None; links.len()],
            principal: Vec::new(),
            order: Vec::new(),
        };
        let mut reached = vec![false; links.len()];
        reached[root] = true;
        let mut queue = std::collections::VecDeque::from([root]);
        while let Some(l) = queue.pop_front() {
            for &k in &children[l] {
                let j = &joints[k];
                tree.world[j.child] = tree.world[l].then(&j.origin);
                tree.body[j.child] = if j.kind == Kind::Fixed {
                    tree.body[l]
                } else {
                    tree.principal.push(j.child);
                    Some(tree.principal.len() - 1)
                };
                tree.order.push(k);
                reached[j.child] = true;
                queue.push_back(j.child);
            }
        }
        if let Some(l) = (0..links.len()).find(|&l| !reached[l]) {
            return Err(src.err(
                links[l].node,
                format!(
                    "link '{}' is on a loop of joints, not reached from the root link '{}' (a URDF is a tree)",
                    links[l].name, links[root].name
                ),
            ));
        }
        Ok(tree)
    }

    /// Mass, centre of mass (world) and inertia about it (world axes) of body `b`'s links.
    fn mass_properties(&self, links: &[Link<'_, '_>], b: usize) -> (f64, V3, Matrix3<f64>) {
        let parts: Vec<(f64, V3, Matrix3<f64>)> = (0..links.len())
            .filter(|&l| self.body[l] == Some(b))
            .filter_map(|l| {
                let i = links[l].inertial?;
                let frame = self.world[l].then(&i.frame);
                Some((i.mass, frame.p, frame.r * i.tensor * frame.r.transpose()))
            })
            .collect();
        let mass: f64 = parts.iter().map(|p| p.0).sum();
        if mass <= 0.0 {
            return (0.0, V3::zeros(), Matrix3::zeros());
        }
        let center = parts.iter().fold(V3::zeros(), |s, (m, c, _)| s + *m * c) / mass;
        let tensor = parts.iter().fold(Matrix3::zeros(), |s, (m, c, j)| {
            let d = c - center;
            s + j + *m * (Matrix3::identity() * d.norm_squared() - d * d.transpose())
        });
        (mass, center, tensor)
    }

    fn elements(
        &self,
        src: &Source<'_>,
        name: &str,
        links: &[Link<'_, '_>],
        joints: &[UrdfJoint<'_>],
    ) -> Result<ModelBuilder, SceneError> {
        let mut model = ModelBuilder::spatial(name).gravity([0.0, 0.0, -9.81]);
        let body_name = |b: Option<usize>| b.map_or("ground", |b| links[self.principal[b]].name);
        for (b, &l) in self.principal.iter().enumerate() {
            let link = &links[l];
            if link.name == "ground" {
                return Err(src.err(
                    link.node,
                    "link 'ground' moves, but 'ground' names the fixed frame in a scene: rename the link",
                ));
            }
            let (mass, center, tensor) = self.mass_properties(links, b);
            if mass <= 0.0 {
                return Err(src.err(
                    link.node,
                    format!(
                        "link '{}' moves but has no mass: give it an <inertial> with a positive mass (or fix a link that has one to it)",
                        link.name
                    ),
                ));
            }
            let axes = self.world[l].r;
            let j = axes.transpose() * tensor * axes;
            let p = UnitQuaternion::from_matrix(&axes);
            let orientation = KeyValue::table([("quaternion", KeyValue::from([p.w, p.i, p.j, p.k]))]);
            model = model.body(
                body(link.name)
                    .mass(mass)
                    .set(
                        "inertia",
                        [j[(0, 0)], j[(1, 1)], j[(2, 2)], j[(0, 1)], j[(0, 2)], j[(1, 2)]],
                    )
                    .position(<[f64; 3]>::from(center))
                    .set("orientation", orientation),
            );
        }
        for &k in &self.order {
            let j = &joints[k];
            let kind = match j.kind {
                Kind::Revolute => "revolute",
                Kind::Prismatic => "prismatic",
                Kind::Fixed | Kind::Floating => continue,
            };
            let frame = self.world[j.child];
            let axis = frame.r * j.axis;
            let bodies = [body_name(self.body[j.parent]), body_name(self.body[j.child])];
            model = model.joint(
                joint(&j.name, kind, bodies)
                    .at(<[f64; 3]>::from(frame.p))
                    .axis(<[f64; 3]>::from(axis)),
            );
            if j.damping > 0.0 {
                let name = format!("{}-damping", j.name);
                let damper = match j.kind {
                    Kind::Revolute => force(&name, "rotational-spring-damper").set("joint", j.name.as_str()),
                    _ => {
                        // Along the axis, from a point of the parent 1 m behind the joint to the
                        // joint's point on the child: the line stays the axis as the joint slides.
                        let behind = frame.p - axis;
                        force(&name, "spring-damper")
                            .set("bodies", bodies)
                            .set("at", [<[f64; 3]>::from(behind), <[f64; 3]>::from(frame.p)])
                    }
                };
                model = model.force(damper.set("stiffness", 0.0).set("damping", j.damping));
            }
        }
        Ok(model)
    }
}

/// The scene a URDF file describes (see the module documentation); `origin` names the file in
/// errors, which name the element and its line.
pub(crate) fn scene(text: &str, origin: &str) -> Result<Scene, SceneError> {
    with_scene(text, origin, None)
}

/// The scene of a URDF file, with a TOML scene's additions when `around` is `Some((tables,
/// text, origin))`: its `[scene]` keys (name, gravity) replace the robot's, its bodies, joints,
/// drivers and forces are added to the robot's, and its `[simulation]` and `[initial]` are the
/// scene's. Errors are placed in the file that holds the element they name.
fn with_scene(text: &str, origin: &str, around: Option<(toml::Table, &str, &str)>) -> Result<Scene, SceneError> {
    let doc = xml::parse(text, origin)?;
    let src = Source { text, origin };
    let (model, places, notes) = read(&src, &doc)?;
    let mut tables = model.into_table();
    let (outer_text, outer_origin) = around.as_ref().map_or((text, origin), |(_, t, o)| (*t, *o));
    let around_given = around.is_some();
    if let Some((outer, _, _)) = around {
        for (key, value) in outer {
            match (key.as_str(), value) {
                ("scene", toml::Value::Table(keys)) => {
                    if let Some(toml::Value::Table(scene)) = tables.get_mut("scene") {
                        scene.extend(keys.into_iter().filter(|(k, _)| k != "urdf"));
                    }
                }
                ("bodies" | "joints" | "drivers" | "forces", toml::Value::Array(more)) => match tables.get_mut(&key) {
                    Some(toml::Value::Array(list)) => list.extend(more),
                    _ => {
                        tables.insert(key, toml::Value::Array(more));
                    }
                },
                (_, value) => {
                    tables.insert(key, value);
                }
            }
        }
    }
    let merged = toml::to_string(&tables).unwrap_or_default();
    let scene = Scene::from_toml(&merged, outer_origin).map_err(|e| {
        // The scene builder's message names an element: place it at its line, in the URDF file
        // or the TOML scene around it.
        // An element the TOML scene names is placed there first: it is what the user wrote.
        let names: Vec<&str> = e.message.split('\'').skip(1).step_by(2).collect();
        let in_outer = |n: &&str| {
            let quoted = outer_text.find(&format!("\"{n}\""));
            quoted.or_else(|| outer_text.find(&format!("{n} =")))
        };
        let outer_place = around_given.then(|| names.iter().find_map(in_outer)).flatten();
        if let Some(a) = outer_place {
            return SceneError::at(outer_origin, outer_text, Some(a..a), e.message);
        }
        if let Some(&node) = names.iter().find_map(|n| places.get(*n)) {
            return src.err(node, e.message);
        }
        SceneError {
            file: outer_origin.to_string(),
            position: None,
            message: e.message,
        }
    })?;
    Ok(Scene { notes, ..scene })
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
    with_scene(&urdf, &shown, Some((tables, text, origin)))
}
