//! A tree of rigid links and the joints between them, as robot description formats give it
//! (URDF's links and joints, MJCF's nested bodies), turned into a spatial scene's elements: a
//! body per link that moves, links welded together merged, the root on the ground. The readers
//! (`urdf.rs`, `mjcf.rs`) parse their syntax into [`Link`]s and [`TreeJoint`]s; everything after
//! that is here, once (`docs/import.md`).

use super::xml::Source;
use super::{Scene, SceneError};
use crate::builder::{body, force, joint, KeyValue, ModelBuilder};
use nalgebra::{Matrix3, Vector3};
use roxmltree::Node;
use std::collections::HashMap;

pub(crate) type V3 = Vector3<f64>;

/// A rigid transform: `x ↦ r x + p`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pose {
    pub(crate) p: V3,
    pub(crate) r: Matrix3<f64>,
}

impl Pose {
    pub(crate) const IDENTITY: Pose = Pose {
        p: Vector3::new(0.0, 0.0, 0.0),
        r: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
    };

    /// `self ∘ other`: `other` given in `self`'s frame.
    pub(crate) fn then(&self, other: &Pose) -> Pose {
        Pose {
            p: self.p + self.r * other.p,
            r: self.r * other.r,
        }
    }
}

/// A link's `<inertial>`: frame, mass and tensor (about the centre of mass, inertial axes).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Inertial {
    pub(crate) frame: Pose,
    pub(crate) mass: f64,
    pub(crate) tensor: Matrix3<f64>,
}

/// A shape a link is drawn with.
#[derive(Debug, Clone)]
pub(crate) enum Shape {
    Box([f64; 3]),
    Sphere(f64),
    /// Radius and length, along z.
    Cylinder(f64, f64),
    /// The file as the scene names it and its scale.
    Mesh(String, [f64; 3]),
}

/// A link's `<visual>`: its frame in the link's, its shape, and where the file declares it.
#[derive(Debug, Clone)]
pub(crate) struct LinkVisual {
    pub(crate) pose: Pose,
    pub(crate) shape: Shape,
    pub(crate) declared: String,
}

