//! MJCF model files, a subset (`docs/import.md`, "MJCF"): the `worldbody` tree of bodies with
//! one joint each, inertias given or computed from geoms as MuJoCo computes them, `default`
//! classes, `compiler angle` and `eulerseq`, `equality connect` and `weld` as exact joints, and
//! `actuator motor` as named inputs. The bodies and joints become the [`tree`](super::tree) the
//! URDF reader also builds on. Everything outside the subset is refused in one line naming the
//! element and its line, or, for what carries no dynamics here (assets, sites, lights,
//! contacts), skipped with a note.

mod actuators;
mod meshes;

use super::tree::{
    combined, quoted, scene_of, Inertial, Kind, Link, LinkVisual, Pose, Read, Shape, Tree, TreeJoint, V3,
};
use super::xml::{self, Source};
use super::{Scene, SceneError};
use crate::builder::{force, joint, Function};
use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};
use roxmltree::Node;
use std::collections::HashMap;
use std::f64::consts::PI;

/// A geom's type, `size` numbers, frame in its body and half-length along its z.
type GeomShape<'a> = (&'a str, Vec<f64>, Pose, Option<f64>);

/// The scene an MJCF file describes; `origin` names the file in errors.
pub(crate) fn scene(text: &str, origin: &str) -> Result<Scene, SceneError> {
    let doc = xml::parse(text, origin)?;
    let src = Source { text, origin };
    let read = Reader::new(&src, &doc)?.read()?;
    scene_of(&src, read, None)
}

/// The attributes that place a frame: `pos` and the five ways of giving an orientation.
const FRAME_KEYS: [&str; 6] = ["pos", "quat", "axisangle", "euler", "xyaxes", "zaxis"];

/// Attribute values by class, element tag and attribute (`<default>`).
type Defaults<'a> = HashMap<String, HashMap<String, HashMap<String, &'a str>>>;

struct Reader<'s, 'a> {
    src: &'s Source<'a>,
    doc: &'a roxmltree::Document<'a>,
    defaults: Defaults<'a>,
    degrees: bool,
    eulerseq: Vec<char>,
    from_geoms: &'a str,
    gravity: [f64; 3],
    step: Option<f64>,
    /// `compiler meshdir`, else `assetdir`.
    mesh_folder: Option<String>,
    /// The `<asset>` meshes by name.
    meshes: HashMap<String, meshes::MeshAsset>,
    notes: Vec<String>,
    skipped: Vec<String>,
}

/// One body of the tree as read: its link, and where its joint frame sits in its own frame.
struct Part<'a> {
    link: Link<'a, 'a>,
    /// The joint's position in the body's frame: the link's frame is the body's moved there.
    offset: V3,
}

impl<'s, 'a> Reader<'s, 'a> {
    fn new(src: &'s Source<'a>, doc: &'a roxmltree::Document<'a>) -> Result<Self, SceneError> {
        let root = doc.root_element();
        if root.tag_name().name() != "mujoco" {
            return Err(src.err(
                root,
                format!(
                    "the root element is <{}>; an MJCF file's is <mujoco>",
                    root.tag_name().name()
                ),
            ));
        }
        let mut r = Reader {
            src,
            doc,
            defaults: HashMap::new(),
            degrees: true,
            eulerseq: vec!['x', 'y', 'z'],
            from_geoms: "auto",
            gravity: [0.0, 0.0, -9.81],
            step: None,
            mesh_folder: None,
            meshes: HashMap::new(),
            notes: Vec::new(),
            skipped: Vec::new(),
        };
        for c in root.children().filter(Node::is_element) {
            match c.tag_name().name() {
                "compiler" => r.compiler(c)?,
                "option" => r.option(c)?,
                "default" => r.default(c, "main", &HashMap::new())?,
                "asset" => {}
                "worldbody" | "equality" | "actuator" => {}
                "visual" | "statistic" | "size" | "sensor" | "keyframe" | "custom" => {
                    r.skip(format!("<{}>", c.tag_name().name()))
                }
                "contact" => r.skip("<contact> (contacts are not modelled)".into()),
                other => {
                    return Err(src.err(
                        c,
                        format!("<{other}> is outside the MJCF subset this reader reads (docs/import.md)"),
                    ))
                }
            }
        }
        // Assets after the compiler (its mesh folder), wherever the file puts them.
        for c in root.children().filter(|c| c.has_tag_name("asset")) {
            r.assets(c)?;
        }
        Ok(r)
    }

    fn skip(&mut self, what: String) {
        if !self.skipped.contains(&what) {
            self.skipped.push(what);
        }
    }

    fn err(&self, node: Node<'_, '_>, message: impl Into<String>) -> SceneError {
        self.src.err(node, message)
    }

    /// Refuses attributes of `node` outside `known` (nothing that changes the dynamics is
    /// dropped); `quiet` ones are accepted and play no part here.
    fn attributes(&self, node: Node<'_, '_>, known: &[&str], quiet: &[&str]) -> Result<(), SceneError> {
        for a in node.attributes() {
            if !known.contains(&a.name()) && !quiet.contains(&a.name()) {
                return Err(self.err(
                    node,
                    format!(
                        "<{}> attribute '{}' is outside the MJCF subset this reader reads",
                        node.tag_name().name(),
                        a.name()
                    ),
                ));
            }
        }
        Ok(())
    }

