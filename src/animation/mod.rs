//! A self-contained HTML animation of a run: one file that plays the motion in any browser, with
//! no network access (every script and style is inlined).
//!
//! The page draws each body from its shape and attachment points (rods as bars, disks as circles,
//! sliders as blocks, point masses as dots), joints as pins, ground pivots and guides, massless
//! links and springs (zig-zag); it has play/pause, a time slider, a speed control and the time, an
//! optional trace of chosen body points, and fits the view to the motion's bounding box. Opening it
//! with `#t=1.5` in the address shows that instant, paused.
//!
//! ```
//! use dalembert::animation::{Frames, Trace, Viewer};
//! use dalembert::Scene;
//!
//! let scene = Scene::from_toml(include_str!("../../scenes/pendulum.toml"), "pendulum.toml").unwrap();
//! let mut sim = scene.simulation();
//! sim.end = 0.5;
//! let mut frames = Frames::for_drawing(&scene.drawing);
//! sim.run(&mut |s| frames.push(s.t, s.q)).unwrap();
//! let trace = Trace::parse("rod:0.5,0", &scene.drawing).unwrap();
//! let html = Viewer::new(&scene.name, &scene.drawing).trace(trace).html(&frames);
//! assert!(html.starts_with("<!DOCTYPE html>") && !html.contains("<script src"));
//! ```

mod collada;
mod drawing;
mod frames;
mod html;
mod mesh;
mod mesh_files;
mod solid;

pub(crate) use drawing::xy;
pub use drawing::{BodyDrawing, DrawBody, Drawing, Mark, Shape};
pub use frames::Frames;
pub use html::{Trace, TraceError, Viewer, DEFAULT_MAX_FRAMES};
pub use mesh::Mesh;
pub use mesh_files::{read_mesh, LoadedMeshes, MeshError, MeshSources, MAX_MESH_BYTES, MAX_TRIANGLES};
pub use solid::{inertia_box, JointMark, Solid, SolidBody, SpatialDrawing, Visual};
