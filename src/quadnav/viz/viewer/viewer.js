// quadnav run viewer: the map, explored tree, path, trajectory (coloured by speed), flown
// track and the drone's body box moving in time, drawn by three.js (WebGL, with a depth
// buffer) and turned with its OrbitControls. The run is the JSON in #run-data, written by
// quadnav.viz.html_viewer (positions flattened x, y, z, ...). Lengths in m, times in s;
// world z is up. window.quadnavViewer offers the camera and two helpers, for the console
// and the tests: setView(azimuthDeg, elevationDeg) and screenOf([x, y, z]) (CSS px in the
// canvas).
"use strict";
(() => {
  const data = JSON.parse(document.getElementById("run-data").textContent);
  const $ = (id) => document.getElementById(id);
  const canvas = $("view");
  const clamp = (x, a, b) => Math.min(Math.max(x, a), b);
  const point = (flat, i) => [flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]];

  // ------------------------------------------------------------------ colours and layers
  const VIRIDIS = [[68, 1, 84], [72, 40, 120], [62, 73, 137], [49, 104, 142], [38, 130, 142],
    [31, 158, 137], [53, 183, 121], [110, 206, 88], [181, 222, 43], [253, 231, 37]];
  const viridisRgb = (f) => {
    const x = clamp(f, 0, 1) * (VIRIDIS.length - 1);
    const i = Math.min(Math.floor(x), VIRIDIS.length - 2);
    return VIRIDIS[i].map((a, k) => a + (x - i) * (VIRIDIS[i + 1][k] - a));
  };
  const viridis = (f) => `rgb(${viridisRgb(f).map(Math.round)})`;
  const START = "#e00000", GOAL = "#008000", PATH = "#e00000", FLOWN = "#111111";
  const TRUTH = "#9467bd"; // a Tello run's true track (matplotlib's tab:purple)
  const TREE = "#598cd9", DRONE = "#ff7f0e", COLLISION = "#e000e0";
  const layers = {}; // name -> {label, swatch, shown at first, objects}
  const addLayer = (name, label, swatch, shown = true) => {
    layers[name] = { label, swatch, shown, objects: [] };
  };
  if (data.blocks.length) addLayer("blocks", `blocks (${data.blocks.length / 6})`,
    `rgb(${data.colors.slice(0, 3).map((x) => Math.round(255 * x))})`);
  if (data.tree.length) {
    const drawn = data.tree.length / 6;
    // off at first when there is a path (thousands of edges would bury it, the trajectory
    // and the flight), and dimmed beneath them when shown
    addLayer("tree", `tree (${data.treeEdges.toLocaleString("en")} edges` +
      (drawn < data.treeEdges ? `, ${drawn.toLocaleString("en")} drawn)` : ")"),
      "rgba(89, 140, 217, 0.3)", !data.path);
  }
  if (data.path) addLayer("path", `path (${data.path.length / 3} waypoints)`, PATH);
  if (data.trajectory) addLayer("trajectory", "trajectory (colour: speed)",
    `linear-gradient(to right, ${viridis(0)}, ${viridis(0.5)}, ${viridis(1)})`);
  if (data.flight) addLayer("flown", "flown track", FLOWN);
  if (data.truth) addLayer("truth", "true track", TRUTH);
  const speedMax = data.trajectory ? data.trajectory.speed.reduce((a, b) => Math.max(a, b), 1e-9)
    : 0;

  // ------------------------------------------------------------------ side panel
  const element = (tag, props, ...children) => {
    const e = Object.assign(document.createElement(tag), props);
    e.append(...children);
    return e;
  };
  $("title").textContent = data.title;
  $("subtitle").textContent = data.subtitle;
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
  if (data.trajectory) {
    const stops = Array.from({ length: 11 }, (_, k) => viridis(k / 10)).join(", ");
    const ticks = [0, 0.5, 1].map((f) => element("span", {}, (f * speedMax).toFixed(2)));
    $("scale").append(
      element("div", { id: "scale-bar", style: `background: linear-gradient(to right, ${stops})` }),
      element("div", { id: "scale-ticks" }, ...ticks));
  } else {
    $("scale").textContent = "no trajectory (no path found)";
  }

  // ------------------------------------------------------------------ renderer
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  } catch (error) {
    $("nowebgl").hidden = false;
    $("timebar").hidden = true;
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setClearColor(0xffffff, 1);
  const scene = new THREE.Scene();
  const lo = data.boundary.slice(0, 3), hi = data.boundary.slice(3, 6);
  const centre = new THREE.Vector3(...lo.map((a, k) => (a + hi[k]) / 2));
  const radius = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2;
  const size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  const sun = new THREE.DirectionalLight(0xffffff, 0.55);
  sun.position.set(0.3, 0.5, 0.81).add(centre);
  sun.target.position.copy(centre);
  scene.add(sun, sun.target);

  const wideLines = []; // LineMaterials, whose resolution follows the canvas
  const wideLine = (flat, width, colour, colours) => {
    const geometry = new THREE.LineGeometry();
    geometry.setPositions(flat);
    // drawn after the tree and the other lines before them, none writing depth, so each
    // lies on those: the tree under the path, the trajectory and the flown track, in that
    // order; blocks in front still hide them
    const material = new THREE.LineMaterial({ color: colour ?? 0xffffff, linewidth: width,
      vertexColors: Boolean(colours), transparent: true, depthWrite: false });
    if (colours) geometry.setColors(colours);
    wideLines.push(material);
    const line = new THREE.Line2(geometry, material);
    line.renderOrder = wideLines.length;
    line.computeLineDistances();
    return line;
  };
  const segments = (flat, material) => {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.Float32BufferAttribute(flat, 3));
    return new THREE.LineSegments(geometry, material);
  };
  const boxEdges = (b) => {
    const c = Array.from({ length: 8 }, (_, n) => [0, 1, 2].map((k) => ((n >> k) & 1 ? b[k + 3] : b[k])));
    const EDGES = [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5],
      [2, 6], [3, 7]];
    return EDGES.flatMap(([a, d]) => [...c[a], ...c[d]]);
  };

  // the boundary: its edges and a faint floor
  scene.add(segments(boxEdges(data.boundary),
    new THREE.LineBasicMaterial({ color: 0x000000, transparent: true, opacity: 0.5 })));
  const floor = new THREE.Mesh(new THREE.PlaneGeometry(hi[0] - lo[0], hi[1] - lo[1]),
    new THREE.MeshBasicMaterial({ color: 0x808080, transparent: true, opacity: 0.08,
      depthWrite: false, side: THREE.DoubleSide }));
  floor.position.set(centre.x, centre.y, lo[2]);
  scene.add(floor);

  // blocks: one instanced unit box, placed, sized and coloured per block, with their edges
  const nBlocks = data.blocks.length / 6;
  if (nBlocks) {
    const blocks = new THREE.InstancedMesh(new THREE.BoxGeometry(1, 1, 1),
      new THREE.MeshLambertMaterial(), nBlocks);
    const matrix = new THREE.Matrix4(), colour = new THREE.Color();
    const edges = [];
    for (let i = 0; i < nBlocks; i++) {
      const b = data.blocks.slice(6 * i, 6 * i + 6);
      matrix.makeScale(b[3] - b[0], b[4] - b[1], b[5] - b[2])
        .setPosition((b[0] + b[3]) / 2, (b[1] + b[4]) / 2, (b[2] + b[5]) / 2);
      blocks.setMatrixAt(i, matrix);
      blocks.setColorAt(i, colour.setRGB(...data.colors.slice(3 * i, 3 * i + 3)));
      edges.push(...boxEdges(b));
    }
    const outline = segments(edges, new THREE.LineBasicMaterial({ color: 0x000000,
      transparent: true, opacity: 0.25 }));
    layers.blocks.objects.push(blocks, outline);
  }
  if (data.tree.length) {
    layers.tree.objects.push(segments(data.tree, new THREE.LineBasicMaterial({ color: TREE,
      transparent: true, opacity: data.path ? 0.2 : 0.45, depthWrite: false })));
  }
  if (data.path) layers.path.objects.push(wideLine(data.path, 2.4, PATH));
  if (data.trajectory) {
    const v = data.trajectory.speed;
    const colours = v.flatMap((s) => viridisRgb(s / speedMax).map((c) => c / 255));
    layers.trajectory.objects.push(wideLine(data.trajectory.position, 3, null, colours));
  }
  if (data.flight) layers.flown.objects.push(wideLine(data.flight.position, 1.5, FLOWN));
  if (data.truth) layers.truth.objects.push(wideLine(data.truth, 1.5, TRUTH));
  for (const layer of Object.values(layers)) {
    for (const object of layer.objects) object.visible = layer.shown;
    scene.add(...layer.objects);
  }

  // start, goal, and where a collision stopped the flight
  const ball = (p, colour, r) => {
    const mesh = new THREE.Mesh(new THREE.SphereGeometry(r, 24, 16),
      new THREE.MeshLambertMaterial({ color: colour }));
    mesh.position.set(...p);
    scene.add(mesh);
  };
  if (data.start) ball(data.start, START, 0.012 * size);
  if (data.goal) ball(data.goal, GOAL, 0.012 * size);
  if (data.flight && data.collision) {
    const mesh = new THREE.Mesh(new THREE.OctahedronGeometry(0.015 * size),
      new THREE.MeshBasicMaterial({ color: COLLISION }));
    mesh.position.set(...point(data.flight.position, data.flight.t.length - 1));
    scene.add(mesh);
  }

  // the drone: its body box, two arms and a heading mark, enlarged to be seen; a line
  // down to the floor
  const drone = new THREE.Group();
  const drop = new THREE.Line(new THREE.BufferGeometry().setFromPoints(
    [new THREE.Vector3(), new THREE.Vector3()]),
  new THREE.LineBasicMaterial({ color: 0x000000, transparent: true, opacity: 0.35 }));
  if (data.flight) {
    const arm = Math.max(data.armLength, 1e-3);
    const body = data.bodySize.map((s) => Math.max(s, 0.2 * arm));
    const box = (sx, sy, sz, colour) => new THREE.Mesh(new THREE.BoxGeometry(sx, sy, sz),
      new THREE.MeshLambertMaterial({ color: colour }));
    drone.add(box(...body, DRONE));
    for (const angle of [Math.PI / 4, -Math.PI / 4]) {
      const beam = box(2 * arm, 0.12 * arm, 0.06 * arm, 0x222222);
      beam.rotation.z = angle;
      drone.add(beam);
    }
    const nose = box(0.9 * arm, 0.12 * arm, 0.12 * arm, DRONE);
    nose.position.x = body[0] / 2 + 0.45 * arm;
    drone.add(nose);
    drone.scale.setScalar(Math.max(1, 0.02 * size / arm));
    scene.add(drone, drop);
  }

  // ------------------------------------------------------------------ camera
  const camera = new THREE.PerspectiveCamera(30, 1, radius / 100, radius * 100);
  camera.up.set(0, 0, 1);
  const controls = new THREE.OrbitControls(camera, canvas);
  controls.target.copy(centre);
  controls.screenSpacePanning = true;
  const setView = (azimuthDeg, elevationDeg) => {
    const az = azimuthDeg * Math.PI / 180, el = elevationDeg * Math.PI / 180;
    const distance = 4 * radius;
    camera.position.set(centre.x + distance * Math.cos(el) * Math.cos(az),
      centre.y + distance * Math.cos(el) * Math.sin(az), centre.z + distance * Math.sin(el));
    controls.target.copy(centre);
    controls.update();
    redraw();
  };

  // ------------------------------------------------------------------ axis labels
  const labelLayer = $("labels");
  const toScreen = (p) => {
    const v = new THREE.Vector3(...p).project(camera);
    return [(v.x + 1) / 2 * canvas.clientWidth, (1 - v.y) / 2 * canvas.clientHeight];
  };
  const niceStep = (span, count) => {
    const raw = span / count, unit = 10 ** Math.floor(Math.log10(raw)), m = raw / unit;
    return unit * (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10);
  };
  // Tick values on the floor edges nearest the eye (x, y) and a vertical edge (z), each
  // pushed outwards on the screen; the axis name beyond its middle.
  const drawLabels = () => {
    const eye = camera.position;
    const near = (k) => (eye.getComponent(k) > centre.getComponent(k) ? hi[k] : lo[k]);
    const far = (k) => (eye.getComponent(k) > centre.getComponent(k) ? lo[k] : hi[k]);
    const axes = [[(v) => [v, near(1), lo[2]], "x (m)"], [(v) => [near(0), v, lo[2]], "y (m)"],
      [(v) => [near(0), far(1), v], "z (m)"]];
    const middle = toScreen(centre.toArray());
    const spans = [];
    axes.forEach(([at, name], k) => {
      const mid = toScreen(at((lo[k] + hi[k]) / 2));
      let dx = mid[0] - middle[0], dy = mid[1] - middle[1];
      const len = Math.hypot(dx, dy) || 1;
      dx /= len; dy /= len;
      const a = toScreen(at(lo[k])), b = toScreen(at(hi[k]));
      const px = Math.hypot(b[0] - a[0], b[1] - a[1]);
      const step = niceStep(hi[k] - lo[k], clamp(px / 60, 1, 6));
      const decimals = Math.max(0, -Math.floor(Math.log10(step)));
      if (px / ((hi[k] - lo[k]) / step) >= 16) {
        for (let v = Math.ceil(lo[k] / step - 1e-9) * step; v <= hi[k] + 1e-9 * step; v += step) {
          const s = toScreen(at(v));
          spans.push(["tick", v.toFixed(decimals), s[0] + 14 * dx, s[1] + 14 * dy]);
        }
      }
      spans.push(["axis", name, mid[0] + 36 * dx, mid[1] + 36 * dy]);
    });
    labelLayer.replaceChildren(...spans.map(([kind, text, x, y]) => element("span",
      { className: kind, textContent: text, style: `left: ${x}px; top: ${y}px` })));
  };

  // ------------------------------------------------------------------ drawing
  let index = 0, pending = false, frames = 0;
  const placeDrone = () => {
    if (!data.flight) return;
    const f = data.flight, p = point(f.position, index), q = f.attitude.slice(4 * index, 4 * index + 4);
    drone.position.set(...p);
    drone.quaternion.set(q[1], q[2], q[3], q[0]); // three.js: (x, y, z, w)
    drop.geometry.setFromPoints([new THREE.Vector3(...p), new THREE.Vector3(p[0], p[1], lo[2])]);
  };
  const render = () => {
    pending = false;
    const width = canvas.clientWidth, height = canvas.clientHeight;
    const buffer = renderer.getSize(new THREE.Vector2());
    if (buffer.x !== width || buffer.y !== height) {
      renderer.setSize(width, height, false);
      camera.aspect = width / Math.max(height, 1);
      camera.updateProjectionMatrix();
      for (const material of wideLines) material.resolution.set(width, height);
    }
    placeDrone();
    renderer.render(scene, camera);
    drawLabels();
    canvas.dataset.frames = String(++frames); // lets a test wait for a drawing
  };
  const redraw = () => {
    if (!pending) { pending = true; requestAnimationFrame(render); }
  };
  controls.addEventListener("change", redraw);
  new ResizeObserver(() => redraw()).observe(canvas);
  setView(-60, 30);
  controls.saveState();
  canvas.addEventListener("dblclick", () => { controls.reset(); redraw(); });
  canvas.addEventListener("contextmenu", (ev) => ev.preventDefault());

  // ------------------------------------------------------------------ layers panel
  for (const layer of Object.values(layers)) {
    const box = element("input", { type: "checkbox", checked: layer.shown });
    box.addEventListener("change", () => {
      for (const object of layer.objects) object.visible = box.checked;
      redraw();
    });
    $("layers").append(element("label", {}, box,
      element("span", { className: "swatch", style: `background: ${layer.swatch}` }), layer.label));
  }
  const markers = [];
  if (data.start) markers.push(["start", START]);
  if (data.goal) markers.push(["goal", GOAL]);
  if (data.flight) markers.push(["drone (body box)", DRONE]);
  if (data.collision) markers.push(["collision (\u25c6)", COLLISION]);
  for (const [label, colour] of markers) {
    $("layers").append(element("div", {},
      element("span", { className: "swatch dot", style: `background: ${colour}` }), label));
  }

  // ------------------------------------------------------------------ time
  let playing = false, clock = 0, lastTick = 0;
  const slider = $("time"), playButton = $("play");
  const showTime = () => {
    const f = data.flight, p = point(f.position, index).map((x) => x.toFixed(2));
    $("readout").textContent = `t = ${f.t[index].toFixed(2)} s\u2003position (${p.join(", ")}) m` +
      `\u2003speed ${f.speed[index].toFixed(2)} m/s`;
    slider.value = String(index);
    redraw();
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
  window.quadnavViewer = { camera, controls, setView, screenOf: toScreen };
  redraw();
})();