    fn compiler(&mut self, node: Node<'a, 'a>) -> Result<(), SceneError> {
        self.attributes(
            node,
            &["angle", "eulerseq", "inertiafromgeom", "meshdir", "assetdir"],
            &["autolimits", "texturedir", "discardvisual"],
        )?;
        if let Some(dir) = node.attribute("meshdir").or_else(|| node.attribute("assetdir")) {
            self.mesh_folder = Some(dir.to_string());
        }
        if let Some(a) = node.attribute("angle") {
            self.degrees = match a {
                "degree" => true,
                "radian" => false,
                other => return Err(self.err(node, format!("<compiler angle=\"{other}\">: expected degree or radian"))),
            };
        }
        if let Some(seq) = node.attribute("eulerseq") {
            let chars: Vec<char> = seq.chars().collect();
            if chars.len() != 3 || !chars.iter().all(|c| "xyzXYZ".contains(*c)) {
                return Err(self.err(
                    node,
                    format!("<compiler eulerseq=\"{seq}\">: expected three of x, y, z, X, Y, Z"),
                ));
            }
            self.eulerseq = chars;
        }
        if let Some(g) = node.attribute("inertiafromgeom") {
            if !["auto", "true", "false"].contains(&g) {
                return Err(self.err(
                    node,
                    format!("<compiler inertiafromgeom=\"{g}\">: expected auto, true or false"),
                ));
            }
            self.from_geoms = g;
        }
        Ok(())
    }

    fn option(&mut self, node: Node<'a, 'a>) -> Result<(), SceneError> {
        self.attributes(
            node,
            &["gravity", "timestep"],
            &["integrator", "iterations", "tolerance", "solver", "cone", "jacobian"],
        )?;
        self.gravity = self.src.vector(node, "gravity", self.gravity)?.into();
        if node.attribute("timestep").is_some() {
            self.step = Some(self.src.number(node, "timestep", None)?);
        }
        for c in node.children().filter(Node::is_element) {
            if c.tag_name().name() != "flag" {
                return Err(self.err(
                    c,
                    format!("<{}> in <option> is outside the MJCF subset", c.tag_name().name()),
                ));
            }
        }
        Ok(())
    }

    /// A `<default>` class and its nested classes, each inheriting its parent's values.
    fn default(
        &mut self,
        node: Node<'a, 'a>,
        class: &str,
        parent: &HashMap<String, HashMap<String, &'a str>>,
    ) -> Result<(), SceneError> {
        let mut own = parent.clone();
        for c in node.children().filter(Node::is_element) {
            let tag = c.tag_name().name();
            if tag == "default" {
                continue;
            }
            let values = own.entry(tag.to_string()).or_default();
            for a in c.attributes() {
                values.insert(a.name().to_string(), a.value());
            }
        }
        for c in node.children().filter(|c| c.has_tag_name("default")) {
            let name = self.src.required(c, "class")?;
            self.default(c, name, &own)?;
        }
        self.defaults.insert(class.to_string(), own);
        Ok(())
    }

