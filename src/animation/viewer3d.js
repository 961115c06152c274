// dalembert 3D viewer: plays the poses of a spatial run with three.js (inlined in the page).
// Data: the JSON element #dalembert-data (drawing.spatial, traces, base64 times and poses: per
// body x, y, z, e0, e1, e2, e3; optionally reactions: per joint fx, fy, fz, then per compliant
// contact fx, fy, fz, px, py, pz). Address options: #t=1.5 opens paused at t = 1.5 s; &reactions
// shows the reaction arrows (the contact forces' arrows are shown unless &nocontacts).
// The page reports on <body>: data-status, data-time, data-errors, data-viewport,
// data-first-draw-ms, data-meshes (the visual meshes drawn), data-reactions and data-contacts (the
// arrows) and
// data-reaction-scale (newtons per metre of arrow); on the canvas, data-view: the camera's view-projection matrix, the canvas'
// place in the window and the bodies' colours (the rendering test projects with them).
"use strict";
const errors = [];
const record = (msg) => {
  errors.push(String(msg));
  document.body.dataset.errors = JSON.stringify(errors);
};
window.addEventListener("error", (e) => record(e.message));
window.addEventListener("unhandledrejection", (e) => record(e.reason));

const source = document.getElementById("three-source");
const THREE = await import(URL.createObjectURL(new Blob([source.textContent], { type: "text/javascript" })));
source.textContent = "";

const data = JSON.parse(document.getElementById("dalembert-data").textContent);
const decode = (b64, Kind) => {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Kind(bytes.buffer);
};
const times = decode(data.times, Float64Array);
const poses = decode(data.poses, Float32Array);
const drawing = data.drawing.spatial;
const nb = drawing.bodies.length;
const nf = times.length;
const W = 7 * nb;
const t0 = nf ? times[0] : 0;
const t1 = nf ? times[nf - 1] : 0;

const palette = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
  "#17becf", "#bcbd22", "#7f7f7f"];
const color = (i) => palette[i % palette.length];
const traceColors = ["#e6550d", "#3182bd", "#31a354", "#756bb1"];
const MARKER = "#111111";

// ---- the size of the motion ------------------------------------------------------------------
// Each body's reach from its centre of mass (its solid and its joint points), and the box of the
// centres over the run widened by the largest reach.
const v3 = (a) => new THREE.Vector3(a[0], a[1], a[2]);
// Meshes (the bodies' visuals): little-endian f32 corners and u32 triangles.
const meshGeometries = (data.meshes || []).map((m) => {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(decode(m.positions, Float32Array), 3));
  if (m.indices.length) geometry.setIndex(new THREE.BufferAttribute(decode(m.indices, Uint32Array), 1));
  geometry.computeBoundingSphere();
  return geometry;
});
const meshOf = (i, k) => (data.mesh_of && data.mesh_of[i] ? data.mesh_of[i][k] : null);
function solidReach(s, mesh) {
  if (s.kind === "box") return 0.5 * Math.hypot(...s.size);
  if (s.kind === "sphere") return s.radius;
  if (s.kind === "mesh") {
    if (mesh === null || mesh === undefined) return 0;
    const sphere = meshGeometries[mesh].boundingSphere;
    return (sphere.center.length() + sphere.radius) * Math.max(...s.scale.map(Math.abs));
  }
  return Math.hypot(s.radius, 0.5 * s.length);
}
// A body's reach from its centre of mass: its visuals' (those drawn), else its solid's.
function bodyReach(b, i) {
  const drawn = b.visuals.map((v, k) => (v.shape.kind !== "mesh" || meshOf(i, k) != null
    ? Math.hypot(...v.position) + solidReach(v.shape, meshOf(i, k)) : -1)).filter((r) => r >= 0);
  return drawn.length ? Math.max(...drawn) : solidReach(b.solid);
}
const groundMeshOf = (k) => (data.ground_mesh_of ? data.ground_mesh_of[k] : null);
const ground = drawing.ground || [];
let reach = 0;
drawing.bodies.forEach((b, i) => {
  reach = Math.max(reach, bodyReach(b, i));
  for (const p of b.points) reach = Math.max(reach, Math.hypot(...p));
});
const lo = new THREE.Vector3(Infinity, Infinity, Infinity);
const hi = new THREE.Vector3(-Infinity, -Infinity, -Infinity);
for (let k = 0; k < nf; k++) {
  for (let b = 0; b < nb; b++) {
    const o = k * W + 7 * b;
    const p = new THREE.Vector3(poses[o], poses[o + 1], poses[o + 2]);
    lo.min(p);
    hi.max(p);
  }
}
for (const j of drawing.joints) {
  for (let s = 0; s < 2; s++) {
    if (j.bodies[s] === null) {
      lo.min(v3(j.points[s]));
      hi.max(v3(j.points[s]));
    }
  }
}
// The ground's visuals (a robot's base), each a ball around its origin.
ground.forEach((v, k) => {
  if (v.shape.kind === "mesh" && groundMeshOf(k) == null) return;
  const r = solidReach(v.shape, groundMeshOf(k));
  lo.min(v3(v.position).subScalar(r - reach));
  hi.max(v3(v.position).addScalar(r - reach));
});
if (!isFinite(lo.x)) { lo.set(-1, -1, -1); hi.set(1, 1, 1); }
lo.subScalar(reach);
hi.addScalar(reach);
const center = lo.clone().add(hi).multiplyScalar(0.5);
const radius = Math.max(0.5 * lo.distanceTo(hi), 1e-3);
// Small things are drawn at least this big: a rod's zero width, a point mass.
const least = 0.012 * radius;

