// dalembert animation viewer: plays the poses of a planar run on a canvas.
// Data: the JSON element #dalembert-data (drawing, traces, base64 times and poses).
// Address options: #t=1.5 opens paused at t = 1.5 s.
"use strict";
(function () {
  const errors = [];
  const record = (msg) => {
    errors.push(String(msg));
    document.body.dataset.errors = JSON.stringify(errors);
  };
  window.addEventListener("error", (e) => record(e.message));
  window.addEventListener("unhandledrejection", (e) => record(e.reason));

  const data = JSON.parse(document.getElementById("dalembert-data").textContent);
  const decode = (b64, Kind) => {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Kind(bytes.buffer);
  };
  const times = decode(data.times, Float64Array);
  const poses = decode(data.poses, Float32Array);
  const drawing = data.drawing;
  const nb = drawing.bodies.length;
  const nf = times.length;
  const W = 3 * nb;
  const t0 = nf ? times[0] : 0;
  const t1 = nf ? times[nf - 1] : 0;

  const palette = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
    "#17becf", "#bcbd22", "#7f7f7f"];
  const color = (i) => palette[i % palette.length];
  const traceColors = ["#e6550d", "#3182bd", "#31a354", "#756bb1"];

  // ---- kinematics --------------------------------------------------------------------------
  // Pose of body b at a fractional frame position: linear interpolation of x, y, angle (angles
  // are continuous in the data, never wrapped).
  const pose = new Float64Array(W);
  function setPose(t) {
    if (nf === 0) return;
    let k = 0;
    if (t <= t0) k = 0;
    else if (t >= t1) k = nf - 1;
    else {
      let lo = 0, hi = nf - 1;
      while (hi - lo > 1) {
        const mid = (lo + hi) >> 1;
        if (times[mid] <= t) lo = mid; else hi = mid;
      }
      const s = (t - times[lo]) / (times[hi] - times[lo]);
      for (let i = 0; i < W; i++) pose[i] = (1 - s) * poses[lo * W + i] + s * poses[hi * W + i];
      return;
    }
    for (let i = 0; i < W; i++) pose[i] = poses[k * W + i];
  }
  function poseOfFrame(k) {
    for (let i = 0; i < W; i++) pose[i] = poses[k * W + i];
  }
  // Global position of local point p of body b (null: the ground, p is global).
  function world(b, p) {
    if (b === null || b === undefined) return [p[0], p[1]];
    const x = pose[3 * b], y = pose[3 * b + 1], a = pose[3 * b + 2];
    const c = Math.cos(a), s = Math.sin(a);
    return [x + c * p[0] - s * p[1], y + s * p[0] + c * p[1]];
  }
  function worldDir(b, d) {
    if (b === null || b === undefined) return [d[0], d[1]];
    const a = pose[3 * b + 2], c = Math.cos(a), s = Math.sin(a);
    return [c * d[0] - s * d[1], s * d[0] + c * d[1]];
  }
  const norm = (v) => Math.hypot(v[0], v[1]);

  // Local outline points of each body (for the bounding box).
  function outline(b) {
    const body = drawing.bodies[b];
    const sh = body.shape;
    const pts = [[0, 0]].concat(body.points);
    if (sh.kind === "rod") pts.push([-sh.length / 2, 0], [sh.length / 2, 0]);
    if (sh.kind === "disk") pts.push([sh.radius, 0], [-sh.radius, 0], [0, sh.radius], [0, -sh.radius]);
    if (sh.kind === "rectangle") {
      const w = sh.width / 2, h = sh.height / 2;
      pts.push([w, h], [-w, h], [w, -h], [-w, -h]);
    }
    return pts;
  }
  const outlines = drawing.bodies.map((_, b) => outline(b));
  // The smallest body's extent: pins, pivots and bars stay smaller than it on screen.
  const smallest = outlines.reduce((m, pts) => {
    const d = 2 * Math.max(...pts.map(norm));
    return d > 0 ? Math.min(m, d) : m;
  }, Infinity);

  // A contact's profile and circle are drawn with their bodies: they count in their extents.
  for (const m of drawing.marks.filter((x) => x.kind === "contact")) {
    const [b0, b1] = m.bodies;
    if (b1 !== null) outlines[b1].push(...m.profile);
    const c = m.points[0], r = m.radii[0];
    if (b0 !== null && r > 0) outlines[b0].push([c[0] + r, c[1]], [c[0] - r, c[1]], [c[0], c[1] + r], [c[0], c[1] - r]);
  }

  // Bounding box of everything drawn over the whole run, and the travel of every guide.
  let box = [Infinity, Infinity, -Infinity, -Infinity];
  const grow = (p) => {
    box = [Math.min(box[0], p[0]), Math.min(box[1], p[1]), Math.max(box[2], p[0]), Math.max(box[3], p[1])];
  };
  const guides = drawing.marks.filter((m) => m.kind === "guide").map((m) => ({ m, lo: 0, hi: 0 }));
  for (let k = 0; k < nf; k++) {
    poseOfFrame(k);
    for (let b = 0; b < nb; b++) for (const p of outlines[b]) grow(world(b, p));
    for (const g of guides) {
      const o = world(g.m.body, g.m.point), d = worldDir(g.m.body, g.m.direction);
      const f = world(g.m.follower, g.m.follower_point);
      const s = ((f[0] - o[0]) * d[0] + (f[1] - o[1]) * d[1]) / (norm(d) || 1);
      g.lo = Math.min(g.lo, s);
      g.hi = Math.max(g.hi, s);
    }
  }
  for (const m of drawing.marks) {
    for (const [b, p] of (m.bodies || []).map((b, i) => [b, m.points[i]])) if (b === null) grow(p);
    if (m.kind === "guide" && m.body === null) grow(m.point);
    if (m.kind === "contact" && m.bodies[1] === null) m.profile.forEach(grow);
  }
  for (const tr of data.traces) for (let k = 0; k < nf; k++) { poseOfFrame(k); grow(world(tr.body, tr.point)); }
  if (!isFinite(box[0])) box = [-1, -1, 1, 1];
  const size = Math.max(box[2] - box[0], box[3] - box[1], 1e-9);
  const margin = 0.08 * size;
  box = [box[0] - margin, box[1] - margin, box[2] + margin, box[3] + margin];

  // Trace paths, precomputed over all frames.
  const paths = data.traces.map((tr) => {
    const xy = new Float64Array(2 * nf);
    for (let k = 0; k < nf; k++) {
      poseOfFrame(k);
      const p = world(tr.body, tr.point);
      xy[2 * k] = p[0];
      xy[2 * k + 1] = p[1];
    }
    return xy;
  });

  // ---- drawing -----------------------------------------------------------------------------
  const canvas = document.getElementById("view");
  const ctx = canvas.getContext("2d");
  let view = { scale: 1, ox: 0, oy: 0 };
  function layout() {
    const r = canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    canvas.width = Math.max(1, Math.round(r.width * dpr));
    canvas.height = Math.max(1, Math.round(r.height * dpr));
    const bw = box[2] - box[0], bh = box[3] - box[1];
    const scale = Math.min(r.width / bw, r.height / bh);
    // CSS pixels, relative to the canvas: x_px = ox + scale x, y_px = oy − scale y.
    view = {
      scale,
      ox: (r.width - scale * bw) / 2 - scale * box[0],
      oy: (r.height + scale * bh) / 2 + scale * box[1],
      left: r.left,
      top: r.top,
      dpr,
    };
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.font = "12px system-ui, sans-serif";
    document.body.dataset.viewport = innerWidth + "x" + innerHeight;
    canvas.dataset.view = JSON.stringify({
      scale: view.scale, ox: view.ox + r.left, oy: view.oy + r.top,
      colors: drawing.bodies.map((_, i) => color(i)),
    });
  }
  const px = (p) => [view.ox + view.scale * p[0], view.oy - view.scale * p[1]];

  function line(a, b, width, style, dash) {
    const A = px(a), B = px(b);
    ctx.beginPath();
    ctx.setLineDash(dash || []);
    ctx.moveTo(A[0], A[1]);
    ctx.lineTo(B[0], B[1]);
    ctx.lineWidth = width;
    ctx.strokeStyle = style;
    ctx.lineCap = "round";
    ctx.stroke();
    ctx.setLineDash([]);
  }
  function dot(p, r, fill, stroke) {
    const P = px(p);
    ctx.beginPath();
    ctx.arc(P[0], P[1], r, 0, 2 * Math.PI);
    if (fill) { ctx.fillStyle = fill; ctx.fill(); }
    if (stroke) { ctx.lineWidth = 1.5; ctx.strokeStyle = stroke; ctx.stroke(); }
  }
  function polygon(points, fill, stroke) {
    ctx.beginPath();
    points.map(px).forEach((P, i) => (i ? ctx.lineTo(P[0], P[1]) : ctx.moveTo(P[0], P[1])));
    ctx.closePath();
    ctx.fillStyle = fill;
    ctx.fill();
    if (stroke) { ctx.lineWidth = 1.5; ctx.strokeStyle = stroke; ctx.stroke(); }
  }
  const clamp = (x, lo, hi) => Math.min(hi, Math.max(lo, x));
  const small = () => (isFinite(smallest) ? smallest * view.scale : Infinity); // px
  const barWidth = () => clamp(Math.min(0.015 * size * view.scale, 0.12 * small()), 2, 12);
  const pinRadius = () => clamp(0.1 * small(), 1.5, 4);

  function onShape(sh, p) {
    const eps = 1e-9 * size;
    if (sh.kind === "rod") return Math.abs(p[1]) <= eps && Math.abs(p[0]) <= sh.length / 2 + eps;
    if (sh.kind === "disk") return norm(p) <= sh.radius + eps;
    if (sh.kind === "rectangle") return Math.abs(p[0]) <= sh.width / 2 + eps && Math.abs(p[1]) <= sh.height / 2 + eps;
    return false;
  }

  function drawBody(b) {
    const body = drawing.bodies[b], sh = body.shape, col = color(b), w = barWidth();
    const at = (p) => world(b, p);
    // Bars from the reference point to attachment points off the shape.
    for (const p of body.points) if (!onShape(sh, p) && norm(p) > 1e-12 * size) line(at([0, 0]), at(p), w * 0.7, col);
    if (sh.kind === "rod") {
      line(at([-sh.length / 2, 0]), at([sh.length / 2, 0]), w, col);
    } else if (sh.kind === "disk") {
      const n = 48, pts = [];
      for (let i = 0; i < n; i++) {
        const a = (2 * Math.PI * i) / n;
        pts.push(at([sh.radius * Math.cos(a), sh.radius * Math.sin(a)]));
      }
      polygon(pts, col + "55", col);
      line(at([0, 0]), at([sh.radius, 0]), 2, col); // shows the rotation
    } else if (sh.kind === "rectangle") {
      const x = sh.width / 2, y = sh.height / 2;
      polygon([at([x, y]), at([-x, y]), at([-x, -y]), at([x, -y])], col + "88", col);
    } else if (body.slider) {
      const x = 0.04 * size, y = 0.025 * size;
      polygon([at([x, y]), at([-x, y]), at([-x, -y]), at([x, -y])], col, "#222");
    } else if (body.point_mass || body.points.length === 0) {
      dot(at([0, 0]), Math.max(5, 0.6 * w), col, "#222");
    }
  }

  function pivot(p) {
    const P = px(p), s = clamp(0.3 * small(), 4, 9);
    ctx.beginPath();
    ctx.moveTo(P[0], P[1]);
    ctx.lineTo(P[0] - s, P[1] + 1.6 * s);
    ctx.lineTo(P[0] + s, P[1] + 1.6 * s);
    ctx.closePath();
    ctx.fillStyle = "#bbb";
    ctx.fill();
    ctx.lineWidth = 1.5;
    ctx.strokeStyle = "#444";
    ctx.stroke();
    for (let i = -1; i <= 1; i++) {
      ctx.beginPath();
      ctx.moveTo(P[0] + i * s * 0.8 - 3, P[1] + 1.6 * s + 5);
      ctx.lineTo(P[0] + i * s * 0.8 + 3, P[1] + 1.6 * s);
      ctx.stroke();
    }
  }

  function spring(a, b) {
    const A = px(a), B = px(b);
    const dx = B[0] - A[0], dy = B[1] - A[1], L = Math.hypot(dx, dy);
    if (L < 1e-9) return;
    const ux = dx / L, uy = dy / L, nx = -uy, ny = ux, amp = 6, coils = 10, lead = 0.12 * L;
    ctx.beginPath();
    ctx.moveTo(A[0], A[1]);
    ctx.lineTo(A[0] + ux * lead, A[1] + uy * lead);
    for (let i = 1; i < 2 * coils; i++) {
      const s = lead + ((L - 2 * lead) * i) / (2 * coils), side = i % 2 ? amp : -amp;
      ctx.lineTo(A[0] + ux * s + nx * side, A[1] + uy * s + ny * side);
    }
    ctx.lineTo(B[0] - ux * lead, B[1] - uy * lead);
    ctx.lineTo(B[0], B[1]);
    ctx.lineWidth = 1.5;
    ctx.strokeStyle = "#555";
    ctx.stroke();
  }

  function drawMarks(pass) {
    for (const m of drawing.marks) {
      if (m.kind === "guide" && pass === 0) {
        const g = guides.find((x) => x.m === m);
        const d = worldDir(m.body, m.direction), u = norm(d) || 1;
        const o = world(m.body, m.point), pad = 0.06 * size;
        const a = [o[0] + (d[0] / u) * (g.lo - pad), o[1] + (d[1] / u) * (g.lo - pad)];
        const b = [o[0] + (d[0] / u) * (g.hi + pad), o[1] + (d[1] / u) * (g.hi + pad)];
        line(a, b, m.body === null ? 2 : 3, m.body === null ? "#666" : color(m.body), m.body === null ? [8, 5] : []);
      } else if (m.kind === "spring" && pass === 0) {
        spring(world(m.bodies[0], m.points[0]), world(m.bodies[1], m.points[1]));
      } else if (m.kind === "link" && pass === 0) {
        line(world(m.bodies[0], m.points[0]), world(m.bodies[1], m.points[1]), 2, "#333");
      } else if (m.kind === "pin" && pass === 1) {
        const [b0, b1] = m.bodies;
        if (b0 === null) pivot(m.points[0]);
        if (b1 === null) pivot(m.points[1]);
        const p = b1 === null ? world(b0, m.points[0]) : world(b1, m.points[1]);
        if (small() >= 10) dot(p, pinRadius(), "#fff", "#222"); // no pins on bodies a few pixels long
      }
    }
  }

  // ---- contacts ----------------------------------------------------------------------------
  // Each contact's shapes, and the arrow of its normal force on its first body (the frames'
  // reactions: per rigid contact, its `<name>.normal`), scaled to the largest force of the run.
  // Then per compliant contact its force on its body and the point where it acts (`<name>.fx`,
  // `.fy`, `.px`, `.py`), drawn from that point on the same scale.
  const reactions = data.reactions ? decode(data.reactions, Float32Array) : new Float32Array(0);
  const contacts = drawing.marks.filter((m) => m.kind === "contact");
  const forced = contacts.filter((m) => m.force);
  const compliant = drawing.contacts || [];
  const perFrame = forced.length + 4 * compliant.length;
  const framesOfForces = perFrame ? reactions.length / perFrame : 0;
  let largestForce = 0;
  for (let f = 0; f < framesOfForces; f++) {
    const o = f * perFrame;
    for (let j = 0; j < forced.length; j++) largestForce = Math.max(largestForce, Math.abs(reactions[o + j]));
    for (let c = 0; c < compliant.length; c++) {
      const k = o + forced.length + 4 * c;
      largestForce = Math.max(largestForce, Math.hypot(reactions[k], reactions[k + 1]));
    }
  }
  const arrowColor = "#e6007e";
  const shade = (b) => (b === null ? "#666666" : color(b));
  // The contact point and the direction of the force on the first body, in the current pose
  // (a profile's nearest knot or support knot: a drawing, not the solver's closest point).
  function contactAt(m) {
    const [b0, b1] = m.bodies;
    if (m.form === "circle-line") {
      const n = worldDir(b1, m.normal), c = world(b0, m.points[0]);
      return { p: [c[0] - m.radii[0] * n[0], c[1] - m.radii[0] * n[1]], n };
    }
    if (m.form === "circle-circle") {
      const c0 = world(b0, m.points[0]), c1 = world(b1, m.points[1]);
      const d = [c0[0] - c1[0], c0[1] - c1[1]], l = norm(d) || 1, n = [d[0] / l, d[1] / l];
      return { p: [c1[0] + m.radii[1] * n[0], c1[1] + m.radii[1] * n[1]], n };
    }
    const knots = m.profile.map((q) => world(b1, q));
    if (m.form === "circle-profile") {
      const c = world(b0, m.points[0]);
      let p = knots[0];
      for (const k of knots) if (norm([k[0] - c[0], k[1] - c[1]]) < norm([p[0] - c[0], p[1] - c[1]])) p = k;
      const d = [c[0] - p[0], c[1] - p[1]], l = norm(d) || 1;
      return { p, n: [d[0] / l, d[1] / l] };
    }
    const f = worldDir(b0, m.normal);
    let p = knots[0];
    for (const k of knots) if (f[0] * k[0] + f[1] * k[1] < f[0] * p[0] + f[1] * p[1]) p = k;
    return { p, n: [-f[0], -f[1]] };
  }
  function drawContacts(pass, t) {
    const k = frameIndex(t);
    contacts.forEach((m) => {
      const [b0, b1] = m.bodies;
      if (pass === 0) {
        if (m.profile.length) polygon(m.profile.map((q) => world(b1, q)), shade(b1) + "44", shade(b1));
        const lineOn = m.form === "circle-line" ? b1 : m.form === "line-profile" ? b0 : undefined;
        if (lineOn !== undefined) {
          const at = m.form === "circle-line" ? world(b1, m.points[1]) : world(b0, m.points[0]);
          const n = worldDir(lineOn, m.normal), u = [-n[1], n[0]];
          // Centred on the first shape's side of the contact: the circle's foot, or the face's point.
          const c = m.form === "circle-line" ? world(b0, m.points[0]) : at;
          const s = (c[0] - at[0]) * u[0] + (c[1] - at[1]) * u[1], half = 0.25 * size;
          const mid = [at[0] + s * u[0], at[1] + s * u[1]];
          line([mid[0] - half * u[0], mid[1] - half * u[1]], [mid[0] + half * u[0], mid[1] + half * u[1]], 2, shade(lineOn));
        }
        if (m.radii[0] > 0) {
          const c = world(b0, m.points[0]), pts = [];
          for (let i = 0; i < 48; i++) {
            const a = (2 * Math.PI * i) / 48;
            pts.push([c[0] + m.radii[0] * Math.cos(a), c[1] + m.radii[0] * Math.sin(a)]);
          }
          polygon(pts, "#ffffff00", shade(b0));
        }
      } else if (m.force && largestForce > 0 && perFrame) {
        const j = forced.indexOf(m), force = reactions[k * perFrame + j];
        if (!(force > 0)) return;
        const { p, n } = contactAt(m), L = (0.2 * size * force) / largestForce;
        arrow(p, [p[0] + L * n[0], p[1] + L * n[1]]);
      }
    });
    if (pass !== 0 && largestForce > 0 && framesOfForces) {
      for (let c = 0; c < compliant.length; c++) {
        const o = k * perFrame + forced.length + 4 * c;
        const f = [reactions[o], reactions[o + 1]], size_ = norm(f);
        if (!(size_ > 0)) continue;
        const p = [reactions[o + 2], reactions[o + 3]], L = (0.2 * size * size_) / largestForce;
        arrow(p, [p[0] + (L * f[0]) / size_, p[1] + (L * f[1]) / size_]);
      }
    }
    document.body.dataset.contactForces = JSON.stringify(
      forced.map((m, j) => (perFrame ? reactions[k * perFrame + j] : null)),
    );
    document.body.dataset.compliantContacts = String(framesOfForces ? compliant.length : 0);
  }
  function arrow(a, b) {
    line(a, b, 3, arrowColor);
    const A = px(a), B = px(b), dx = B[0] - A[0], dy = B[1] - A[1], l = Math.hypot(dx, dy);
    if (l < 1) return;
    const ux = dx / l, uy = dy / l, h = Math.min(10, 0.4 * l);
    ctx.beginPath();
    ctx.moveTo(B[0], B[1]);
    ctx.lineTo(B[0] - h * ux - 0.5 * h * uy, B[1] - h * uy + 0.5 * h * ux);
    ctx.lineTo(B[0] - h * ux + 0.5 * h * uy, B[1] - h * uy - 0.5 * h * ux);
    ctx.closePath();
    ctx.fillStyle = arrowColor;
    ctx.fill();
  }

  function drawTraces(k, t) {
    paths.forEach((xy, i) => {
      const col = traceColors[i % traceColors.length];
      ctx.beginPath();
      for (let j = 0; j <= k; j++) {
        const P = px([xy[2 * j], xy[2 * j + 1]]);
        if (j) ctx.lineTo(P[0], P[1]); else ctx.moveTo(P[0], P[1]);
      }
      const here = world(data.traces[i].body, data.traces[i].point);
      const H = px(here);
      ctx.lineTo(H[0], H[1]);
      ctx.lineWidth = 1.5;
      ctx.strokeStyle = col;
      ctx.stroke();
      dot(here, 3, col, null);
      ctx.fillStyle = col;
      ctx.fillText(data.traces[i].label, H[0] + 6, H[1] - 6);
    });
  }

  let current = t0;
  function frameIndex(t) {
    let lo = 0, hi = nf - 1;
    if (nf === 0 || t <= t0) return 0;
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (times[mid] <= t) lo = mid; else hi = mid;
    }
    return t >= t1 ? nf - 1 : lo;
  }
  function draw(t) {
    current = t;
    const r = canvas.getBoundingClientRect();
    ctx.clearRect(0, 0, r.width, r.height);
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, r.width, r.height);
    if (nf === 0) {
      ctx.fillStyle = "#a40000";
      ctx.fillText("no frames to show", 20, 30);
      return;
    }
    setPose(t);
    drawMarks(0);
    drawTraces(frameIndex(t), t);
    setPose(t);
    for (let b = 0; b < nb; b++) drawBody(b);
    drawContacts(0, t);
    drawMarks(1);
    drawContacts(1, t);
    clock.textContent = "t = " + t.toFixed(3) + " s";
    slider.value = t1 > t0 ? Math.round((10000 * (t - t0)) / (t1 - t0)) : 0;
    document.body.dataset.time = String(t);
  }

  // ---- controls ----------------------------------------------------------------------------
  const clock = document.getElementById("clock");
  const slider = document.getElementById("time");
  const playButton = document.getElementById("play");
  const speed = document.getElementById("speed");
  document.getElementById("title").textContent = data.title;
  if (data.note) document.getElementById("note").textContent = data.note;

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
  document.addEventListener("keydown", (e) => {
    if (e.code === "Space" && e.target === document.body) {
      e.preventDefault();
      playButton.click();
    }
  });
  window.addEventListener("resize", () => {
    layout();
    draw(current);
  });

  // #t=1.5: that instant, paused.
  const hash = new URLSearchParams(location.hash.slice(1));
  const start = hash.has("t") ? parseFloat(hash.get("t")) : NaN;
  layout();
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
})();
