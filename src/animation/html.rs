//! The HTML page: the drawing and the frames as inlined data, the viewer script and its style.

use super::{Drawing, Frames, LoadedMeshes};
use serde::Serialize;
use std::fmt;

/// The viewer script and page, inlined into every file (no network access needed to open it).
const TEMPLATE: &str = include_str!("viewer.html");
const SCRIPT: &str = include_str!("viewer.js");

/// The 3D viewer's page and script (spatial scenes), and three.js, inlined likewise: the
/// single-file ES module build `three.module.min.js` of the npm package `three` 0.159.0 (MIT
/// licence, `src/animation/THREE-LICENSE`), the last release that ships one file (later releases
/// split the library across modules that would need a bundler to inline).
const TEMPLATE_3D: &str = include_str!("viewer3d.html");
const SCRIPT_3D: &str = include_str!("viewer3d.js");
const THREE: &str = include_str!("three.module.min.js");

/// Frames kept by default: 60 frames per second over 40 s of playback at 1×, more than a screen
/// can show for shorter runs, and a page that opens quickly for any run length.
pub const DEFAULT_MAX_FRAMES: usize = 2400;

/// A point of a body whose path the viewer draws.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trace {
    /// Index of the body.
    pub body: usize,
    /// The point in the body's frame (`[x, y]`, or `[x, y, z]` in a spatial scene).
    pub point: Vec<f64>,
    /// Label, `body:x,y` (`body:x,y,z`).
    pub label: String,
}

/// A trace specification that does not name a body point of the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceError(pub String);

impl fmt::Display for TraceError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for TraceError {}

impl Trace {
    /// Parses `BODY:X,Y` (a point at local coordinates `X, Y` of body `BODY`, metres), e.g.
    /// `coupler:0.5,0`; `BODY:X,Y,Z` in a spatial scene. Errors name the specification and say
    /// what is wrong.
    pub fn parse(spec: &str, drawing: &Drawing) -> Result<Trace, TraceError> {
        let spatial = drawing.spatial.is_some();
        let form = if spatial { "X,Y,Z" } else { "X,Y" };
        let bad = |why: String| TraceError(format!("trace '{spec}': {why}"));
        let (name, point) = spec
            .rsplit_once(':')
            .ok_or_else(|| bad(format!("expected BODY:{form} (a point in the body's frame, metres)")))?;
        let body = drawing.body_index(name).ok_or_else(|| {
            bad(format!(
                "unknown body '{name}' (bodies: {})",
                drawing.body_names().join(", ")
            ))
        })?;
        let parts: Vec<&str> = point.split(',').collect();
        let count = if spatial { 3 } else { 2 };
        let what = if spatial { "three" } else { "two" };
        if parts.len() != count {
            return Err(bad(format!("'{point}' is not {what} numbers {form}")));
        }
        let parse = |s: &str| s.trim().parse::<f64>().ok().filter(|v| v.is_finite());
        let values: Option<Vec<f64>> = parts.iter().map(|p| parse(p)).collect();
        match values {
            Some(point) => Ok(Trace {
                body,
                point,
                label: spec.to_string(),
            }),
            None => Err(bad(format!("'{point}' is not {what} finite numbers {form}"))),
        }
    }
}

/// Builds the animation page of a scene.
#[derive(Debug, Clone)]
pub struct Viewer<'a> {
    title: &'a str,
    drawing: &'a Drawing,
    traces: Vec<Trace>,
    max_frames: usize,
    note: Option<String>,
    meshes: LoadedMeshes,
}

/// A mesh in the page: little-endian f32 corners and u32 triangles (empty: every three corners
/// are one), base64.
#[derive(Serialize)]
struct PageMesh {
    positions: String,
    indices: String,
}

#[derive(Serialize)]
struct Data<'a> {
    title: &'a str,
    drawing: &'a Drawing,
    traces: &'a [Trace],
    note: Option<&'a str>,
    meshes: Vec<PageMesh>,
    /// For each body and visual, the index of its mesh in `meshes`.
    mesh_of: &'a [Vec<Option<usize>>],
    /// For each of the ground's visuals, the index of its mesh.
    ground_mesh_of: &'a [Option<usize>],
    frames: usize,
    /// Times, little-endian f64, base64.
    times: String,
    /// Poses, little-endian f32, base64 (single precision is far below a pixel).
    poses: String,
    /// Joint reactions (`fx, fy, fz` per joint of a spatial drawing, per frame), little-endian
    /// f32, base64; empty when the frames have none.
    reactions: String,
}