// ---- scene -----------------------------------------------------------------------------------
const canvas = document.getElementById("view");
const stage = document.getElementById("stage");
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
const scene = new THREE.Scene();
scene.background = new THREE.Color("#ffffff");
const g = v3(drawing.gravity);
const up = g.lengthSq() > 0 ? g.clone().normalize().negate() : new THREE.Vector3(0, 0, 1);
scene.add(new THREE.HemisphereLight(0xffffff, 0x666666, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
scene.add(sun);

// A grid under the motion, across the "up" direction.
{
  const grid = new THREE.GridHelper(4 * radius, 20, 0xb0b0b0, 0xdedede);
  grid.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), up);
  let lowest = Infinity;
  for (const c of [lo.x, hi.x]) for (const d of [lo.y, hi.y]) for (const e of [lo.z, hi.z]) {
    lowest = Math.min(lowest, new THREE.Vector3(c, d, e).dot(up));
  }
  grid.position.copy(center).addScaledVector(up, lowest - center.dot(up));
  scene.add(grid);
}

const quaternionOf = (e) => new THREE.Quaternion(e[1], e[2], e[3], e[0]);
function solidGeometry(s) {
  if (s.kind === "box") return new THREE.BoxGeometry(...s.size.map((x) => Math.max(x, least)));
  if (s.kind === "sphere") return new THREE.SphereGeometry(Math.max(s.radius, least), 32, 16);
  const geometry = new THREE.CylinderGeometry(Math.max(s.radius, least), Math.max(s.radius, least),
    Math.max(s.length, least), 32);
  return geometry.rotateX(Math.PI / 2); // three's cylinder lies along y; ours along z
}
// Each body's own size: the larger of its solid and its farthest joint point. Bars and joint
// balls are kept small beside it, so that a chain of many short links stays a chain.
const sizes = drawing.bodies.map((b, i) => Math.max(bodyReach(b, i), ...b.points.map((p) => Math.hypot(...p)), 0));
// A bar between two points of a body (its frame).
function bar(a, b, material, size) {
  const length = a.distanceTo(b);
  const r = Math.min(0.5 * least, 0.08 * size);
  const mesh = new THREE.Mesh(new THREE.CylinderGeometry(r, r, length, 12), material);
  mesh.position.copy(a).add(b).multiplyScalar(0.5);
  mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), b.clone().sub(a).normalize());
  return mesh;
}

