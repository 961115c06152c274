//! A spatial body's `visual` key: the shapes it is drawn with (`docs/scenes.md`, "Visuals"), and
//! the same shapes as a reader of a robot description writes them.
//!
//! ```toml
//! visual = [
//!     { mesh = "meshes/link.stl", scale = [0.001, 0.001, 0.001] },
//!     { box = [0.1, 0.1, 0.4], position = [0, 0, 0.2], orientation = { axis = [0, 0, 1], angle = 0.5 } },
//! ]
//! ```

use super::spatial::{CylinderDef, OrientationDef};
use super::strict;
use crate::animation::{Solid, Visual};
use dalembert_spatial::euler_parameters;
use serde::Deserialize;

/// One entry of a body's `visual`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct VisualDef {
    pub sphere: Option<f64>,
    #[serde(rename = "box", default, deserialize_with = "strict::xyz_opt")]
    pub cuboid: Option<[f64; 3]>,
    pub cylinder: Option<CylinderDef>,
    pub mesh: Option<String>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub scale: Option<[f64; 3]>,
    #[serde(default, deserialize_with = "strict::xyz_opt")]
    pub position: Option<[f64; 3]>,
    pub orientation: Option<OrientationDef>,
    /// Where a reader found it (`ur5.urdf line 44`); a TOML scene's own are placed by their body.
    pub declared: Option<String>,
}

/// The visuals of a body, in the body's frame about its centre of mass: `center` is the centre of
/// mass from the point `position` names (the body's `center_of_mass`), `declared` where the body
/// is in the file.
pub(crate) fn visuals(defs: &[VisualDef], center: [f64; 3], declared: &str) -> Result<Vec<Visual>, String> {
    defs.iter()
        .enumerate()
        .map(|(k, d)| {
            let at = |m: String| format!("visual {}: {m}", k + 1);
            let positive = |what: &str, v: f64| {
                if v.is_finite() && v > 0.0 {
                    Ok(v)
                } else {
                    Err(at(format!("{what} must be positive and finite, got {v}")))
                }
            };
            let shape = match (d.sphere, d.cuboid, &d.cylinder, &d.mesh) {
                (Some(r), None, None, None) => Solid::Sphere {
                    radius: positive("the sphere's radius", r)?,
                },
                (None, Some(size), None, None) => {
                    for s in size {
                        positive("a side of the box", s)?;
                    }
                    Solid::Box { size }
                }
                (None, None, Some(c), None) => Solid::Cylinder {
                    radius: positive("the cylinder's radius", c.radius)?,
                    length: positive("the cylinder's length", c.length)?,
                },
                (None, None, None, Some(file)) => {
                    if file.trim().is_empty() {
                        return Err(at("mesh is an empty path".into()));
                    }
                    let scale = d.scale.unwrap_or([1.0; 3]);
                    if scale.iter().any(|s| !s.is_finite() || *s == 0.0) {
                        return Err(at(format!("scale must be three finite non-zero numbers, got {scale:?}")));
                    }
                    Solid::Mesh {
                        file: file.clone(),
                        scale,
                    }
                }
                _ => {
                    return Err(at(
                        "give exactly one of sphere = r, box = [a, b, c], cylinder = { radius = r, length = l }, mesh = \"file\"".into(),
                    ))
                }
            };
            if d.scale.is_some() && d.mesh.is_none() {
                return Err(at("scale applies to a mesh".into()));
            }
            let rotation = match &d.orientation {
                Some(o) => super::spatial::orientation(o).map_err(|m| at(format!("orientation: {m}")))?,
                None => euler_parameters::IDENTITY,
            };
            let p = d.position.unwrap_or_default();
            Ok(Visual {
                shape,
                position: [p[0] - center[0], p[1] - center[1], p[2] - center[2]],
                rotation,
                declared: d.declared.clone().unwrap_or_else(|| declared.to_string()),
            })
        })
        .collect()
}
