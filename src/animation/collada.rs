//! COLLADA (`.dae`) meshes for the 3D viewer, the subset robot descriptions use: the triangles of
//! each `<geometry>`'s `<mesh>` (`<triangles>`, `<polylist>`, `<polygons>`; lines are passed over),
//! placed by the `<node>` transforms of the document's visual scene (`<matrix>`, `<translate>`,
//! `<rotate>`, `<scale>`), in metres by `<unit meter>`, and turned to z up by `<up_axis>`. The
//! document is parsed as every model file is (no DTD, bounded; `scene/xml.rs`).

use super::mesh::Mesh;
use nalgebra::{Matrix4, Rotation3, Unit, Vector3, Vector4};
use roxmltree::Node;
use std::collections::HashMap;

/// The triangles of a COLLADA document, every geometry its visual scene instances placed there.
pub(crate) fn dae(bytes: &[u8]) -> Result<Mesh, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "not text: a COLLADA file is XML")?;
    let doc = crate::scene::parse_xml(text, "mesh").map_err(|e| e.message)?;
    let root = doc.root_element();
    if root.tag_name().name() != "COLLADA" {
        return Err(format!(
            "the root element is <{}>; a COLLADA file's is <COLLADA>",
            root.tag_name().name()
        ));
    }
    let asset = child(root, "asset");
    let meter = match asset.and_then(|a| child(a, "unit")).and_then(|u| u.attribute("meter")) {
        Some(m) => m
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|m| m.is_finite() && *m > 0.0)
            .ok_or_else(|| format!("<unit meter=\"{m}\"> is not a positive number"))?,
        None => 1.0,
    };
    let up = asset
        .and_then(|a| child(a, "up_axis"))
        .and_then(|u| u.text())
        .unwrap_or("Y_UP")
        .trim();
    // To z up: COLLADA's default is y up (a turn of +90° about x takes y to z); x up turns about y.
    let to_z_up = match up {
        "Z_UP" => Matrix4::identity(),
        "Y_UP" => Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::FRAC_PI_2).to_homogeneous(),
        "X_UP" => Rotation3::from_axis_angle(&Vector3::y_axis(), -std::f64::consts::FRAC_PI_2).to_homogeneous(),
        other => return Err(format!("<up_axis> is '{other}', not X_UP, Y_UP or Z_UP")),
    };
    let base = to_z_up * Matrix4::new_scaling(meter);
    let geometries: HashMap<&str, Node> = root
        .descendants()
        .filter(|n| n.has_tag_name("geometry"))
        .filter_map(|g| Some((g.attribute("id")?, g)))
        .collect();
    let mut out = Mesh::default();
    let scene = root
        .descendants()
        .find(|n| n.has_tag_name("instance_visual_scene"))
        .and_then(|i| i.attribute("url"))
        .and_then(|u| u.strip_prefix('#'))
        .and_then(|id| {
            root.descendants()
                .find(|n| n.has_tag_name("visual_scene") && n.attribute("id") == Some(id))
        })
        .or_else(|| root.descendants().find(|n| n.has_tag_name("visual_scene")));
    match scene {
        Some(s) => {
            for node in s.children().filter(|n| n.has_tag_name("node")) {
                walk(node, &base, &geometries, &mut out, 0)?;
            }
        }
        None => {
            for g in geometries.values() {
                add_geometry(*g, &base, &mut out)?;
            }
        }
    }
    if out.indices.is_empty() {
        return Err("no triangles".into());
    }
    Ok(out)
}

fn child<'a, 'i>(n: Node<'a, 'i>, tag: &str) -> Option<Node<'a, 'i>> {
    n.children().find(|c| c.has_tag_name(tag))
}

fn numbers<T: std::str::FromStr>(n: Node<'_, '_>) -> Result<Vec<T>, String> {
    n.text()
        .unwrap_or("")
        .split_ascii_whitespace()
        .map(|w| {
            w.parse::<T>()
                .map_err(|_| format!("<{}> holds '{w}', not a number", n.tag_name().name()))
        })
        .collect()
}

/// Nodes nest at most this deep (a document nesting deeper is refused, not recursed into).
const MAX_DEPTH: usize = 64;