    /// Attribute `key` of `node`, or its class's default (`class`, else the enclosing
    /// `childclass`, else `main`).
    fn value(&self, node: Node<'a, 'a>, key: &str) -> Option<&'a str> {
        if let Some(v) = node.attribute(key) {
            return Some(v);
        }
        let class = node
            .attribute("class")
            .or_else(|| node.ancestors().skip(1).find_map(|a| a.attribute("childclass")));
        let tag = node.tag_name().name();
        let look = |c: &str| {
            self.defaults
                .get(c)
                .and_then(|d| d.get(tag))
                .and_then(|m| m.get(key))
                .copied()
        };
        class.and_then(look).or_else(|| look("main"))
    }

    fn numbers<const N: usize>(&self, node: Node<'a, 'a>, key: &str) -> Result<Option<[f64; N]>, SceneError> {
        let Some(s) = self.value(node, key) else {
            return Ok(None);
        };
        let parts: Vec<f64> = s
            .split_whitespace()
            .map(|p| p.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                self.err(
                    node,
                    format!("<{}> {key}=\"{s}\": expected {N} numbers", node.tag_name().name()),
                )
            })?;
        if parts.len() != N || !parts.iter().all(|x| x.is_finite()) {
            return Err(self.err(
                node,
                format!(
                    "<{}> {key}=\"{s}\": expected {N} finite numbers",
                    node.tag_name().name()
                ),
            ));
        }
        let mut out = [0.0; N];
        out.copy_from_slice(&parts);
        Ok(Some(out))
    }

    /// `key`'s two numbers where the element is limited: where `flag` is `true`, or "auto" (the
    /// default) and the range is given, as MuJoCo decides (joint ranges, actuators' control and
    /// force ranges); `None` where it is not. `flag="true"` without the range is an error.
    fn limited_range(&self, node: Node<'a, 'a>, key: &str, flag: &str) -> Result<Option<[f64; 2]>, SceneError> {
        let tag = node.tag_name().name();
        let given = self.numbers::<2>(node, key)?;
        let on = match self.value(node, flag).unwrap_or("auto") {
            "true" => true,
            "false" => false,
            "auto" => given.is_some(),
            other => {
                return Err(self.err(
                    node,
                    format!("<{tag}> {flag}=\"{other}\": expected true, false or auto"),
                ))
            }
        };
        match (on, given) {
            (true, None) => Err(self.err(node, format!("<{tag}> {flag}=\"true\" needs {key}"))),
            (true, given) => Ok(given),
            (false, _) => Ok(None),
        }
    }

    fn number(&self, node: Node<'a, 'a>, key: &str, default: f64) -> Result<f64, SceneError> {
        Ok(self.numbers::<1>(node, key)?.map_or(default, |[x]| x))
    }

    fn angle(&self, a: f64) -> f64 {
        if self.degrees {
            a * PI / 180.0
        } else {
            a
        }
    }

    /// The frame `pos` and `quat` / `axisangle` / `euler` / `xyaxes` / `zaxis` give.
    fn frame(&self, node: Node<'a, 'a>) -> Result<Pose, SceneError> {
        let p = self.numbers::<3>(node, "pos")?.map_or(V3::zeros(), V3::from);
        let given: Vec<&str> = FRAME_KEYS[1..]
            .iter()
            .copied()
            .filter(|k| node.attribute(*k).is_some())
            .collect();
        if given.len() > 1 {
            return Err(self.err(
                node,
                format!(
                    "<{}> gives its orientation twice ({})",
                    node.tag_name().name(),
                    given.join(", ")
                ),
            ));
        }
        let bad = |what: &str| self.err(node, format!("<{}> {what}", node.tag_name().name()));
        let r = if let Some([w, x, y, z]) = self.numbers::<4>(node, "quat")? {
            let q = nalgebra::Quaternion::new(w, x, y, z);
            if q.norm() < 1e-12 {
                return Err(bad("quat is zero"));
            }
            *UnitQuaternion::from_quaternion(q).to_rotation_matrix().matrix()
        } else if let Some([x, y, z, a]) = self.numbers::<4>(node, "axisangle")? {
            let axis = Unit::try_new(Vector3::new(x, y, z), 1e-12).ok_or_else(|| bad("axisangle has a zero axis"))?;
            *Rotation3::from_axis_angle(&axis, self.angle(a)).matrix()
        } else if let Some(e) = self.numbers::<3>(node, "euler")? {
            let mut r = Matrix3::identity();
            for (c, a) in self.eulerseq.iter().zip(e) {
                let axis = match c.to_ascii_lowercase() {
                    'x' => Vector3::x_axis(),
                    'y' => Vector3::y_axis(),
                    _ => Vector3::z_axis(),
                };
                let turn = *Rotation3::from_axis_angle(&axis, self.angle(a)).matrix();
                // Lower case: about the moving frame's axis; upper case: about the fixed one.
                r = if c.is_ascii_lowercase() { r * turn } else { turn * r };
            }
            r
        } else if let Some([x1, x2, x3, y1, y2, y3]) = self.numbers::<6>(node, "xyaxes")? {
            let x = Vector3::new(x1, x2, x3);
            let y = Vector3::new(y1, y2, y3);
            let (xn, yp) = (x.norm(), y - x * x.dot(&y) / x.norm_squared().max(1e-300));
            if xn < 1e-12 || yp.norm() < 1e-12 {
                return Err(bad("xyaxes are zero or parallel"));
            }
            let (x, y) = (x / xn, yp.normalize());
            Matrix3::from_columns(&[x, y, x.cross(&y)])
        } else if let Some(z) = self.numbers::<3>(node, "zaxis")? {
            let z = Vector3::from(z);
            if z.norm() < 1e-12 {
                return Err(bad("zaxis is zero"));
            }
            *UnitQuaternion::rotation_between(&Vector3::z(), &z)
                .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI))
                .to_rotation_matrix()
                .matrix()
        } else {
            Matrix3::identity()
        };
        Ok(Pose { p, r })
    }

    /// An `<inertial>`: its frame, mass and `diaginertia` or `fullinertia`.
    fn inertial(&self, node: Node<'a, 'a>) -> Result<Inertial, SceneError> {
        let known = [&FRAME_KEYS[..], &["mass", "diaginertia", "fullinertia"]].concat();
        self.attributes(node, &known, &[])?;
        let frame = self.frame(node)?;
        let mass = self.number(node, "mass", f64::NAN)?;
        if mass.is_nan() || mass < 0.0 {
            return Err(self.err(node, "<inertial> needs a non-negative 'mass'"));
        }
        let tensor = match (
            self.numbers::<3>(node, "diaginertia")?,
            self.numbers::<6>(node, "fullinertia")?,
        ) {
            (Some(d), None) => Matrix3::from_diagonal(&Vector3::from(d)),
            (None, Some([xx, yy, zz, xy, xz, yz])) => Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz),
            _ => return Err(self.err(node, "<inertial> needs one of 'diaginertia' and 'fullinertia'")),
        };
        Ok(Inertial { frame, mass, tensor })
    }

    /// A geom's type, `size` numbers, frame (body frame; `fromto` gives a capsule's or cylinder's)
    /// and half-length along its z ([`GeomShape`]).
    fn geom_shape(&self, node: Node<'a, 'a>) -> Result<GeomShape<'a>, SceneError> {
        let kind = self.value(node, "type").unwrap_or("sphere");
        let size: Vec<f64> = match self.value(node, "size") {
            Some(s) => s
                .split_whitespace()
                .map(|p| p.parse::<f64>().unwrap_or(f64::NAN))
                .collect(),
            None => Vec::new(),
        };
        if size.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(self.err(node, "<geom> size must be non-negative numbers"));
        }
        let mut frame = self.frame(node)?;
        let mut half = size.get(1).copied();
        if let Some([x1, y1, z1, x2, y2, z2]) = self.numbers::<6>(node, "fromto")? {
            if !matches!(kind, "capsule" | "cylinder") {
                return Err(self.err(
                    node,
                    format!(
                        "<geom type=\"{kind}\"> with fromto is outside the subset (capsules and cylinders take it)"
                    ),
                ));
            }
            let (a, b) = (V3::new(x1, y1, z1), V3::new(x2, y2, z2));
            let axis = b - a;
            frame.p = 0.5 * (a + b);
            frame.r = *UnitQuaternion::rotation_between(&Vector3::z(), &axis)
                .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI))
                .to_rotation_matrix()
                .matrix();
            half = Some(0.5 * axis.norm());
        }
        Ok((kind, size, frame, half))
    }

    /// What a body's geoms look like (the link's frame is the body's moved by `offset`): spheres,
    /// boxes and cylinders as they are, a capsule as its cylinder and two balls, a mesh from its
    /// asset's file (read by the viewer). Ellipsoids and planes are not drawn (a body with none of
    /// the others is drawn as its box of inertia). As MuJoCo's viewer by default, only the geoms
    /// of groups 0 to 2 are drawn where a body has any (Menagerie's collision geoms are group 3).
    /// A mesh geom naming no `<asset>` mesh is an error naming its line.
    fn geom_visuals(&self, body: Node<'a, 'a>, offset: V3) -> Result<Vec<LinkVisual>, SceneError> {
        let mut out = Vec::new();
        let geoms: Vec<Node<'a, 'a>> = body.children().filter(|c| c.has_tag_name("geom")).collect();
        let group = |g: &Node<'a, 'a>| {
            self.value(*g, "group")
                .and_then(|v| v.trim().parse::<i64>().ok())
                .unwrap_or(0)
        };
        let shown = geoms.iter().any(|g| group(g) <= 2);
        for g in geoms.into_iter().filter(|g| !shown || group(g) <= 2) {
            // A geom outside the inertia subset still loads when an <inertial> is given: it is only
            // left undrawn.
            let Ok((kind, size, mut frame, half)) = self.geom_shape(g) else {
                continue;
            };
            frame.p -= offset;
            let s = |k: usize| size.get(k).copied().filter(|v| *v > 0.0);
            let line = super::error::line_col(self.src.text, g.range().start).0;
            let declared = format!("{} line {line}", self.src.origin);
            let mut push = |pose: Pose, shape: Shape| {
                out.push(LinkVisual {
                    pose,
                    shape,
                    declared: declared.clone(),
                })
            };
            match (kind, s(0), s(1), s(2), half.filter(|h| *h > 0.0)) {
                ("sphere", Some(r), ..) => push(frame, Shape::Sphere(r)),
                ("box", Some(a), Some(b), Some(c), _) => push(frame, Shape::Box([2.0 * a, 2.0 * b, 2.0 * c])),
                ("cylinder", Some(r), _, _, Some(h)) => push(frame, Shape::Cylinder(r, 2.0 * h)),
                ("capsule", Some(r), _, _, Some(h)) => {
                    push(frame, Shape::Cylinder(r, 2.0 * h));
                    for end in [-h, h] {
                        let p = frame.p + frame.r * V3::new(0.0, 0.0, end);
                        push(Pose { p, r: frame.r }, Shape::Sphere(r));
                    }
                }
                ("mesh", ..) => {
                    let name = self.value(g, "mesh").unwrap_or("");
                    let asset = self.meshes.get(name).ok_or_else(|| {
                        self.err(g, format!("<geom mesh=\"{name}\">: no <mesh> of that name in <asset>"))
                    })?;
                    push(frame, Shape::Mesh(asset.file.clone(), asset.scale));
                }
                _ => {}
            }
        }
        Ok(out)
    }

    /// A geom's mass, centre and inertia about it (body frame), as MuJoCo computes them from its
    /// shape and density (or mass).
    fn geom(&self, node: Node<'a, 'a>) -> Result<(f64, V3, Matrix3<f64>), SceneError> {
        let (kind, size, frame, half) = self.geom_shape(node)?;
        let s = |k: usize| size.get(k).copied();
        let need = |v: Option<f64>, what: &str| {
            v.ok_or_else(|| self.err(node, format!("<geom type=\"{kind}\"> needs its {what} in 'size'")))
        };
        // Volume and the inertia per unit mass about the centre, principal in the geom's frame.
        let (volume, unit) = match kind {
            "sphere" => {
                let r = need(s(0), "radius")?;
                (4.0 / 3.0 * PI * r.powi(3), [0.4 * r * r; 3])
            }
            "box" => {
                let (a, b, c) = (need(s(0), "half-sizes")?, need(s(1), "half-sizes")?, need(s(2), "half-sizes")?);
                (8.0 * a * b * c, [(b * b + c * c) / 3.0, (a * a + c * c) / 3.0, (a * a + b * b) / 3.0])
            }
            "ellipsoid" => {
                let (a, b, c) = (need(s(0), "radii")?, need(s(1), "radii")?, need(s(2), "radii")?);
                (4.0 / 3.0 * PI * a * b * c, [(b * b + c * c) / 5.0, (a * a + c * c) / 5.0, (a * a + b * b) / 5.0])
            }
            "cylinder" => {
                let (r, h) = (need(s(0), "radius")?, 2.0 * need(half, "half-length")?);
                let across = (3.0 * r * r + h * h) / 12.0;
                (PI * r * r * h, [across, across, 0.5 * r * r])
            }
            "capsule" => {
                let (r, h) = (need(s(0), "radius")?, 2.0 * need(half, "half-length")?);
                // The cylinder and the two hemispheres, as fractions of the mass.
                let ball = 4.0 * r / (4.0 * r + 3.0 * h);
                let tube = 1.0 - ball;
                let across = tube * (3.0 * r * r + h * h) / 12.0 + ball * (0.4 * r * r + h * (3.0 * r + 2.0 * h) / 8.0);
                (PI * r * r * h + 4.0 / 3.0 * PI * r.powi(3), [across, across, tube * 0.5 * r * r + ball * 0.4 * r * r])
            }
            "plane" => return Ok((0.0, frame.p, Matrix3::zeros())),
            other => {
                return Err(self.err(node, format!("<geom type=\"{other}\"> is outside the subset (sphere, box, ellipsoid, cylinder, capsule; a mesh's inertia needs its file)")))
            }
        };
        let mass = match self.value(node, "mass") {
            Some(_) => self.number(node, "mass", 0.0)?,
            None => self.number(node, "density", 1000.0)? * volume,
        };
        let tensor = frame.r * Matrix3::from_diagonal(&(mass * Vector3::from(unit))) * frame.r.transpose();
        Ok((mass, frame.p, tensor))
    }

    /// The body's inertial: given, or from its geoms (`compiler inertiafromgeom`).
    fn body_inertial(&self, body: Node<'a, 'a>) -> Result<Option<Inertial>, SceneError> {
        let given = body.children().find(|c| c.has_tag_name("inertial"));
        if let (Some(i), false) = (given, self.from_geoms == "true") {
            return self.inertial(i).map(Some);
        }
        if self.from_geoms == "false" {
            return Ok(None);
        }
        let mut parts = Vec::new();
        for g in body.children().filter(|c| c.has_tag_name("geom")) {
            parts.push(self.geom(g)?);
        }
        Ok(combined(&parts).map(|(mass, center, tensor)| Inertial {
            frame: Pose {
                p: center,
                r: Matrix3::identity(),
            },
            mass,
            tensor,
        }))
    }

    fn read(mut self) -> Result<Read<'a>, SceneError> {
        let root = self.doc.root_element();
        let stem = std::path::Path::new(self.src.origin)
            .file_stem()
            .and_then(|s| s.to_str());
        let name = root.attribute("model").or(stem).unwrap_or("mjcf");
        let world = root
            .children()
            .find(|c| c.has_tag_name("worldbody"))
            .ok_or_else(|| self.err(root, "the file has no <worldbody>"))?;
        let mut parts: Vec<Part<'a>> = vec![Part {
            link: Link {
                name: "world".to_string(),
                node: world,
                inertial: None,
                visuals: Vec::new(),
            },
            offset: V3::zeros(),
        }];
        let mut joints: Vec<TreeJoint> = Vec::new();
        let mut names: HashMap<String, usize> = HashMap::from([("world".to_string(), 0)]);
        let mut places: HashMap<String, Node<'a, 'a>> = HashMap::new();
        let mut damped_extras = Vec::new();
        self.bodies(
            world,
            0,
            &mut parts,
            &mut joints,
            &mut names,
            &mut places,
            &mut damped_extras,
        )?;
        let links: Vec<Link<'a, 'a>> = parts.iter().map(|p| p.link.clone()).collect();
        let mut parent_joint = vec![None; links.len()];
        for (k, j) in joints.iter().enumerate() {
            parent_joint[j.child] = Some(k);
        }
        let tree = Tree::of(self.src, root, &links, &joints, &parent_joint, false)?;
        if tree.principal.is_empty() {
            return Err(self.err(world, "nothing moves: no body in <worldbody> has a joint"));
        }
        let mut model = tree
            .elements(self.src, name, &links, &joints, "body")?
            .gravity(self.gravity);
        if let Some(step) = self.step {
            model = model.simulation("step", step);
        }
        let body_name = |link: usize| tree.body[link].map_or("ground", |b| links[tree.principal[b]].name.as_str());
        // Equality constraints, exact here (MuJoCo's are soft).
        if let Some(eq) = root.children().find(|c| c.has_tag_name("equality")) {
            for (k, c) in eq.children().filter(Node::is_element).enumerate() {
                let tag = c.tag_name().name();
                if self.value(c, "active") == Some("false") {
                    continue;
                }
                let link_of = |key: &str| -> Result<usize, SceneError> {
                    match self.value(c, key) {
                        None => Ok(0),
                        Some(n) => names
                            .get(n)
                            .copied()
                            .ok_or_else(|| self.err(c, format!("<{tag}> {key}=\"{n}\": no such body"))),
                    }
                };
                let default_name = format!("{tag}{k}");
                let label = self.value(c, "name").unwrap_or(&default_name).to_string();
                match tag {
                    "connect" => {
                        self.attributes(
                            c,
                            &["name", "body1", "body2", "anchor", "active", "class"],
                            &["solref", "solimp"],
                        )?;
                        let (b1, b2) = (link_of("body1")?, link_of("body2")?);
                        let anchor = self.numbers::<3>(c, "anchor")?.map_or(V3::zeros(), V3::from);
                        // The anchor is in body 1's frame, the link's frame less its joint offset.
                        let at = tree.world[b1].p + tree.world[b1].r * (anchor - parts[b1].offset);
                        model = model
                            .joint(joint(&label, "spherical", [body_name(b1), body_name(b2)]).at(<[f64; 3]>::from(at)));
                        places.insert(label, c);
                    }
                    "weld" => {
                        self.attributes(c, &["name", "body1", "body2", "active", "class"], &["solref", "solimp"])?;
                        let (b1, b2) = (link_of("body1")?, link_of("body2")?);
                        let at = tree.world[b1].p;
                        model = model
                            .joint(joint(&label, "fixed", [body_name(b1), body_name(b2)]).at(<[f64; 3]>::from(at)));
                        places.insert(label, c);
                    }
                    "joint" => {
                        // joint1 = p(joint2), each from its reference (0 here): a coupling
                        // (`docs/couplings.md`); without joint2, joint1 held at polycoef[0].
                        self.attributes(
                            c,
                            &["name", "joint1", "joint2", "polycoef", "active", "class"],
                            &["solref", "solimp"],
                        )?;
                        let moving = |key: &str| -> Result<Option<String>, SceneError> {
                            let Some(target) = self.value(c, key) else {
                                return Ok(None);
                            };
                            let j = joints
                                .iter()
                                .find(|j| j.file_name == target)
                                .ok_or_else(|| self.err(c, format!("<joint> {key}=\"{target}\": no such joint")))?;
                            if !matches!(j.kind, Kind::Revolute | Kind::Prismatic) {
                                return Err(self.err(
                                    c,
                                    format!("<joint> {key}=\"{target}\": a coupling joins hinge and slide joints"),
                                ));
                            }
                            Ok(Some(j.name.clone()))
                        };
                        let follower = moving("joint1")?.ok_or_else(|| self.err(c, "<joint> needs 'joint1'"))?;
                        let leader = moving("joint2")?;
                        let coefficients = self.numbers::<5>(c, "polycoef")?.unwrap_or([0.0, 1.0, 0.0, 0.0, 0.0]);
                        let element = crate::builder::coupling(&label, leader.as_deref().unwrap_or(""), &follower)
                            .set("polynomial", coefficients);
                        model = model.coupling(if leader.is_none() {
                            element.without("leader")
                        } else {
                            element
                        });
                        places.insert(label, c);
                    }
                    other => {
                        return Err(self.err(
                            c,
                            format!("<equality> <{other}> is outside the subset (connect, weld and joint are read)"),
                        ))
                    }
                }
            }
            self.notes
                .push("equality constraints are exact here (MuJoCo's are soft: solref and solimp play no part)".into());
        }
        // Actuators: a named input each, a torque about its hinge (a force along its slide).
        if let Some(act) = root.children().find(|c| c.has_tag_name("actuator")) {
            for c in act.children().filter(Node::is_element) {
                let law = self.actuator_law(c)?;
                let tag = c.tag_name().name();
                let target = self
                    .value(c, "joint")
                    .ok_or_else(|| self.err(c, format!("<{tag}> needs 'joint'")))?;
                let j = joints
                    .iter()
                    .find(|j| j.file_name == target && j.kind != Kind::Fixed)
                    .ok_or_else(|| self.err(c, format!("<{tag}> joint=\"{target}\": no such joint")))?;
                let input = self.value(c, "name").unwrap_or(target);
                // The element is named after the actuator, or `<name>-actuator` where a body or a
                // joint has the name (Menagerie's Kinova names its actuators after their joints).
                let taken = links.iter().any(|l| l.name == input) || joints.iter().any(|j| j.name == input);
                let element = if taken {
                    format!("{input}-actuator")
                } else {
                    input.to_string()
                };
                let gear = law.gear;
                let held = |f: Function, [lo, hi]: [f64; 2]| {
                    if lo.is_finite() || hi.is_finite() {
                        f.range(lo, hi)
                    } else {
                        f
                    }
                };
                model = model.force(match (j.kind, law.servo()) {
                    // A motor: the force is gear × the input, held within both ranges (its gain is 1).
                    (Kind::Revolute, false) if law.gain == 1.0 => force(&element, "torque")
                        .set("joint", j.name.as_str())
                        .set("value", held(Function::input(input).gain(gear), law.motor_range())),
                    // Along a slide: a servo with no gains, its added force the same.
                    (Kind::Prismatic, false) if law.gain == 1.0 => force(&element, "servo")
                        .set("joint", j.name.as_str())
                        .set("value", held(Function::input(input).gain(gear), law.motor_range())),
                    (Kind::Revolute | Kind::Prismatic, _) => {
                        // τ = gear clamp(g ū + b₁ gear θ + b₂ gear θ̇, forcerange), ū the control
                        // held in ctrlrange: a servo with k = −b₁ gear², c = −b₂ gear², the
                        // target g ū / (−b₁ gear) (or, with b₁ = 0, the torque gear g ū) and
                        // the range gear × forcerange (on a slide θ is the displacement, τ a force).
                        let [_, b1, b2] = law.bias;
                        let mut range = law.force_range.map(|r| r * gear);
                        if range[0] > range[1] {
                            range.swap(0, 1);
                        }
                        let control = |gain: f64| held(Function::input(input).gain(gain), law.ctrl_range);
                        let mut servo = force(&element, "servo")
                            .set("joint", j.name.as_str())
                            .set("stiffness", -b1 * gear * gear)
                            .set("damping", -b2 * gear * gear);
                        servo = if b1 != 0.0 {
                            servo.set("target", control(law.gain / (-b1 * gear)))
                        } else {
                            servo.set("value", control(law.gain * gear))
                        };
                        if range[0].is_finite() || range[1].is_finite() {
                            servo = servo.set("range", range);
                        }
                        servo
                    }
                    _ => {
                        return Err(self.err(
                            c,
                            format!("<{tag}> on joint '{target}': actuators act on hinge and slide joints"),
                        ))
                    }
                });
                places.insert(input.to_string(), c);
            }
        }
        if !damped_extras.is_empty() {
            self.notes.push(format!(
                "the cone limits of ball joints are not modelled yet; the model leaves out those of {}",
                quoted(&damped_extras)
            ));
        }
        for s in &self.skipped {
            self.notes
                .push(format!("skipped {s}: not an element of the dynamics this reader reads"));
        }
        Ok((model, places, self.notes))
    }

    /// Reads the bodies under `parent` (link `parent_link`) into `parts` and `joints`.
    #[allow(clippy::too_many_arguments)]
    fn bodies(
        &mut self,
        parent: Node<'a, 'a>,
        parent_link: usize,
        parts: &mut Vec<Part<'a>>,
        joints: &mut Vec<TreeJoint>,
        names: &mut HashMap<String, usize>,
        places: &mut HashMap<String, Node<'a, 'a>>,
        limited: &mut Vec<String>,
    ) -> Result<(), SceneError> {
        for c in parent.children().filter(Node::is_element) {
            let tag = c.tag_name().name();
            match tag {
                "body" => {}
                "inertial" | "joint" | "freejoint" | "geom" if parent_link != 0 => continue,
                "geom" => {
                    self.skip("geoms of the world (floors: contacts are not modelled)".into());
                    continue;
                }
                "site" | "camera" | "light" => {
                    self.skip(format!("<{tag}>"));
                    continue;
                }
                other => {
                    return Err(self.err(
                        c,
                        format!(
                            "<{other}> in <{}> is outside the MJCF subset this reader reads",
                            parent.tag_name().name()
                        ),
                    ))
                }
            }
            let known = [&FRAME_KEYS[..], &["name", "childclass"]].concat();
            self.attributes(c, &known, &[])?;
            let index = parts.len();
            let name = c.attribute("name").map_or_else(|| format!("body{index}"), String::from);
            if names.insert(name.clone(), index).is_some() {
                return Err(self.err(c, format!("a second body named '{name}'")));
            }
            let pose = self.frame(c)?;
            let js: Vec<Node<'a, 'a>> = c
                .children()
                .filter(|n| n.has_tag_name("joint") || n.has_tag_name("freejoint"))
                .collect();
            if js.len() > 1 {
                return Err(self.err(
                    js[1],
                    format!(
                        "body '{name}' has {} joints: one joint per body is read (nest a body per joint)",
                        js.len()
                    ),
                ));
            }
            let mut kind = Kind::Fixed;
            let (mut offset, mut axis, mut damping, mut joint_name) = (V3::zeros(), V3::z(), 0.0, name.clone());
            let (mut stiffness, mut spring_rest, mut friction) = (0.0, 0.0, 0.0);
            let mut range = None;
            let mut file_name = name.clone();
            if let Some(&j) = js.first() {
                if j.has_tag_name("freejoint") {
                    kind = Kind::Floating;
                } else {
                    self.attributes(
                        j,
                        &[
                            "name",
                            "type",
                            "pos",
                            "axis",
                            "damping",
                            "stiffness",
                            "armature",
                            "frictionloss",
                            "springref",
                            "ref",
                            "class",
                            "range",
                            "limited",
                        ],
                        &[
                            "margin",
                            "solreflimit",
                            "solimplimit",
                            "solreffriction",
                            "solimpfriction",
                            "group",
                            "user",
                            "actuatorfrcrange",
                            "actuatorfrclimited",
                        ],
                    )?;
                    // Dry friction on the joint: a constant friction torque or force (exact here,
                    // where MuJoCo's is soft).
                    friction = self.number(j, "frictionloss", 0.0)?;
                    if friction.is_nan()
                        || friction < 0.0
                        || (friction > 0.0 && !matches!(self.value(j, "type").unwrap_or("hinge"), "hinge" | "slide"))
                    {
                        return Err(self.err(
                            j,
                            format!(
                                "<joint> frictionloss=\"{friction}\": non-negative, and on hinge and slide joints only"
                            ),
                        ));
                    }
                    for key in ["armature", "ref"] {
                        let v = self.number(j, key, 0.0)?;
                        if v != 0.0 {
                            return Err(
                                self.err(j, format!("<joint> {key}=\"{v}\" is not modelled yet (it must be 0)"))
                            );
                        }
                    }
                    kind = match self.value(j, "type").unwrap_or("hinge") {
                        "hinge" => Kind::Revolute,
                        "slide" => Kind::Prismatic,
                        "ball" => Kind::Spherical,
                        "free" => Kind::Floating,
                        other => {
                            return Err(self.err(
                                j,
                                format!("<joint type=\"{other}\">: expected hinge, slide, ball or free"),
                            ))
                        }
                    };
                    offset = self.numbers::<3>(j, "pos")?.map_or(V3::zeros(), V3::from);
                    axis = self.numbers::<3>(j, "axis")?.map_or(V3::z(), V3::from);
                    if axis.norm() < 1e-12 {
                        return Err(self.err(j, "<joint> axis is zero"));
                    }
                    damping = self.number(j, "damping", 0.0)?;
                    if damping < 0.0 || (damping > 0.0 && kind == Kind::Spherical) {
                        return Err(self.err(
                            j,
                            format!("<joint> damping=\"{damping}\": non-negative, and on hinge and slide joints only"),
                        ));
                    }
                    // A spring on the joint: −stiffness (q − springref), MuJoCo's passive force
                    // (springref in degrees on a hinge where the compiler's angles are).
                    stiffness = self.number(j, "stiffness", 0.0)?;
                    spring_rest = self.number(j, "springref", 0.0)?;
                    if stiffness < 0.0 || (stiffness > 0.0 && kind == Kind::Spherical) {
                        return Err(self.err(
                            j,
                            format!(
                                "<joint> stiffness=\"{stiffness}\": non-negative, and on hinge and slide joints only"
                            ),
                        ));
                    }
                    if kind == Kind::Revolute {
                        spring_rest = self.angle(spring_rest);
                    }
                    if let Some(n) = j.attribute("name") {
                        file_name = n.to_string();
                        joint_name = n.to_string();
                    } else {
                        joint_name = format!("{name}-joint");
                    }
                    match self.limited_range(j, "range", "limited")? {
                        Some(_) if kind == Kind::Spherical => limited.push(joint_name.clone()),
                        Some([lo, hi]) if kind == Kind::Revolute => range = Some([self.angle(lo), self.angle(hi)]),
                        Some(bounds) if kind == Kind::Prismatic => range = Some(bounds),
                        _ => {}
                    }
                }
            }
            if names.contains_key(&joint_name) && kind != Kind::Fixed && kind != Kind::Floating {
                joint_name = format!("{joint_name}-joint");
            }
            let limits = match range {
                Some([lo, hi]) => match super::tree::stops(&joint_name, lo, hi) {
                    Ok(bounds) => Some(bounds),
                    Err(note) => {
                        self.notes.push(note);
                        None
                    }
                },
                None => None,
            };
            let mut inertial = self.body_inertial(c)?;
            if let Some(i) = inertial.as_mut() {
                i.frame.p -= offset;
            }
            // The link's frame is the body's moved to its joint; the body's pose was given in its
            // parent body's frame, which is its parent link's moved by that link's offset.
            let origin = Pose {
                p: pose.p - parts[parent_link].offset + pose.r * offset,
                r: pose.r,
            };
            places.insert(name.clone(), c);
            parts.push(Part {
                link: Link {
                    name,
                    node: c,
                    inertial,
                    visuals: self.geom_visuals(c, offset)?,
                },
                offset,
            });
            joints.push(TreeJoint {
                file_name,
                name: joint_name.clone(),
                kind,
                parent: parent_link,
                child: index,
                origin,
                axis: axis.normalize(),
                damping,
                stiffness,
                spring_rest,
                friction,
                limits,
            });
            if let Some(&j) = js.first() {
                places.insert(joint_name, j);
            }
            self.bodies(c, index, parts, joints, names, places, limited)?;
        }
        Ok(())
    }
}