const bodies = [];
const axisObjects = [];
// Meshes are shaded face by face (their files' normals are not read), from both sides (a mirrored
// scale turns faces inside out).
let meshesDrawn = 0;
// Adds the visuals to `owner` (a body's group, or the scene for the ground's); returns how many.
function addVisuals(owner, visuals, meshIndex, tint) {
  const material = new THREE.MeshStandardMaterial({ color: tint, roughness: 0.55, metalness: 0.05 });
  let drawn = 0;
  visuals.forEach((v, k) => {
    let object;
    if (v.shape.kind === "mesh") {
      const m = meshIndex(k);
      if (m === null || m === undefined) return;
      object = new THREE.Mesh(meshGeometries[m], new THREE.MeshStandardMaterial({ color: tint, roughness: 0.55,
        metalness: 0.05, flatShading: true, side: THREE.DoubleSide }));
      object.scale.set(...v.shape.scale);
      meshesDrawn++;
    } else {
      object = new THREE.Mesh(solidGeometry(v.shape), material);
    }
    object.position.copy(v3(v.position));
    object.quaternion.copy(quaternionOf(v.rotation));
    owner.add(object);
    drawn++;
  });
  return drawn;
}
addVisuals(scene, ground, groundMeshOf, "#9a9a9a");
for (let i = 0; i < nb; i++) {
  const b = drawing.bodies[i];
  const group = new THREE.Group();
  const material = new THREE.MeshStandardMaterial({ color: color(i), roughness: 0.55, metalness: 0.05 });
  // The body's visuals where the scene gives them (a mesh not read is left out), else its solid.
  const drawn = addVisuals(group, b.visuals, (k) => meshOf(i, k), color(i));
  if (!drawn) {
    const solid = new THREE.Mesh(solidGeometry(b.solid), material);
    solid.quaternion.copy(quaternionOf(b.rotation));
    group.add(solid);
  }
  const barMaterial = new THREE.MeshStandardMaterial({ color: color(i), roughness: 0.7 });
  for (const p of b.points) {
    if (Math.hypot(...p) > least) group.add(bar(new THREE.Vector3(), v3(p), barMaterial, sizes[i]));
  }
  const frame = new THREE.AxesHelper(0.15 * radius);
  frame.visible = false;
  axisObjects.push(frame);
  group.add(frame);
  scene.add(group);
  bodies.push(group);
}
document.body.dataset.meshes = String(meshesDrawn);
// Joints: a dark ball at the joint's point on its first body, and its axis on demand.
const jointMaterial = new THREE.MeshStandardMaterial({ color: "#404040", roughness: 0.4 });
for (const j of drawing.joints) {
  const owner = j.bodies[0] === null ? scene : bodies[j.bodies[0]];
  const near = j.bodies.filter((b) => b !== null).map((b) => sizes[b]);
  const ball = new THREE.Mesh(new THREE.SphereGeometry(Math.min(1.3 * least, 0.2 * Math.min(...near, Infinity)), 16, 12),
    jointMaterial);
  ball.position.copy(v3(j.points[0]));
  owner.add(ball);
  if (j.kind !== "spherical" && j.kind !== "fixed" && j.kind !== "distance") {
    const arrow = new THREE.ArrowHelper(v3(j.axis).normalize(), v3(j.points[0]), 0.25 * radius, 0x202020);
    arrow.visible = false;
    axisObjects.push(arrow);
    owner.add(arrow);
  }
}
// Reactions: per joint an arrow at its point on its first body, the force its second body exerts
// on its first (as in the CSV); then per compliant contact an arrow of its force on its body at
// the point where it acts. One scale for both: the largest force of the run is 0.3 of the scene's
// size.
const reactions = data.reactions ? decode(data.reactions, Float32Array) : new Float32Array(0);
const nj = drawing.joints.length;
const nc = (drawing.contacts || []).length;
const R = 3 * nj + 6 * nc;
const REACTION = "#c0392b";
const CONTACT = "#16a085";
const recorded = R > 0 && reactions.length === R * nf;
let largestForce = 0;
for (let f = 0; recorded && f < nf; f++) {
  for (let j = 0; j < nj + nc; j++) {
    const k = f * R + (j < nj ? 3 * j : 3 * nj + 6 * (j - nj));
    largestForce = Math.max(largestForce, Math.hypot(reactions[k], reactions[k + 1], reactions[k + 2]));
  }
}
const metresPerNewton = largestForce > 0 ? (0.3 * radius) / largestForce : 0;
const forceArrow = (colour) => {
  const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 1, colour,
    0.2 * 0.3 * radius, 0.08 * 0.3 * radius);
  arrow.visible = false;
  arrow.cone.material.depthTest = false;
  arrow.line.material.depthTest = false;
  arrow.renderOrder = 11;
  scene.add(arrow);
  return arrow;
};
const reactionArrows = [];
const contactArrows = [];
const scaleText = largestForce > 0 ? "(1 m = " + (1 / metresPerNewton).toPrecision(3) + " N)" : "";
if (recorded && largestForce > 0) {
  document.body.dataset.reactionScale = String(1 / metresPerNewton);
  if (nj > 0) {
    for (let j = 0; j < nj; j++) reactionArrows.push(forceArrow(REACTION));
    document.getElementById("reactions-label").hidden = false;
    document.getElementById("reaction-scale").textContent = scaleText;
    document.body.dataset.reactions = String(nj);
  }
  if (nc > 0) {
    for (let c = 0; c < nc; c++) contactArrows.push(forceArrow(CONTACT));
    document.getElementById("contacts-label").hidden = false;
    document.getElementById("contact-scale").textContent = scaleText;
    document.body.dataset.contacts = String(nc);
  }
}
let showReactions = false;
let showContacts = true;