impl<'a> Viewer<'a> {
    /// A viewer for `drawing`, titled `title`.
    pub fn new(title: &'a str, drawing: &'a Drawing) -> Self {
        Viewer {
            title,
            drawing,
            traces: Vec::new(),
            max_frames: DEFAULT_MAX_FRAMES,
            note: None,
            meshes: LoadedMeshes::default(),
        }
    }

    /// Draws the bodies' visual meshes, read by [`super::MeshSources::load`] (without them, a body
    /// whose visuals are all meshes is drawn as its box of inertia). Their notes join the page's.
    pub fn meshes(mut self, meshes: LoadedMeshes) -> Self {
        for n in &meshes.notes {
            self.note = Some(match self.note.take() {
                Some(before) => format!("{before}; {n}"),
                None => n.clone(),
            });
        }
        self.meshes = meshes;
        self
    }

    /// Draws the path of a body point.
    pub fn trace(mut self, trace: Trace) -> Self {
        self.traces.push(trace);
        self
    }

    /// Keeps at most `max` frames (default [`DEFAULT_MAX_FRAMES`]; see [`Frames::decimated`]).
    pub fn max_frames(mut self, max: usize) -> Self {
        self.max_frames = max;
        self
    }

    /// A line shown under the controls, e.g. where and why a run stopped (after any other).
    pub fn note(mut self, note: impl Into<String>) -> Self {
        let note = note.into();
        self.note = Some(match self.note.take() {
            Some(before) => format!("{before}; {note}"),
            None => note,
        });
        self
    }

    /// The complete page for `frames`.
    pub fn html(&self, frames: &Frames) -> String {
        let frames = frames.decimated(self.max_frames);
        let times: Vec<u8> = frames.times.iter().flat_map(|t| t.to_le_bytes()).collect();
        let poses: Vec<u8> = frames.poses.iter().flat_map(|p| (*p as f32).to_le_bytes()).collect();
        let reactions: Vec<u8> = frames
            .reactions
            .iter()
            .flat_map(|p| (*p as f32).to_le_bytes())
            .collect();
        let data = Data {
            title: self.title,
            drawing: self.drawing,
            traces: &self.traces,
            note: self.note.as_deref(),
            meshes: self
                .meshes
                .meshes
                .iter()
                .map(|m| PageMesh {
                    positions: base64(&m.positions.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()),
                    indices: base64(&m.indices.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()),
                })
                .collect(),
            mesh_of: &self.meshes.of,
            ground_mesh_of: &self.meshes.ground,
            frames: frames.len(),
            times: base64(&times),
            poses: base64(&poses),
            reactions: base64(&reactions),
        };
        // Serializing plain data to a string cannot fail; `</` is escaped so that no name can end
        // the script element.
        let json = serde_json::to_string(&data)
            .unwrap_or_else(|_| "{}".into())
            .replace("</", "<\\/");
        let (template, script) = match self.drawing.spatial {
            Some(_) => (TEMPLATE_3D, SCRIPT_3D),
            None => (TEMPLATE, SCRIPT),
        };
        // The data goes in last: no text of the user's can hold a placeholder that is replaced.
        template
            .replace("{{title}}", &escape_html(self.title))
            .replace("{{three}}", THREE)
            .replace("{{script}}", script)
            .replace("{{data}}", &json)
    }
}

fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('{', "&#123;")
}

/// Standard base64 (RFC 4648) with padding.
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_test_vectors() {
        // RFC 4648 §10.
        for (plain, encoded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), encoded);
        }
    }

    #[test]
    fn names_cannot_close_the_script_element() {
        let drawing = Drawing::default();
        let page = Viewer::new("a</script><script>alert(1)", &drawing).html(&Frames::new(0));
        assert_eq!(
            page.matches("</script>").count(),
            2,
            "the data and the viewer script only"
        );
        assert!(page.contains("<title>a&lt;/script&gt;"));
    }
}