fn walk(
    node: Node<'_, '_>,
    parent: &Matrix4<f64>,
    geometries: &HashMap<&str, Node<'_, '_>>,
    out: &mut Mesh,
    depth: usize,
) -> Result<(), String> {
    if depth > MAX_DEPTH {
        return Err(format!("<node> elements nest more than {MAX_DEPTH} deep"));
    }
    let mut m = *parent;
    for c in node.children().filter(Node::is_element) {
        let v: Vec<f64> = match c.tag_name().name() {
            "matrix" | "translate" | "rotate" | "scale" => numbers(c)?,
            _ => continue,
        };
        let need = match c.tag_name().name() {
            "matrix" => 16,
            "rotate" => 4,
            _ => 3,
        };
        if v.len() != need || v.iter().any(|x| !x.is_finite()) {
            return Err(format!("<{}> needs {need} finite numbers", c.tag_name().name()));
        }
        m *= match c.tag_name().name() {
            "matrix" => Matrix4::from_row_slice(&v),
            "translate" => Matrix4::new_translation(&Vector3::new(v[0], v[1], v[2])),
            "scale" => Matrix4::new_nonuniform_scaling(&Vector3::new(v[0], v[1], v[2])),
            _ => match Unit::try_new(Vector3::new(v[0], v[1], v[2]), 1e-12) {
                Some(axis) => Rotation3::from_axis_angle(&axis, v[3].to_radians()).to_homogeneous(),
                None => Matrix4::identity(),
            },
        };
    }
    for c in node.children().filter(Node::is_element) {
        match c.tag_name().name() {
            "instance_geometry" => {
                let url = c.attribute("url").unwrap_or("");
                let g = url
                    .strip_prefix('#')
                    .and_then(|id| geometries.get(id))
                    .ok_or_else(|| format!("<instance_geometry url=\"{url}\"> names no geometry of the file"))?;
                add_geometry(*g, &m, out)?;
            }
            "node" => walk(c, &m, geometries, out, depth + 1)?,
            _ => {}
        }
    }
    Ok(())
}

/// Appends the triangles of `geometry`'s mesh, placed by `m`.
fn add_geometry(geometry: Node<'_, '_>, m: &Matrix4<f64>, out: &mut Mesh) -> Result<(), String> {
    let Some(mesh) = child(geometry, "mesh") else {
        return Ok(()); // splines and convex meshes carry no triangles
    };
    let id = geometry.attribute("id").unwrap_or("?");
    let sources: HashMap<&str, Node> = mesh
        .children()
        .filter(|n| n.has_tag_name("source"))
        .filter_map(|s| Some((s.attribute("id")?, s)))
        .collect();
    // <vertices id> → its POSITION source.
    let vertices: HashMap<&str, &str> = mesh
        .children()
        .filter(|n| n.has_tag_name("vertices"))
        .filter_map(|v| {
            let input = v
                .children()
                .find(|i| i.has_tag_name("input") && i.attribute("semantic") == Some("POSITION"))?;
            Some((v.attribute("id")?, input.attribute("source")?.strip_prefix('#')?))
        })
        .collect();
    let mut placed: HashMap<&str, u32> = HashMap::new();
    for prim in mesh.children().filter(Node::is_element) {
        let kind = prim.tag_name().name();
        if !matches!(kind, "triangles" | "polylist" | "polygons") {
            continue;
        }
        let inputs: Vec<Node> = prim.children().filter(|n| n.has_tag_name("input")).collect();
        let offset = |i: &Node| i.attribute("offset").and_then(|o| o.parse::<usize>().ok()).unwrap_or(0);
        let stride = inputs.iter().map(|i| offset(i) + 1).max().unwrap_or(1);
        let vertex = inputs
            .iter()
            .find(|i| i.attribute("semantic") == Some("VERTEX"))
            .ok_or_else(|| format!("geometry '{id}': <{kind}> has no VERTEX input"))?;
        let source_id = vertex
            .attribute("source")
            .and_then(|s| s.strip_prefix('#'))
            .and_then(|v| vertices.get(v))
            .ok_or_else(|| format!("geometry '{id}': its VERTEX input names no <vertices> of the mesh"))?;
        let first = match placed.get(source_id) {
            Some(&f) => f,
            None => {
                let s = sources
                    .get(source_id)
                    .ok_or_else(|| format!("geometry '{id}': no <source id=\"{source_id}\">"))?;
                let f = (out.positions.len() / 3) as u32;
                add_positions(*s, m, out).map_err(|e| format!("geometry '{id}': {e}"))?;
                placed.insert(source_id, f);
                f
            }
        };
        let count = out.positions.len() / 3 - first as usize;
        let corner = |p: &[u32], k: usize| -> Result<u32, String> {
            let i = *p
                .get(k * stride + offset(vertex))
                .ok_or(format!("geometry '{id}': <p> is short"))?;
            if (i as usize) < count {
                Ok(first + i)
            } else {
                Err(format!("geometry '{id}': <p> names vertex {i} of {count}"))
            }
        };
        let mut fan = |p: &[u32], start: usize, n: usize| -> Result<(), String> {
            let c0 = corner(p, start)?;
            for k in 1..n.saturating_sub(1) {
                out.indices
                    .extend([c0, corner(p, start + k)?, corner(p, start + k + 1)?]);
            }
            Ok(())
        };
        match kind {
            "triangles" => {
                let p: Vec<u32> = child(prim, "p").map(numbers).transpose()?.unwrap_or_default();
                for t in 0..p.len() / (3 * stride) {
                    fan(&p, 3 * t, 3)?;
                }
            }
            "polylist" => {
                let p: Vec<u32> = child(prim, "p").map(numbers).transpose()?.unwrap_or_default();
                let counts: Vec<usize> = child(prim, "vcount").map(numbers).transpose()?.unwrap_or_default();
                let mut start = 0;
                for n in counts {
                    fan(&p, start, n)?;
                    start += n;
                }
            }
            _ => {
                for polygon in prim.children().filter(|n| n.has_tag_name("p")) {
                    let p: Vec<u32> = numbers(polygon)?;
                    fan(&p, 0, p.len() / stride)?;
                }
            }
        }
    }
    Ok(())
}