// Centres of mass: small dark squares of fixed size (4 px), drawn over everything.
const markerGeometry = new THREE.BufferGeometry();
const markerPositions = new Float32Array(3 * nb);
markerGeometry.setAttribute("position", new THREE.BufferAttribute(markerPositions, 3));
const markers = new THREE.Points(markerGeometry,
  new THREE.PointsMaterial({ color: MARKER, size: 4, sizeAttenuation: false, depthTest: false }));
markers.renderOrder = 10;
markers.frustumCulled = false;
scene.add(markers);

// Traces: the path of a body point over the whole run, shown up to the current time.
const traces = data.traces.map((tr, n) => {
  const positions = new Float32Array(3 * Math.max(nf, 1));
  const p = v3(tr.point);
  for (let k = 0; k < nf; k++) {
    const o = k * W + 7 * tr.body;
    const q = new THREE.Quaternion(poses[o + 4], poses[o + 5], poses[o + 6], poses[o + 3]).normalize();
    const w = p.clone().applyQuaternion(q).add(new THREE.Vector3(poses[o], poses[o + 1], poses[o + 2]));
    positions.set([w.x, w.y, w.z], 3 * k);
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
  const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: traceColors[n % traceColors.length] }));
  line.frustumCulled = false;
  scene.add(line);
  return line;
});

// ---- camera and its controls -----------------------------------------------------------------
const camera = new THREE.PerspectiveCamera(35, 1, radius * 1e-3, radius * 100);
camera.up.copy(up);
const target = new THREE.Vector3();
function fit() {
  // From the front-right and above: the basis (e1, e2, up) with e1 across "up".
  const e1 = Math.abs(up.x) < 0.9 ? new THREE.Vector3(1, 0, 0) : new THREE.Vector3(0, 1, 0);
  e1.addScaledVector(up, -e1.dot(up)).normalize();
  const e2 = up.clone().cross(e1);
  const direction = e1.clone().multiplyScalar(0.55).addScaledVector(e2, -1).addScaledVector(up, 0.45).normalize();
  const fov = THREE.MathUtils.degToRad(camera.fov);
  const distance = (0.8 * radius) / Math.sin(0.5 * Math.min(fov, fov * Math.max(camera.aspect, 1e-3)));
  target.copy(center);
  camera.position.copy(center).addScaledVector(direction, distance);
  camera.lookAt(target);
}
function orbit(dx, dy) {
  const offset = camera.position.clone().sub(target);
  offset.applyAxisAngle(up, -0.008 * dx);
  const right = offset.clone().cross(up).normalize();
  const turned = offset.clone().applyAxisAngle(right, 0.008 * dy);
  const angle = turned.angleTo(up);
  if (angle > 0.05 && angle < Math.PI - 0.05) offset.copy(turned);
  camera.position.copy(target).add(offset);
  camera.lookAt(target);
}
function pan(dx, dy) {
  const distance = camera.position.distanceTo(target);
  const perPixel = (2 * distance * Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2)) / canvas.clientHeight;
  const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
  const screenUp = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
  const move = right.multiplyScalar(-dx * perPixel).addScaledVector(screenUp, dy * perPixel);
  target.add(move);
  camera.position.add(move);
}
function zoom(factor) {
  const offset = camera.position.clone().sub(target).multiplyScalar(factor);
  camera.position.copy(target).add(offset);
}
let drag = null;
canvas.addEventListener("pointerdown", (e) => {
  drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.shiftKey };
  canvas.setPointerCapture(e.pointerId);
});
canvas.addEventListener("pointermove", (e) => {
  if (!drag) return;
  const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
  drag.x = e.clientX;
  drag.y = e.clientY;
  if (drag.pan) pan(dx, dy); else orbit(dx, dy);
  render();
});
canvas.addEventListener("pointerup", () => { drag = null; });
canvas.addEventListener("contextmenu", (e) => e.preventDefault());
canvas.addEventListener("wheel", (e) => {
  e.preventDefault();
  zoom(Math.exp(0.001 * e.deltaY));
  render();
}, { passive: false });
canvas.addEventListener("dblclick", () => { fit(); render(); });

