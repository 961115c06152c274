//! Where the 3D viewer may read mesh files from, and reading them. A model file is untrusted
//! input (`docs/import.md`, "Meshes"):
//!
//! - a mesh path resolves only inside the scene's folder, or inside the folder the user names for
//!   a `package://NAME/…` (no absolute path, no `..`, no symbolic link leading out), unless the
//!   user allows any path ([`MeshSources::any_path`]);
//! - only STL, OBJ and COLLADA files are read, each checked by its content;
//! - a file is at most [`MAX_MESH_BYTES`] and a page at most [`MAX_TRIANGLES`] triangles;
//! - nothing else from the disk goes into the page.

use super::collada::dae;
use super::mesh::{obj, stl, Mesh};
use super::{Solid, SpatialDrawing};
use std::collections::HashMap;
use std::fmt;
use std::path::{Component, Path, PathBuf};

/// The largest mesh file read (bytes): a robot link's mesh is a few MB.
pub const MAX_MESH_BYTES: u64 = 64 << 20;

/// The most triangles one page holds, over all its meshes.
pub const MAX_TRIANGLES: usize = 4_000_000;

/// The folders meshes may be read from.
#[derive(Debug, Clone, Default)]
pub struct MeshSources {
    folder: PathBuf,
    packages: Vec<(String, PathBuf)>,
    any_path: bool,
}

/// A mesh the page cannot draw: one line naming the body, the visual, where it is declared and
/// the cause.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshError(pub String);

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MeshError {}

/// The meshes of a drawing, read: each distinct file once.
#[derive(Debug, Clone, Default)]
pub struct LoadedMeshes {
    /// The meshes read.
    pub meshes: Vec<Mesh>,
    /// For each body and each of its visuals, the mesh drawn (`None`: a primitive, or a mesh of
    /// a package the user has not named).
    pub of: Vec<Vec<Option<usize>>>,
    /// The same for the ground's visuals.
    pub ground: Vec<Option<usize>>,
    /// What is not drawn, and why (a package not named), one line each.
    pub notes: Vec<String>,
}

impl MeshSources {
    /// Meshes of a scene in `folder` (the folder of the scene's file).
    pub fn new(folder: impl Into<PathBuf>) -> Self {
        MeshSources {
            folder: folder.into(),
            ..Self::default()
        }
    }

    /// Meshes of the scene whose file is `origin` (as [`crate::Scene::origin`] names it).
    pub fn of_scene(origin: &str) -> Self {
        Self::new(Path::new(origin).parent().unwrap_or(Path::new("")))
    }

    /// `package://name/…` resolves inside `folder`.
    pub fn package(mut self, name: impl Into<String>, folder: impl Into<PathBuf>) -> Self {
        self.packages.push((name.into(), folder.into()));
        self
    }

    /// Allows absolute paths and `..` (a model file the user trusts).
    pub fn any_path(mut self, allow: bool) -> Self {
        self.any_path = allow;
        self
    }

    /// The file `name` names (`None`: a package the user has not named).
    pub fn resolve(&self, name: &str) -> Result<Option<PathBuf>, String> {
        let (root, rest) = if let Some(p) = name.strip_prefix("package://") {
            let (package, rest) = p.split_once('/').unwrap_or((p, ""));
            match self.packages.iter().find(|(n, _)| n == package) {
                Some((_, folder)) => (folder.clone(), rest),
                None => return Ok(None),
            }
        } else if let Some(p) = name.strip_prefix("file://") {
            (PathBuf::new(), p)
        } else {
            (self.folder.clone(), name)
        };
        let path = Path::new(rest);
        let inside = path
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
        if !inside && !self.any_path {
            return Err(
                "the path leaves its folder (absolute, or with '..'): meshes are read inside the scene's folder or a named package only (a model you trust may be given any mesh path)"
                    .into(),
            );
        }
        let file = root.join(path);
        let real = file.canonicalize().map_err(|e| format!("cannot read it: {e}"))?;
        if !self.any_path {
            let base = root
                .canonicalize()
                .map_err(|e| format!("cannot read its folder {}: {e}", root.display()))?;
            if !real.starts_with(&base) {
                return Err(
                    "a symbolic link leads out of its folder (a model you trust may be given any mesh path)".into(),
                );
            }
        }
        Ok(Some(real))
    }

