// quadnav run viewer: the map, explored tree, path, trajectory (coloured by speed), flown
// track and a drone marker moving in time, drawn on a 2D canvas with a perspective
// projection and painter's order (far to near). The run is the JSON in #run-data, written
// by quadnav.viz.html_viewer (positions flattened x, y, z, ...). Lengths in m, times in s.
"use strict";
(() => {
  const data = JSON.parse(document.getElementById("run-data").textContent);
  const $ = (id) => document.getElementById(id);
  const canvas = $("view");
  // The static scene (boundary, blocks, lines, axes) is drawn on `scene` when the view
  // changes; each frame copies it to the screen and draws the markers over it.
  const screen = canvas.getContext("2d");
  const scene = document.createElement("canvas").getContext("2d");
  let ctx = scene; // the context being drawn on
  const clamp = (x, a, b) => Math.min(Math.max(x, a), b);
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const point = (flat, i) => [flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]];

  // ------------------------------------------------------------------ colours and layers
  const VIRIDIS = [[68, 1, 84], [72, 40, 120], [62, 73, 137], [49, 104, 142], [38, 130, 142],
    [31, 158, 137], [53, 183, 121], [110, 206, 88], [181, 222, 43], [253, 231, 37]];
  const viridis = (f) => {
    const x = clamp(f, 0, 1) * (VIRIDIS.length - 1);
    const i = Math.min(Math.floor(x), VIRIDIS.length - 2);
    return `rgb(${VIRIDIS[i].map((a, k) => Math.round(a + (x - i) * (VIRIDIS[i + 1][k] - a)))})`;
  };
  const SPEED_BINS = 64; // trajectory colours, so that equal colours draw in one batch
  const START = "#e00000", GOAL = "#008000", PATH = "#e00000", FLOWN = "#111111";
  const TREE = "rgba(89, 140, 217, 0.45)", DRONE = "#ff7f0e", COLLISION = "#e000e0";
  const layers = {}; // name -> {label, swatch, on}
  const addLayer = (name, label, swatch) => { layers[name] = { label, swatch, on: true }; };
  if (data.blocks.length) addLayer("blocks", `blocks (${data.blocks.length / 6})`,
    `rgb(${data.colors.slice(0, 3).map((x) => Math.round(255 * x))})`);
  if (data.tree.length) {
    const drawn = data.tree.length / 6;
    addLayer("tree", `tree (${data.treeEdges.toLocaleString("en")} edges` +
      (drawn < data.treeEdges ? `, ${drawn.toLocaleString("en")} drawn)` : ")"), TREE);
  }
  if (data.path) addLayer("path", `path (${data.path.length / 3} waypoints)`, PATH);
  if (data.trajectory) addLayer("trajectory", "trajectory (colour: speed)",
    `linear-gradient(to right, ${viridis(0)}, ${viridis(0.5)}, ${viridis(1)})`);
  if (data.flight) addLayer("flown", "flown track", FLOWN);

  // ------------------------------------------------------------------ scene geometry
  const lo = data.boundary.slice(0, 3), hi = data.boundary.slice(3, 6);
  const centre = lo.map((a, k) => (a + hi[k]) / 2);
  const radius = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2;
  const size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);

  // Line segments: endpoints (6 numbers each) and a style (stroke, width, layer) each.
  const styles = [], segXYZ = [], segStyle = [];
  const style = (layer, stroke, width) => styles.push({ layer, stroke, width }) - 1;
  const TREE_STYLE = style("tree", TREE, 0.6), PATH_STYLE = style("path", PATH, 2.4);
  const FLOWN_STYLE = style("flown", FLOWN, 1.2);
  const SPEED_STYLES = Array.from({ length: SPEED_BINS },
    (_, k) => style("trajectory", viridis(k / (SPEED_BINS - 1)), 3));
  const addSegment = (a, b, s) => { segXYZ.push(...a, ...b); segStyle.push(s); };
  // A polyline, long pieces split so that the painter's order stays right along them.
  const addPolyline = (flat, styleOf, longest = radius / 25) => {
    for (let i = 0; i + 1 < flat.length / 3; i++) {
      const a = point(flat, i), b = point(flat, i + 1);
      const n = Math.max(1, Math.ceil(Math.hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]) / longest));
      for (let j = 0; j < n; j++) {
        addSegment(a.map((v, k) => v + (b[k] - v) * j / n),
          a.map((v, k) => v + (b[k] - v) * (j + 1) / n), styleOf(i));
      }
    }
  };
  for (let i = 0; i < data.tree.length; i += 6) {
    addSegment(data.tree.slice(i, i + 3), data.tree.slice(i + 3, i + 6), TREE_STYLE);
  }
  if (data.path) addPolyline(data.path, () => PATH_STYLE);
  const speedMax = data.trajectory ? data.trajectory.speed.reduce((a, b) => Math.max(a, b), 1e-9)
    : 0;
  if (data.trajectory) {
    const v = data.trajectory.speed;
    addPolyline(data.trajectory.position, (i) =>
      SPEED_STYLES[Math.round((v[i] + v[i + 1]) / 2 / speedMax * (SPEED_BINS - 1))]);
  }
  if (data.flight) addPolyline(data.flight.position, () => FLOWN_STYLE);
  const nSeg = segStyle.length, segPoints = Float64Array.from(segXYZ);

  // Box faces: four corners (numbered by bits x, y, z), the outward normal, the fill.
  const FACES = [[0, 2, 6, 4, [-1, 0, 0]], [1, 3, 7, 5, [1, 0, 0]], [0, 1, 5, 4, [0, -1, 0]],
    [2, 3, 7, 6, [0, 1, 0]], [0, 1, 3, 2, [0, 0, -1]], [4, 5, 7, 6, [0, 0, 1]]];
  const LIGHT = [0.3, 0.5, 0.81]; // unit vector towards the light
  const boxCorners = (b) => Array.from({ length: 8 },
    (_, c) => [0, 1, 2].map((k) => ((c >> k) & 1 ? b[k + 3] : b[k])));
  const faces = [];
  for (let i = 0; i < data.blocks.length / 6; i++) {
    const corners = boxCorners(data.blocks.slice(6 * i, 6 * i + 6));
    const rgb = data.colors.slice(3 * i, 3 * i + 3);
    for (const [a, b, c, d, normal] of FACES) {
      const pts = [a, b, c, d].map((k) => corners[k]);
      const shade = 0.65 + 0.35 * dot(normal, LIGHT);
      faces.push({ pts, normal, centre: [0, 1, 2].map((k) => (pts[0][k] + pts[2][k]) / 2),
        fill: `rgba(${rgb.map((x) => Math.round(255 * x * shade))}, 0.92)` });
    }
  }
  const nFace = faces.length;
  const boundaryCorners = boxCorners(data.boundary);

  // ------------------------------------------------------------------ camera
  const DEFAULT_VIEW = { azimuth: -60, elevation: 30, zoom: 1, panX: 0, panY: 0 };
  let view = { ...DEFAULT_VIEW };
  const cam = {};
  const setCamera = (width, height) => {
    const az = view.azimuth * Math.PI / 180, el = view.elevation * Math.PI / 180;
    cam.e = [Math.cos(el) * Math.cos(az), Math.cos(el) * Math.sin(az), Math.sin(el)];
    cam.right = [-Math.sin(az), Math.cos(az), 0];
    cam.up = [-Math.sin(el) * Math.cos(az), -Math.sin(el) * Math.sin(az), Math.cos(el)];
    cam.distance = 4 * radius; // of the eye from the centre
    cam.eye = centre.map((c, k) => c + cam.distance * cam.e[k]);
    cam.scale = view.zoom * 0.46 * Math.min(width, height) / radius; // px per m at the centre
    cam.cx = width / 2 + view.panX;
    cam.cy = height / 2 + view.panY;
  };
  // Screen position (px), depth (m along the view, larger is nearer) and px per m of a point.
  const project = (p) => {
    const r = [p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]];
    const depth = dot(r, cam.e), w = cam.scale * cam.distance / (cam.distance - depth);
    return { x: cam.cx + w * dot(r, cam.right), y: cam.cy - w * dot(r, cam.up), depth, w };
  };

  // ------------------------------------------------------------------ drawing
  const segScreen = new Float64Array(4 * nSeg);
  const depth = new Float64Array(nFace + nSeg);
  const order = new Uint32Array(nFace + nSeg);
  const polygon = (pts) => {
    ctx.beginPath();
    for (const p of pts) { const s = project(p); ctx.lineTo(s.x, s.y); } // the first: a move
    ctx.closePath();
  };
  const line = (a, b, stroke, width) => {
    const s = project(a), t = project(b);
    ctx.beginPath(); ctx.moveTo(s.x, s.y); ctx.lineTo(t.x, t.y);
    ctx.strokeStyle = stroke; ctx.lineWidth = width; ctx.stroke();
  };
  const disc = (p, radiusPx, fill) => {
    const s = project(p);
    ctx.beginPath(); ctx.arc(s.x, s.y, radiusPx, 0, 2 * Math.PI);
    ctx.fillStyle = fill; ctx.fill();
    ctx.strokeStyle = "rgba(0, 0, 0, 0.7)"; ctx.lineWidth = 1; ctx.stroke();
  };

  const drawBoundary = () => {
    for (const [a, b, c, d] of FACES) {
      polygon([a, b, c, d].map((k) => boundaryCorners[k]));
      ctx.fillStyle = "rgba(128, 128, 128, 0.04)"; ctx.fill();
      ctx.strokeStyle = "rgba(0, 0, 0, 0.5)"; ctx.lineWidth = 0.8; ctx.stroke();
    }
  };

  // Visible block faces and segments, far to near; equal consecutive styles in one stroke.
  const drawScene = () => {
    let n = 0;
    if (layers.blocks?.on) {
      for (let f = 0; f < nFace; f++) {
        const face = faces[f];
        const toEye = cam.eye.map((v, k) => v - face.centre[k]);
        if (dot(face.normal, toEye) <= 0) continue; // a back face
        depth[f] = project(face.centre).depth;
        order[n++] = f;
      }
    }
    for (let s = 0; s < nSeg; s++) {
      if (!layers[styles[segStyle[s]].layer].on) continue;
      const a = project(segPoints.subarray(6 * s, 6 * s + 3));
      const b = project(segPoints.subarray(6 * s + 3, 6 * s + 6));
      segScreen.set([a.x, a.y, b.x, b.y], 4 * s);
      depth[nFace + s] = (a.depth + b.depth) / 2;
      order[n++] = nFace + s;
    }
    let open = -1;
    const flush = () => { if (open >= 0) ctx.stroke(); open = -1; };
    ctx.lineCap = "round";
    for (const k of order.subarray(0, n).sort((a, b) => depth[a] - depth[b])) {
      if (k < nFace) {
        flush();
        polygon(faces[k].pts);
        ctx.fillStyle = faces[k].fill; ctx.fill();
        ctx.strokeStyle = "rgba(0, 0, 0, 0.25)"; ctx.lineWidth = 0.5; ctx.stroke();
        continue;
      }
      const s = k - nFace;
      if (segStyle[s] !== open) {
        flush();
        open = segStyle[s];
        ctx.beginPath();
        ctx.strokeStyle = styles[open].stroke; ctx.lineWidth = styles[open].width;
      }
      ctx.moveTo(segScreen[4 * s], segScreen[4 * s + 1]);
      ctx.lineTo(segScreen[4 * s + 2], segScreen[4 * s + 3]);
    }
    flush();
  };

  // Rotate the vector v by the unit quaternion q = (w, x, y, z).
  const rotate = (q, v) => {
    const [w, x, y, z] = q;
    const t = [2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])];
    return [v[0] + w * t[0] + y * t[2] - z * t[1], v[1] + w * t[1] + z * t[0] - x * t[2],
      v[2] + w * t[2] + x * t[1] - y * t[0]];
  };

  // Start, goal, a collision cross and the drone (arms, heading, a line down to the floor).
  const drawMarkers = () => {
    const sphere = (p, fill) => disc(p, Math.max(4, project(p).w * 0.02 * size), fill);
    if (data.start) sphere(data.start, START);
    if (data.goal) sphere(data.goal, GOAL);
    if (!data.flight) return;
    const f = data.flight, n = f.t.length;
    if (data.collision) {
      const s = project(point(f.position, n - 1));
      ctx.beginPath();
      ctx.moveTo(s.x - 8, s.y - 8); ctx.lineTo(s.x + 8, s.y + 8);
      ctx.moveTo(s.x - 8, s.y + 8); ctx.lineTo(s.x + 8, s.y - 8);
      ctx.strokeStyle = COLLISION; ctx.lineWidth = 3; ctx.stroke();
    }
    const p = point(f.position, index), q = f.attitude.slice(4 * index, 4 * index + 4);
    const arm = Math.max(data.armLength, 0.02 * size); // enlarged to be seen
    const at = (v) => rotate(q, v).map((x, k) => p[k] + x);
    line(p, [p[0], p[1], lo[2]], "rgba(0, 0, 0, 0.35)", 1);
    for (const [a, b] of [[1, 1], [1, -1]]) {
      const u = arm * Math.SQRT1_2;
      line(at([a * u, b * u, 0]), at([-a * u, -b * u, 0]), "#222", 2.5);
    }
    line(p, at([1.6 * arm, 0, 0]), DRONE, 2.5);
    disc(p, 4.5, DRONE);
  };

  // A round tick spacing (1, 2 or 5 times a power of ten) giving about `count` ticks.
  const niceStep = (span, count) => {
    const raw = span / count, unit = 10 ** Math.floor(Math.log10(raw)), m = raw / unit;
    return unit * (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10);
  };
  // Ticks and labels on three boundary edges: x and y along the floor edges nearest the
  // eye, z up the vertical edge furthest left on the screen.
  const drawAxes = () => {
    const near = (k) => (cam.e[k] > 0 ? hi[k] : lo[k]);
    const corners = [[lo[0], lo[1]], [hi[0], lo[1]], [lo[0], hi[1]], [hi[0], hi[1]]];
    const [zx, zy] = corners.reduce((best, c) =>
      (project([...c, lo[2]]).x < project([...best, lo[2]]).x ? c : best));
    const axes = [[(v) => [v, near(1), lo[2]], "x (m)"], [(v) => [near(0), v, lo[2]], "y (m)"],
      [(v) => [zx, zy, v], "z (m)"]];
    const middle = project(centre);
    ctx.fillStyle = "#333"; ctx.strokeStyle = "#333"; ctx.lineWidth = 1;
    ctx.textAlign = "center"; ctx.textBaseline = "middle"; ctx.font = "11px system-ui, sans-serif";
    axes.forEach(([at, label], k) => {
      const mid = project(at((lo[k] + hi[k]) / 2));
      let dx = mid.x - middle.x, dy = mid.y - middle.y;
      const len = Math.hypot(dx, dy) || 1;
      dx /= len; dy /= len; // outwards on the screen
      const a = project(at(lo[k])), b = project(at(hi[k])), px = Math.hypot(b.x - a.x, b.y - a.y);
      const step = niceStep(hi[k] - lo[k], clamp(px / 60, 1, 6));
      const decimals = Math.max(0, -Math.floor(Math.log10(step)));
      const crowded = px / ((hi[k] - lo[k]) / step) < 16; // px between tick labels
      for (let v = Math.ceil(lo[k] / step - 1e-9) * step; v <= hi[k] + 1e-9 * step; v += step) {
        const s = project(at(v));
        ctx.beginPath(); ctx.moveTo(s.x, s.y); ctx.lineTo(s.x + 5 * dx, s.y + 5 * dy); ctx.stroke();
        if (!crowded) ctx.fillText(v.toFixed(decimals), s.x + 16 * dx, s.y + 16 * dy);
      }
      ctx.font = "bold 12px system-ui, sans-serif";
      const away = 30 + ctx.measureText(label).width / 2 * Math.abs(dx) + 4 * Math.abs(dy);
      ctx.fillText(label, mid.x + away * dx, mid.y + away * dy);
      ctx.font = "11px system-ui, sans-serif";
    });
  };

  let pending = false, sceneStale = true, frames = 0;
  const render = () => {
    pending = false;
    const dpr = window.devicePixelRatio || 1;
    const width = canvas.clientWidth, height = canvas.clientHeight;
    const w = Math.round(width * dpr), h = Math.round(height * dpr);
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = scene.canvas.width = w;
      canvas.height = scene.canvas.height = h;
      sceneStale = true;
    }
    setCamera(width, height);
    if (sceneStale) {
      ctx = scene;
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      ctx.fillStyle = "#ffffff"; ctx.fillRect(0, 0, width, height);
      drawBoundary();
      drawScene();
      drawAxes();
      sceneStale = false;
    }
    ctx = screen;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.drawImage(scene.canvas, 0, 0);
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    drawMarkers();
    canvas.dataset.frames = String(++frames); // lets a test wait for a drawing
  };
  // Draw on the next frame; `moved` false when only the markers changed.
  const redraw = (moved = true) => {
    sceneStale ||= moved;
    if (!pending) { pending = true; requestAnimationFrame(render); }
  };
  new ResizeObserver(() => redraw()).observe(canvas);

  // ------------------------------------------------------------------ mouse
  let drag = null;
  canvas.addEventListener("pointerdown", (ev) => {
    drag = { x: ev.clientX, y: ev.clientY, pan: ev.shiftKey || ev.button !== 0 };
    canvas.setPointerCapture(ev.pointerId);
  });
  canvas.addEventListener("pointermove", (ev) => {
    if (!drag) return;
    const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
    drag.x = ev.clientX; drag.y = ev.clientY;
    if (drag.pan) { view.panX += dx; view.panY += dy; } else {
      view.azimuth -= 0.4 * dx;
      view.elevation = clamp(view.elevation + 0.4 * dy, -89, 89);
    }
    redraw();
  });
  for (const type of ["pointerup", "pointercancel"]) {
    canvas.addEventListener(type, () => { drag = null; });
  }
  canvas.addEventListener("wheel", (ev) => {
    ev.preventDefault();
    view.zoom = clamp(view.zoom * Math.exp(-0.0015 * ev.deltaY), 0.2, 50);
    redraw();
  }, { passive: false });
  canvas.addEventListener("dblclick", () => { view = { ...DEFAULT_VIEW }; redraw(); });
  canvas.addEventListener("contextmenu", (ev) => ev.preventDefault());

  // ------------------------------------------------------------------ time
  let index = 0, playing = false, clock = 0, lastTick = 0;
  const slider = $("time"), playButton = $("play");
  const showTime = () => {
    const f = data.flight, p = point(f.position, index).map((x) => x.toFixed(2));
    $("readout").textContent = `t = ${f.t[index].toFixed(2)} s\u2003position (${p.join(", ")}) m` +
      `\u2003speed ${f.speed[index].toFixed(2)} m/s`;
    slider.value = String(index);
    redraw(false);
  };
  const tick = (now) => {
    if (!playing) return;
    const t = data.flight.t, end = t[t.length - 1];
    clock = Math.min(end, clock + (now - lastTick) / 1000 * Number($("rate").value));
    lastTick = now;
    while (index + 1 < t.length && t[index + 1] <= clock) index++;
    if (clock >= end) setPlaying(false);
    showTime();
    if (playing) requestAnimationFrame(tick);
  };
  const setPlaying = (on) => {
    playing = on;
    playButton.textContent = on ? "pause" : "play";
    if (!on) return;
    const t = data.flight.t;
    if (index === t.length - 1) index = 0; // play again from the start
    clock = t[index];
    lastTick = performance.now();
    requestAnimationFrame(tick);
  };
  if (data.flight) {
    slider.max = String(data.flight.t.length - 1);
    slider.addEventListener("input", () => {
      index = Number(slider.value);
      clock = data.flight.t[index];
      showTime();
    });
    playButton.addEventListener("click", () => setPlaying(!playing));
    showTime();
  } else {
    $("timebar").hidden = true;
  }

  // ------------------------------------------------------------------ side panel
  $("title").textContent = data.title;
  $("subtitle").textContent = data.subtitle;
  const element = (tag, props, ...children) => {
    const e = Object.assign(document.createElement(tag), props);
    e.append(...children);
    return e;
  };
  for (const layer of Object.values(layers)) {
    const box = element("input", { type: "checkbox", checked: true });
    box.addEventListener("change", () => { layer.on = box.checked; redraw(); });
    $("layers").append(element("label", {}, box,
      element("span", { className: "swatch", style: `background: ${layer.swatch}` }), layer.label));
  }
  const markers = [["start", START], ["goal", GOAL]];
  if (data.flight) markers.push(["drone", DRONE]);
  if (data.collision) markers.push(["collision (\u00d7)", COLLISION]);
  for (const [label, colour] of markers) {
    $("layers").append(element("div", {},
      element("span", { className: "swatch dot", style: `background: ${colour}` }), label));
  }
  if (data.trajectory) {
    const stops = Array.from({ length: 11 }, (_, k) => viridis(k / 10)).join(", ");
    const ticks = [0, 0.5, 1].map((f) => element("span", {}, (f * speedMax).toFixed(2)));
    $("scale").append(
      element("div", { id: "scale-bar", style: `background: linear-gradient(to right, ${stops})` }),
      element("div", { id: "scale-ticks" }, ...ticks));
  } else {
    $("scale").textContent = "no trajectory (no path found)";
  }
  const format = (v) => {
    if (v === null || v === undefined) return "\u2014";
    if (typeof v === "boolean") return v ? "yes" : "no";
    if (typeof v === "number") return String(Number.isInteger(v) ? v : Number(v.toPrecision(4)));
    if (Array.isArray(v)) return `(${v.map(format).join(", ")})`;
    return String(v);
  };
  for (const [key, value] of Object.entries(data.metrics)) {
    $("metrics").append(element("tr", {}, element("td", {}, key),
      element("td", {}, format(value))));
  }
  redraw();
})();