// ---- poses -----------------------------------------------------------------------------------
// At time t: positions interpolated linearly between frames, orientations by normalized linear
// interpolation of the Euler parameters (same hemisphere).
const qa = new THREE.Quaternion(), qb = new THREE.Quaternion();
let frame = 0;
function setPose(t) {
  if (nf === 0) return;
  let a = 0, b = 0, s = 0;
  if (t >= t1) a = b = nf - 1;
  else if (t > t0) {
    let l = 0, h = nf - 1;
    while (h - l > 1) {
      const mid = (l + h) >> 1;
      if (times[mid] <= t) l = mid; else h = mid;
    }
    a = l; b = h; s = (t - times[l]) / (times[h] - times[l]);
  }
  frame = s > 0 ? b : a;
  for (let i = 0; i < nb; i++) {
    const oa = a * W + 7 * i, ob = b * W + 7 * i;
    const g = bodies[i];
    g.position.set(
      (1 - s) * poses[oa] + s * poses[ob],
      (1 - s) * poses[oa + 1] + s * poses[ob + 1],
      (1 - s) * poses[oa + 2] + s * poses[ob + 2]);
    qa.set(poses[oa + 4], poses[oa + 5], poses[oa + 6], poses[oa + 3]);
    qb.set(poses[ob + 4], poses[ob + 5], poses[ob + 6], poses[ob + 3]);
    const sign = qa.dot(qb) < 0 ? -1 : 1;
    g.quaternion.set(
      (1 - s) * qa.x + s * sign * qb.x, (1 - s) * qa.y + s * sign * qb.y,
      (1 - s) * qa.z + s * sign * qb.z, (1 - s) * qa.w + s * sign * qb.w).normalize();
    markerPositions.set([g.position.x, g.position.y, g.position.z], 3 * i);
  }
  markerGeometry.attributes.position.needsUpdate = true;
  for (const line of traces) line.geometry.setDrawRange(0, frame + 1);
  const place = (arrow, f, length, shown) => {
    arrow.visible = shown && length > 1e-3 * radius;
    if (length > 0) {
      arrow.setDirection(f.normalize());
      arrow.setLength(length, Math.min(0.2 * 0.3 * radius, 0.5 * length), Math.min(0.08 * 0.3 * radius, 0.2 * length));
    }
  };
  const mix = (k) => (1 - s) * reactions[a * R + k] + s * reactions[b * R + k];
  for (let j = 0; j < reactionArrows.length; j++) {
    const f = new THREE.Vector3(mix(3 * j), mix(3 * j + 1), mix(3 * j + 2));
    const joint = drawing.joints[j];
    const at = v3(joint.points[0]);
    if (joint.bodies[0] !== null) {
      const g = bodies[joint.bodies[0]];
      g.updateMatrixWorld();
      at.applyMatrix4(g.matrixWorld);
    }
    reactionArrows[j].position.copy(at);
    place(reactionArrows[j], f, f.length() * metresPerNewton, showReactions);
  }
  for (let c = 0; c < contactArrows.length; c++) {
    const o = 3 * nj + 6 * c;
    const f = new THREE.Vector3(mix(o), mix(o + 1), mix(o + 2));
    contactArrows[c].position.set(mix(o + 3), mix(o + 4), mix(o + 5));
    place(contactArrows[c], f, f.length() * metresPerNewton, showContacts);
  }
}