#[derive(Debug, Clone)]
pub(crate) struct Link<'a, 'i> {
    pub(crate) name: String,
    pub(crate) node: Node<'a, 'i>,
    pub(crate) inertial: Option<Inertial>,
    pub(crate) visuals: Vec<LinkVisual>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Kind {
    Revolute,
    Spherical,
    Prismatic,
    Fixed,
    Floating,
}

#[derive(Debug)]
pub(crate) struct TreeJoint {
    /// The name in the file.
    pub(crate) file_name: String,
    /// The name in the scene (the file's, unless a link has it).
    pub(crate) name: String,
    pub(crate) kind: Kind,
    pub(crate) parent: usize,
    pub(crate) child: usize,
    pub(crate) origin: Pose,
    pub(crate) axis: V3,
    pub(crate) damping: f64,
    /// A spring on the joint coordinate (N·m/rad or N/m; MJCF's `stiffness`) …
    pub(crate) stiffness: f64,
    /// … relaxed at this joint value (rad or m from the file's configuration; `springref`).
    pub(crate) spring_rest: f64,
    /// A constant friction force or torque on the joint (N or N·m; a URDF's `<dynamics
    /// friction>`, an MJCF joint's `frictionloss`; `docs/friction.md`).
    pub(crate) friction: f64,
    /// Stops on the joint value `[lower, upper]` (rad or m from the file's configuration), which
    /// hold it there (a URDF's `<limit>`, an MJCF joint's `range`; `docs/limits.md`).
    pub(crate) limits: Option<[f64; 2]>,
}

/// The stops of joint `name` on `[lower, upper]` (from the file's configuration), or why they
/// are left out (a line for the notes): a zero range, or a file's configuration outside them.
pub(crate) fn stops(name: &str, lower: f64, upper: f64) -> Result<[f64; 2], String> {
    if lower >= upper {
        Err(format!(
            "joint '{name}': its limits [{lower}, {upper}] have no range, so they are left out"
        ))
    } else if lower > 0.0 || upper < 0.0 {
        Err(format!(
            "joint '{name}': the file's configuration (joint value 0) lies outside its limits [{lower}, {upper}], so they are left out"
        ))
    } else {
        Ok([lower, upper])
    }
}

/// `'a', 'b' and 'c'`.
pub(crate) fn quoted(names: &[String]) -> String {
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
pub(crate) struct Skipped(Vec<(String, usize)>);

impl Skipped {
    /// Counts the children of `node` not in `known`, except the `quiet` ones (documented as
    /// carrying no dynamics).
    pub(crate) fn note(&mut self, node: Node<'_, '_>, known: &[&str], quiet: &[&str]) {
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

    pub(crate) fn lines(&self) -> impl Iterator<Item = String> + '_ {
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
/// The mass, centre of mass and inertia about it of rigid parts given as (mass, centre, inertia
/// about that centre), all in one frame: masses add, the centre is their weighted mean, and the
/// inertias add about it by the parallel-axis theorem. `None` without mass.
pub(crate) fn combined(parts: &[(f64, V3, Matrix3<f64>)]) -> Option<(f64, V3, Matrix3<f64>)> {
    let mass: f64 = parts.iter().map(|p| p.0).sum();
    if mass.is_nan() || mass <= 0.0 {
        return None;
    }
    let center = parts.iter().fold(V3::zeros(), |s, (m, c, _)| s + *m * c) / mass;
    let tensor = parts.iter().fold(Matrix3::zeros(), |s, (m, c, j)| {
        let d = c - center;
        s + j + *m * (Matrix3::identity() * d.norm_squared() - d * d.transpose())
    });
    Some((mass, center, tensor))
}

pub(crate) struct Tree {
    /// Each link's frame (world).
    pub(crate) world: Vec<Pose>,
    /// Each link's body: `None` for the ground (the root and the links fixed to it).
    pub(crate) body: Vec<Option<usize>>,
    /// Each body's principal link (the child of the joint that moves it).
    pub(crate) principal: Vec<usize>,
    /// The joints in the order the tree was walked (parents before children).
    pub(crate) order: Vec<usize>,
}

impl Tree {
    pub(crate) fn of(
        src: &Source<'_>,
        robot: Node<'_, '_>,
        links: &[Link<'_, '_>],
        joints: &[TreeJoint],
        parent_joint: &[Option<usize>],
        floating: bool,
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
        if floating {
            // A floating base: the root link is a body of its own, with no joint to the ground.
            tree.principal.push(root);
            tree.body[root] = Some(0);
        }
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
    pub(crate) fn mass_properties(&self, links: &[Link<'_, '_>], b: usize) -> (f64, V3, Matrix3<f64>) {
        let parts: Vec<(f64, V3, Matrix3<f64>)> = (0..links.len())
            .filter(|&l| self.body[l] == Some(b))
            .filter_map(|l| {
                let i = links[l].inertial?;
                let frame = self.world[l].then(&i.frame);
                Some((i.mass, frame.p, frame.r * i.tensor * frame.r.transpose()))
            })
            .collect();
        combined(&parts).unwrap_or((0.0, V3::zeros(), Matrix3::zeros()))
    }

    /// The visuals of body `b`'s links (`None`: the ground's), in the body's frame (`frame`,
    /// world), as a scene's `visual` key writes them.
    fn visuals(&self, links: &[Link<'_, '_>], b: Option<usize>, frame: &Pose) -> Option<KeyValue> {
        let mut out = Vec::new();
        for l in (0..links.len()).filter(|&l| self.body[l] == b) {
            for v in &links[l].visuals {
                let w = self.world[l].then(&v.pose);
                let position = frame.r.transpose() * (w.p - frame.p);
                let q = dalembert_spatial::euler_parameters::from_rotation(&(frame.r.transpose() * w.r));
                let (key, value) = match &v.shape {
                    Shape::Box(size) => ("box", KeyValue::from(*size)),
                    Shape::Sphere(r) => ("sphere", KeyValue::from(*r)),
                    Shape::Cylinder(r, l) => (
                        "cylinder",
                        KeyValue::table([("radius", KeyValue::from(*r)), ("length", KeyValue::from(*l))]),
                    ),
                    Shape::Mesh(file, _) => ("mesh", KeyValue::from(file.as_str())),
                };
                let placed = [
                    (key, value),
                    ("position", KeyValue::from(<[f64; 3]>::from(position))),
                    ("orientation", KeyValue::table([("quaternion", KeyValue::from(q))])),
                    ("declared", KeyValue::from(v.declared.as_str())),
                ];
                out.push(match &v.shape {
                    Shape::Mesh(_, scale) => {
                        let [a, b, c, d] = placed;
                        KeyValue::table([a, b, c, d, ("scale", KeyValue::from(*scale))])
                    }
                    _ => KeyValue::table(placed),
                });
            }
        }
        (!out.is_empty()).then(|| KeyValue::from(out))
    }

    pub(crate) fn elements(
        &self,
        src: &Source<'_>,
        name: &str,
        links: &[Link<'_, '_>],
        joints: &[TreeJoint],
        part: &str,
    ) -> Result<ModelBuilder, SceneError> {
        let mut model = ModelBuilder::spatial(name).gravity([0.0, 0.0, -9.81]);
        let body_name = |b: Option<usize>| b.map_or("ground", |b| links[self.principal[b]].name.as_str());
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
                        "{part} '{}' moves but has no mass: give it an <inertial> with a positive mass (or fix a {part} that has one to it)",
                        link.name
                    ),
                ));
            }
            let axes = self.world[l].r;
            let j = axes.transpose() * tensor * axes;
            let body_frame = Pose { p: center, r: axes };
            // Closed form (Shepperd): an iterative fit would not end on a matrix a malformed file
            // made non-orthogonal.
            let p = dalembert_spatial::euler_parameters::from_rotation(&axes);
            let orientation = KeyValue::table([("quaternion", KeyValue::from(p))]);
            let mut element = body(&link.name)
                .mass(mass)
                .set(
                    "inertia",
                    [j[(0, 0)], j[(1, 1)], j[(2, 2)], j[(0, 1)], j[(0, 2)], j[(1, 2)]],
                )
                .position(<[f64; 3]>::from(center))
                .set("orientation", orientation);
            if let Some(visual) = self.visuals(links, Some(b), &body_frame) {
                element = element.set("visual", visual);
            }
            model = model.body(element);
        }
        if let Some(visual) = self.visuals(links, None, &Pose::IDENTITY) {
            model = model.scene("visual", visual);
        }
        for &k in &self.order {
            let j = &joints[k];
            let kind = match j.kind {
                Kind::Revolute => "revolute",
                Kind::Prismatic => "prismatic",
                Kind::Spherical => "spherical",
                Kind::Fixed | Kind::Floating => continue,
            };
            let frame = self.world[j.child];
            let axis = frame.r * j.axis;
            let bodies = [body_name(self.body[j.parent]), body_name(self.body[j.child])];
            let placed = joint(&j.name, kind, bodies).at(<[f64; 3]>::from(frame.p));
            let placed = match j.limits {
                Some(bounds) => placed.set("limits", bounds),
                None => placed,
            };
            let placed = if j.friction > 0.0 {
                placed.set("friction", KeyValue::table([("constant", KeyValue::from(j.friction))]))
            } else {
                placed
            };
            model = model.joint(match j.kind {
                Kind::Spherical => placed,
                _ => placed.axis(<[f64; 3]>::from(axis)),
            });
            if j.damping > 0.0 || j.stiffness > 0.0 {
                // The joint's passive spring and damper (a URDF's `dynamics damping`, an MJCF
                // joint's `damping`, `stiffness` and `springref`).
                let name = format!("{}-damping", j.name);
                let damper = match j.kind {
                    Kind::Revolute => force(&name, "rotational-spring-damper").set("free_angle", j.spring_rest),
                    // Along the slide's axis: a servo (docs/scenes.md) whose target is the
                    // spring's rest displacement (a target needs a stiffness), the force
                    // `−k (s − s₀) − c ṡ`.
                    _ if j.stiffness > 0.0 => force(&name, "servo").set("target", j.spring_rest),
                    _ => force(&name, "servo"),
                };
                let damper = damper.set("joint", j.name.as_str());
                model = model.force(damper.set("stiffness", j.stiffness).set("damping", j.damping));
            }
        }
        Ok(model)
    }
}

