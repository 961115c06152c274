//! The mesh assets of an MJCF file, for the 3D viewer (`docs/import.md`, "MJCF"): `<asset>`
//! `<mesh name file scale>` with `compiler meshdir` (else `assetdir`). A mesh geom in a body with
//! an `<inertial>` is drawn from its file by the viewer, which reads meshes only inside the
//! model's folder ([`crate::animation::MeshSources`]); its vertices are drawn in the geom's frame
//! as the file gives them (MuJoCo moves a mesh to its centre of mass and the geom's frame by the
//! same offset, which cancels in the drawing).

use super::Reader;
use crate::scene::SceneError;
use roxmltree::Node;

/// A mesh asset: the file (with the mesh folder) and its scale.
#[derive(Debug, Clone)]
pub(super) struct MeshAsset {
    pub file: String,
    pub scale: [f64; 3],
}

impl<'a> Reader<'_, 'a> {
    /// Reads `<asset>`'s meshes; the other assets (materials, textures) carry no dynamics and are
    /// skipped with a note.
    pub(super) fn assets(&mut self, node: Node<'a, 'a>) -> Result<(), SceneError> {
        for c in node.children().filter(Node::is_element) {
            if c.tag_name().name() != "mesh" {
                self.skip(format!("<asset> <{}>", c.tag_name().name()));
                continue;
            }
            self.attributes(c, &["name", "file", "scale", "class"], &["content_type", "maxhullvert"])?;
            let file = self.src.required(c, "file")?;
            let name = match c.attribute("name") {
                Some(n) => n.to_string(),
                None => std::path::Path::new(file)
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or(file)
                    .to_string(),
            };
            let scale = self.numbers::<3>(c, "scale")?.unwrap_or([1.0; 3]);
            if scale.iter().any(|s| !s.is_finite() || *s == 0.0) {
                return Err(self.err(c, "<mesh> scale must be three finite non-zero numbers"));
            }
            let file = match self.mesh_folder.as_deref() {
                Some(dir) if !dir.is_empty() && !std::path::Path::new(file).is_absolute() => {
                    format!("{}/{file}", dir.trim_end_matches('/'))
                }
                _ => file.to_string(),
            };
            if self.meshes.insert(name.clone(), MeshAsset { file, scale }).is_some() {
                return Err(self.err(c, format!("<mesh> name '{name}' is used twice")));
            }
        }
        Ok(())
    }
}