function layout() {
  const w = stage.clientWidth, h = stage.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
  document.body.dataset.viewport = innerWidth + "x" + innerHeight;
}
function render() {
  renderer.render(scene, camera);
  const rect = canvas.getBoundingClientRect();
  const m = new THREE.Matrix4().multiplyMatrices(camera.projectionMatrix, camera.matrixWorldInverse);
  canvas.dataset.view = JSON.stringify({
    matrix: m.elements, left: rect.left, top: rect.top, width: rect.width, height: rect.height,
    marker: MARKER, colors: drawing.bodies.map((_, i) => color(i)),
  });
}

// ---- controls --------------------------------------------------------------------------------
const clock = document.getElementById("clock");
const slider = document.getElementById("time");
const playButton = document.getElementById("play");
const speed = document.getElementById("speed");
document.getElementById("title").textContent = data.title;
if (data.note) document.getElementById("note").textContent = data.note;
let current = t0;
function draw(t) {
  current = t;
  setPose(t);
  render();
  clock.textContent = "t = " + t.toFixed(3) + " s";
  slider.value = t1 > t0 ? Math.round((10000 * (t - t0)) / (t1 - t0)) : 0;
  document.body.dataset.time = String(t);
}
let playing = true;
let last = null;
function setPlaying(p) {
  playing = p;
  playButton.textContent = p ? "Pause" : "Play";
  last = null;
  if (p) requestAnimationFrame(tick);
}
function tick(now) {
  if (!playing) return;
  if (last !== null) {
    let t = current + ((now - last) / 1000) * parseFloat(speed.value);
    if (t > t1) t = t0; // loop
    draw(t);
  }
  last = now;
  requestAnimationFrame(tick);
}
playButton.addEventListener("click", () => {
  if (!playing && current >= t1) current = t0;
  setPlaying(!playing);
});
slider.addEventListener("input", () => {
  setPlaying(false);
  draw(t0 + ((t1 - t0) * slider.value) / 10000);
});
document.getElementById("axes").addEventListener("change", (e) => {
  for (const o of axisObjects) o.visible = e.target.checked;
  render();
});
document.getElementById("reactions").addEventListener("change", (e) => {
  showReactions = e.target.checked;
  draw(current);
});
document.getElementById("contacts").addEventListener("change", (e) => {
  showContacts = e.target.checked;
  draw(current);
});
document.getElementById("centres").addEventListener("change", (e) => {
  markers.visible = e.target.checked;
  render();
});
document.getElementById("fit").addEventListener("click", () => { fit(); render(); });
document.addEventListener("keydown", (e) => {
  if (e.code === "Space" && e.target === document.body) {
    e.preventDefault();
    playButton.click();
  }
});
window.addEventListener("resize", () => { layout(); draw(current); });

// #t=1.5: that instant, paused.
const hash = new URLSearchParams(location.hash.slice(1));
const start = hash.has("t") ? parseFloat(hash.get("t")) : NaN;
if (hash.has("nocontacts") && contactArrows.length) {
  showContacts = false;
  document.getElementById("contacts").checked = false;
}
if (hash.has("reactions") && reactionArrows.length) {
  showReactions = true;
  document.getElementById("reactions").checked = true;
}
layout();
fit();
sun.position.copy(camera.position).addScaledVector(up, radius);
if (isFinite(start)) {
  playing = false;
  playButton.textContent = "Play";
  draw(Math.min(Math.max(start, t0), t1));
} else {
  draw(t0);
  setPlaying(true);
}
document.body.dataset.firstDrawMs = performance.now().toFixed(1);
document.body.dataset.status = "ready";