/// What a reader gives: the robot's scene elements, where each link and joint is in the file (for
/// errors the scene builder finds), and the notes on what the reader left out.
pub(crate) type Read<'a> = (ModelBuilder, HashMap<String, Node<'a, 'a>>, Vec<String>);

/// The scene of a model file's elements (`Read`: what a reader gives), with a TOML scene's additions when `around` is `Some((tables,
/// text, origin))`: its `[scene]` keys (name, gravity) replace the robot's, its bodies, joints,
/// drivers and forces are added to the robot's, and its `[simulation]` and `[initial]` are the
/// scene's. Errors are placed in the file that holds the element they name.
pub(crate) fn scene_of(
    src: &Source<'_>,
    (model, places, notes): Read<'_>,
    around: Option<(toml::Table, &str, &str)>,
) -> Result<Scene, SceneError> {
    let (text, origin) = (src.text, src.origin);
    let mut tables = model.into_table();
    let (outer_text, outer_origin) = around.as_ref().map_or((text, origin), |(_, t, o)| (*t, *o));
    let around_given = around.is_some();
    if let Some((outer, _, _)) = around {
        for (key, value) in outer {
            match (key.as_str(), value) {
                ("scene", toml::Value::Table(keys)) => {
                    if let Some(toml::Value::Table(scene)) = tables.get_mut("scene") {
                        scene.extend(keys.into_iter().filter(|(k, _)| k != "urdf" && k != "floating_base"));
                    }
                }
                ("bodies" | "joints" | "drivers" | "forces" | "couplings", toml::Value::Array(more)) => {
                    match tables.get_mut(&key) {
                        Some(toml::Value::Array(list)) => list.extend(more),
                        _ => {
                            tables.insert(key, toml::Value::Array(more));
                        }
                    }
                }
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