    /// Reads the meshes of `drawing`'s visuals.
    pub fn load(&self, drawing: &SpatialDrawing) -> Result<LoadedMeshes, MeshError> {
        let mut loaded = LoadedMeshes::default();
        let mut read: HashMap<PathBuf, usize> = HashMap::new();
        let mut triangles = 0;
        let mut unnamed: Vec<String> = Vec::new();
        let ground = ("ground".to_string(), drawing.ground.clone());
        let lists = drawing.bodies.iter().map(|b| (b.name.clone(), b.visuals.clone()));
        for (n, (name, visuals)) in lists.chain([ground]).enumerate() {
            let mut of = Vec::new();
            for (k, v) in visuals.iter().enumerate() {
                let Solid::Mesh { file, .. } = &v.shape else {
                    of.push(None);
                    continue;
                };
                let bad = |why: String| {
                    MeshError(format!(
                        "body '{}' visual {} ({}): mesh '{file}': {why}",
                        name,
                        k + 1,
                        v.declared
                    ))
                };
                let Some(path) = self.resolve(file).map_err(bad)? else {
                    let package = file.trim_start_matches("package://").split('/').next().unwrap_or("");
                    if !unnamed.iter().any(|p| p == package) {
                        unnamed.push(package.to_string());
                    }
                    of.push(None);
                    continue;
                };
                let index = match read.get(&path) {
                    Some(&i) => i,
                    None => {
                        let mesh = read_mesh(&path).map_err(bad)?;
                        triangles += mesh.triangles();
                        if triangles > MAX_TRIANGLES {
                            return Err(bad(format!(
                                "the page's meshes have more than {MAX_TRIANGLES} triangles"
                            )));
                        }
                        loaded.meshes.push(mesh);
                        read.insert(path, loaded.meshes.len() - 1);
                        loaded.meshes.len() - 1
                    }
                };
                of.push(Some(index));
            }
            if n < drawing.bodies.len() {
                loaded.of.push(of);
            } else {
                loaded.ground = of;
            }
        }
        for p in unnamed {
            loaded.notes.push(format!(
                "meshes of package '{p}' are not drawn (name its folder: --package {p}=DIR)"
            ));
        }
        Ok(loaded)
    }
}

/// Reads a mesh file by its extension, checking that its content is that format.
pub fn read_mesh(path: &Path) -> Result<Mesh, String> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let reader: fn(&[u8]) -> Result<Mesh, String> = match extension.as_str() {
        "stl" => stl,
        "obj" => obj,
        "dae" => dae,
        _ => return Err("not a mesh file the viewer reads (.stl, .obj, .dae)".into()),
    };
    let size = std::fs::metadata(path).map_err(|e| e.to_string())?.len();
    if size > MAX_MESH_BYTES {
        return Err(format!(
            "{size} bytes is more than a mesh file may hold ({MAX_MESH_BYTES})"
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    reader(&bytes).map_err(|e| format!("not a valid .{extension} file: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder of its own under the system's temporary folder, emptied first.
    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("dalembert-mesh-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("scene/meshes")).unwrap();
        std::fs::create_dir_all(dir.join("package/parts")).unwrap();
        std::fs::write(dir.join("scene/meshes/a.stl"), ascii_triangle()).unwrap();
        std::fs::write(dir.join("package/parts/b.stl"), ascii_triangle()).unwrap();
        std::fs::write(dir.join("outside.stl"), ascii_triangle()).unwrap();
        dir
    }

    fn ascii_triangle() -> &'static str {
        "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n"
    }

    /// One rule each: a relative path inside the scene's folder and a named package's file are
    /// read; an absolute path (`/etc/passwd`), a `..` escape and a symbolic link out of the folder
    /// are refused unless any path is allowed; a package not named is left undrawn.
    #[test]
    fn meshes_resolve_only_inside_the_scene_folder_or_a_named_package() {
        let dir = folder("resolve");
        let sources = MeshSources::new(dir.join("scene")).package("robot", dir.join("package"));
        assert!(sources
            .resolve("meshes/a.stl")
            .unwrap()
            .unwrap()
            .ends_with("scene/meshes/a.stl"));
        assert!(sources
            .resolve("package://robot/parts/b.stl")
            .unwrap()
            .unwrap()
            .ends_with("package/parts/b.stl"));
        assert_eq!(sources.resolve("package://other/parts/b.stl").unwrap(), None);
        for bad in [
            "/etc/passwd",
            "file:///etc/passwd",
            "../outside.stl",
            "package://robot/../outside.stl",
        ] {
            let e = sources.resolve(bad).unwrap_err();
            assert!(e.contains("leaves its folder"), "{bad}: {e}");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(dir.join("outside.stl"), dir.join("scene/meshes/link.stl")).unwrap();
            let e = sources.resolve("meshes/link.stl").unwrap_err();
            assert!(e.contains("symbolic link"), "{e}");
            assert!(sources.clone().any_path(true).resolve("meshes/link.stl").is_ok());
        }
        let trusted = sources.any_path(true);
        assert!(trusted.resolve("../outside.stl").unwrap().is_some());
        assert!(trusted
            .resolve(dir.join("outside.stl").to_str().unwrap())
            .unwrap()
            .is_some());
        assert!(trusted
            .resolve("meshes/missing.stl")
            .unwrap_err()
            .contains("cannot read"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Only mesh formats are read, each checked by its content: a text file named `.stl` or
    /// `.dae` is refused, as is any other extension.
    #[test]
    fn only_mesh_files_are_read_and_their_content_is_checked() {
        let dir = folder("content");
        let text = dir.join("scene/passwd");
        std::fs::write(&text, "root:x:0:0:root:/root:/bin/bash\n").unwrap();
        assert!(read_mesh(&text).unwrap_err().contains("not a mesh file"));
        for name in ["fake.stl", "fake.obj", "fake.dae"] {
            let fake = dir.join("scene").join(name);
            std::fs::copy(&text, &fake).unwrap();
            assert!(read_mesh(&fake).unwrap_err().contains("not a valid"), "{name}");
        }
        assert_eq!(read_mesh(&dir.join("scene/meshes/a.stl")).unwrap().triangles(), 1);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
