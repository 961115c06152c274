//! Triangle meshes for the 3D viewer, read from STL (binary or ASCII) and Wavefront OBJ files;
//! COLLADA is in `collada.rs`. Only the triangles' corners are read (normals, textures and
//! materials are not: the viewer shades each face flat in its body's colour). Each reader checks
//! that the content is what the file's extension says (`docs/import.md`, "Meshes").

/// A triangle mesh in its file's units and axes: corner positions and, when the file shares
/// corners between triangles, the triangles as index triples (empty: every three positions are
/// one triangle).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// `x, y, z` of each corner.
    pub positions: Vec<f32>,
    /// Three corner indices per triangle, or empty.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// The number of triangles.
    pub fn triangles(&self) -> usize {
        if self.indices.is_empty() {
            self.positions.len() / 9
        } else {
            self.indices.len() / 3
        }
    }
}

/// An STL file: binary (80-byte header, triangle count, 50 bytes per triangle, the file's length
/// exactly that) or ASCII (`solid`, then `vertex x y z` three per `facet`).
pub(crate) fn stl(bytes: &[u8]) -> Result<Mesh, String> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            let mut positions = Vec::with_capacity(9 * n);
            for t in 0..n {
                let facet = &bytes[84 + 50 * t..];
                for k in 0..9 {
                    let o = 12 + 4 * k;
                    let v = f32::from_le_bytes([facet[o], facet[o + 1], facet[o + 2], facet[o + 3]]);
                    if !v.is_finite() {
                        return Err(format!("triangle {} has a corner that is not a finite number", t + 1));
                    }
                    positions.push(v);
                }
            }
            return Ok(Mesh {
                positions,
                indices: Vec::new(),
            });
        }
    }
    let text = std::str::from_utf8(bytes)
        .ok()
        .filter(|t| t.trim_start().starts_with("solid"))
        .ok_or("neither a binary STL (its length is not 84 + 50 × its triangle count) nor an ASCII one (`solid …`)")?;
    let mut positions = Vec::new();
    let mut words = text.split_ascii_whitespace();
    while let Some(w) = words.next() {
        if w == "vertex" {
            for _ in 0..3 {
                let v = words
                    .next()
                    .and_then(|s| s.parse::<f32>().ok())
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("vertex {} is not three finite numbers", positions.len() / 3 + 1))?;
                positions.push(v);
            }
        }
    }
    if positions.is_empty() || positions.len() % 9 != 0 {
        return Err(format!(
            "an ASCII STL with {} vertices: not three per facet",
            positions.len() / 3
        ));
    }
    Ok(Mesh {
        positions,
        indices: Vec::new(),
    })
}

/// A Wavefront OBJ file: `v x y z [w]` corners and `f` faces (`i`, `i/t`, `i//n`, `i/t/n`,
/// negative indices counting back), each face a fan of triangles. Other statements (normals,
/// texture coordinates, groups, materials) are passed over; a line that is none of them is
/// refused, so that a file that is not an OBJ is not read as one.
pub(crate) fn obj(bytes: &[u8]) -> Result<Mesh, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "not text: an OBJ file is text")?;
    let mut mesh = Mesh::default();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        let at = |why: &str| format!("line {}: {why}", n + 1);
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            None => {}
            Some(w) if w.starts_with('#') => {}
            Some("v") => {
                let xyz: Vec<f32> = words.take(3).filter_map(|s| s.parse::<f32>().ok()).collect();
                if xyz.len() != 3 || xyz.iter().any(|v| !v.is_finite()) {
                    return Err(at("a vertex needs three finite numbers"));
                }
                mesh.positions.extend(xyz);
            }
            Some("f") => {
                let count = mesh.positions.len() / 3;
                let corners: Vec<u32> = words
                    .map(|c| {
                        let i: i64 = c.split('/').next().and_then(|s| s.parse().ok()).unwrap_or(0);
                        let index = if i < 0 { count as i64 + i } else { i - 1 };
                        u32::try_from(index).ok().filter(|&k| (k as usize) < count)
                    })
                    .collect::<Option<_>>()
                    .ok_or_else(|| at("a face names a vertex the file has not given"))?;
                if corners.len() < 3 {
                    return Err(at("a face needs three vertices"));
                }
                for k in 1..corners.len() - 1 {
                    mesh.indices.extend([corners[0], corners[k], corners[k + 1]]);
                }
            }
            Some("vn" | "vt" | "vp" | "o" | "g" | "s" | "usemtl" | "mtllib" | "l" | "p") => {}
            Some(other) => return Err(at(&format!("'{other}' is not an OBJ statement"))),
        }
    }
    if mesh.indices.is_empty() {
        return Err("no faces".into());
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A binary STL of one triangle and the same triangle in ASCII read to the same corners.
    #[test]
    fn binary_and_ascii_stl_read_the_same_triangle() {
        let corners = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.5];
        let mut binary = vec![b's'; 80]; // a header starting "solid", as some exporters write
        binary.extend(1u32.to_le_bytes());
        binary.extend([0u8; 12]);
        binary.extend(corners.iter().flat_map(|v| v.to_le_bytes()));
        binary.extend([0u8; 2]);
        let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 2 0.5\nendloop\nendfacet\nendsolid t\n";
        assert_eq!(stl(&binary).unwrap().positions, corners);
        assert_eq!(stl(ascii.as_bytes()).unwrap().positions, corners);
        assert_eq!(stl(ascii.as_bytes()).unwrap().triangles(), 1);
        // One byte short of the binary length, and not ASCII: refused.
        assert!(stl(&binary[..binary.len() - 1]).is_err());
        assert!(stl(b"root:x:0:0:root:/root:/bin/bash\n").is_err());
    }

    /// A quad face is two triangles of a fan; `i/t/n` and negative indices name the same corners.
    #[test]
    fn obj_faces_become_fans_of_triangles() {
        let text = "# square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\nf -4 -3 -2\n";
        let mesh = obj(text.as_bytes()).unwrap();
        assert_eq!(mesh.indices, [0, 1, 2, 0, 2, 3, 0, 1, 2]);
        assert_eq!(mesh.triangles(), 3);
        assert!(obj(b"v 0 0 0\nf 1 2 3\n").unwrap_err().contains("line 2"));
        assert!(obj(b"root:x:0:0:root:/root:/bin/bash\n").is_err());
    }
}