/// Appends the points of a `<source>` (its accessor's first three values of each element),
/// placed by `m`.
fn add_positions(source: Node<'_, '_>, m: &Matrix4<f64>, out: &mut Mesh) -> Result<(), String> {
    let values: Vec<f64> = child(source, "float_array")
        .map(numbers)
        .transpose()?
        .unwrap_or_default();
    let accessor = source.descendants().find(|n| n.has_tag_name("accessor"));
    let stride = accessor
        .and_then(|a| a.attribute("stride"))
        .and_then(|s| s.parse::<usize>().ok())
        .unwrap_or(3);
    if stride < 3 {
        return Err(format!("positions with stride {stride}: three coordinates are needed"));
    }
    for p in values.chunks_exact(stride) {
        let w = m * Vector4::new(p[0], p[1], p[2], 1.0);
        if !(w.x.is_finite() && w.y.is_finite() && w.z.is_finite()) {
            return Err("a position is not a finite number".into());
        }
        out.positions.extend([w.x as f32, w.y as f32, w.z as f32]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::dae;

    /// One triangle in centimetres, y up, in a node moved 1 unit along x: corner (1, 2, 0) cm
    /// becomes ((1 + 1) cm, 0, 2 cm) with z up: the unit, the node's move and the turn to z up
    /// each show in the numbers.
    #[test]
    fn a_triangle_is_placed_by_its_node_in_metres_with_z_up() {
        let doc = r##"<?xml version="1.0"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit meter="0.01"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="g-pos"><float_array id="a" count="9">0 0 0 1 2 0 0 0 3</float_array>
      <technique_common><accessor source="#a" count="3" stride="3"/></technique_common></source>
    <vertices id="g-v"><input semantic="POSITION" source="#g-pos"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#g-v" offset="0"/><input semantic="NORMAL" source="#n" offset="1"/>
      <p>0 0 1 0 2 0</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node><translate>1 0 0</translate>
    <instance_geometry url="#g"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>"##;
        let mesh = dae(doc.as_bytes()).unwrap();
        let expect = [0.01, 0.0, 0.0, 0.02, 0.0, 0.02, 0.01, -0.03, 0.0];
        for (a, b) in mesh.positions.iter().zip(expect) {
            assert!((f64::from(*a) - b).abs() < 1e-7, "{:?}", mesh.positions);
        }
        assert_eq!(mesh.indices, [0, 1, 2]);
        assert!(dae(b"<robot/>").unwrap_err().contains("COLLADA"));
    }
}
