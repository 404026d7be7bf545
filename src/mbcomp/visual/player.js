// mbcomp's 3-D player: reads the scene JSON of mbcomp.visual.scene.Scene.to_json() from
// <script type="application/json" id="mbcomp-scene"> and plays it with three.js.
// Inlined by mbcomp.visual.html.write_html; "three" resolves through the page's import map.
// Units: m, s; quaternions in the scene are [w, x, y, z] (three.js takes x, y, z, w).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";

const BACKGROUND = 0xf4f6f8;
let resolveReady, rejectReady;
const api = { ready: new Promise((res, rej) => { resolveReady = res; rejectReady = rej; }) };
window.mbcomp = api;

// ---------------------------------------------------------------- scene data
function decode(b64, Kind = Float64Array) {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Kind(bytes.buffer);  // little-endian on every platform browsers run on
}

function quat(q) { return new THREE.Quaternion(q[1], q[2], q[3], q[0]); }

// index k and fraction a of t on the grid: t[k] <= t < t[k+1] (a = 0 exactly at grid points)
function locate(times, t) {
  const n = times.length;
  if (n === 1 || t <= times[0]) return [0, 0];
  if (t >= times[n - 1]) return [n - 1, 0];
  let lo = 0, hi = n - 1;
  while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (times[mid] <= t) lo = mid; else hi = mid; }
  const a = (t - times[lo]) / (times[lo + 1] - times[lo]);
  return [lo, a];
}

// pose of a link at (k, a): linear position, slerp of the quaternion (the shorter way)
function linkPose(P, k, a, out) {
  const i = 7 * k;
  if (a === 0) {
    out.p.set(P[i], P[i + 1], P[i + 2]);
    out.q.set(P[i + 4], P[i + 5], P[i + 6], P[i + 3]);
    return out;
  }
  const j = i + 7;
  out.p.set(P[i] + a * (P[j] - P[i]), P[i + 1] + a * (P[j + 1] - P[i + 1]), P[i + 2] + a * (P[j + 2] - P[i + 2]));
  out.q.set(P[i + 4], P[i + 5], P[i + 6], P[i + 3]);
  out.q.slerp(TMPQ.set(P[j + 4], P[j + 5], P[j + 6], P[j + 3]), a);
  return out;
}
const TMPQ = new THREE.Quaternion();

// ---------------------------------------------------------------- shapes
function material(v) {
  return new THREE.MeshStandardMaterial({
    color: new THREE.Color(v.color), roughness: 0.55, metalness: 0.1,
    transparent: v.opacity < 1, opacity: v.opacity, side: THREE.DoubleSide,
  });
}

function solid(v) {
  const s = v.shape;
  let geo;
  if (s.type === "box") geo = new THREE.BoxGeometry(s.size[0], s.size[1], s.size[2]);
  else if (s.type === "sphere") geo = new THREE.SphereGeometry(s.radius, 32, 16);
  else if (s.type === "cylinder") geo = new THREE.CylinderGeometry(s.radius, s.radius, s.length, 32).rotateX(Math.PI / 2);
  else if (s.type === "mesh") {
    geo = new THREE.BufferGeometry();
    geo.setAttribute("position", new THREE.BufferAttribute(decode(s.vertices, Float32Array), 3));
    geo.setIndex(new THREE.BufferAttribute(decode(s.faces, Uint32Array), 1));
    geo = geo.toNonIndexed();
    geo.computeVertexNormals();
  } else if (s.type === "grid") {
    const grid = new THREE.GridHelper(s.size, s.divisions, new THREE.Color(v.color).multiplyScalar(0.7), v.color);
    grid.rotateX(Math.PI / 2);  // three's grid lies in x-z; the shape's grid in its x-y plane
    const holder = new THREE.Group();
    holder.add(grid);
    return holder;
  } else throw new Error(`unknown shape type ${s.type} of ${v.name}`);
  return new THREE.Mesh(geo, material(v));
}

// a span (helix, rod) between two points, rebuilt or stretched at every frame
class Span {
  constructor(v, root) {
    this.v = v;
    this.obj = new THREE.Mesh(undefined, material(v));
    if (v.shape.type === "rod") this.obj.geometry = new THREE.CylinderGeometry(v.shape.radius, v.shape.radius, 1, 24);
    this.length = -1;
    root.add(this.obj);
  }

  update(a, b) {
    const d = new THREE.Vector3().subVectors(b, a);
    const L = d.length();
    const dir = L > 0 ? d.clone().divideScalar(L) : new THREE.Vector3(0, 0, 1);
    if (this.v.shape.type === "rod") {
      this.obj.position.copy(a).addScaledVector(d, 0.5);
      this.obj.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), dir);
      this.obj.scale.set(1, Math.max(L, 1e-9), 1);
      return;
    }
    this.obj.position.copy(a);
    this.obj.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), dir);
    if (Math.abs(L - this.length) > 1e-6 * Math.max(L, 1e-3)) {
      this.length = L;
      if (this.obj.geometry) this.obj.geometry.dispose();
      this.obj.geometry = helixGeometry(this.v.shape, Math.max(L, 1e-6));
    }
  }
}

function helixGeometry(s, L) {
  const turns = s.turns, R = s.radius;
  const curve = new THREE.Curve();
  curve.getPoint = (u, target = new THREE.Vector3()) => {
    const phi = 2 * Math.PI * turns * u;
    return target.set(R * Math.cos(phi), R * Math.sin(phi), L * u);
  };
  return new THREE.TubeGeometry(curve, 24 * turns, s.wire, 8, false);
}

// ---------------------------------------------------------------- colour by a column
const VIRIDIS = ["#440154", "#482878", "#3e4989", "#31688e", "#26828e", "#1f9e89", "#35b779", "#6ece58", "#b5de2b", "#fde725"];

function colormap(x, out) {
  const u = Math.min(Math.max(x, 0), 1) * (VIRIDIS.length - 1);
  const i = Math.min(Math.floor(u), VIRIDIS.length - 2);
  return out.set(VIRIDIS[i]).lerp(new THREE.Color(VIRIDIS[i + 1]), u - i);
}

function legend(c, panel) {
  const box = document.createElement("div");
  box.className = "legend";
  const fmt = (x) => Number(x).toPrecision(4);
  box.innerHTML = `<div class="name"></div><div class="bar" style="background:linear-gradient(to right,${VIRIDIS.join(",")})"></div>`
    + `<div class="ends"><span>${fmt(c.min)}</span><span>${fmt(c.max)}</span></div>`;
  box.querySelector(".name").textContent = `${c.component}: ${c.column}`;
  panel.appendChild(box);
}

// ---------------------------------------------------------------- the player
class Player {
  constructor(data, container) {
    this.data = data;
    this.times = decode(data.time);
    this.t = this.times[0];
    this.speed = data.speed || 1;
    this.playing = false;
    this.three = new THREE.Scene();
    this.three.background = new THREE.Color(BACKGROUND);
    this.poses = data.links.map((L) => (L.poses ? decode(L.poses) : null));
    this.groups = data.links.map((L) => { const g = new THREE.Group(); g.name = L.name; this.three.add(g); return g; });
    this.buildVisuals();
    this.buildBodies();
    this.buildTrails();
    this.colors = (data.colors || []).map((c) => ({ ...c, values: decode(c.values) }));
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.appendChild(this.renderer.domElement);
    this.camera = new THREE.PerspectiveCamera(35, 1, 1e-3, 1e3);
    this.camera.up.fromArray(data.up).normalize();  // before the controls: they orbit about camera.up as it is now
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => this.render());
    this.resize();
    this.pose(this.t);
    this.frame();
    this.lights();
  }

  buildVisuals() {
    this.spans = [];
    this.byComponent = {};
    for (const v of this.data.visuals) {
      let obj;
      if (v.to) { const s = new Span(v, this.three); s.from = v; this.spans.push(s); obj = s.obj; }
      else {
        obj = solid(v);
        obj.position.set(v.r[0], v.r[1], v.r[2]);
        obj.quaternion.copy(quat(v.q));
        this.groups[v.link].add(obj);
      }
      obj.name = v.name;
      obj.userData.grid = v.shape.type === "grid";
      (this.byComponent[v.component] ||= []).push(obj);
    }
  }

  buildBodies() {
    this.bodies = {};
    for (const [name, b] of Object.entries(this.data.bodies)) {
      const o = new THREE.Object3D();
      o.name = name;
      o.position.set(b.r[0], b.r[1], b.r[2]);
      o.quaternion.copy(quat(b.q));
      this.groups[b.link].add(o);
      this.bodies[name] = o;
    }
  }

  // the world positions of a point of a link at every output time (float64)
  pointPath(link, r) {
    const n = this.times.length, out = new Float64Array(3 * n), pose = { p: new THREE.Vector3(), q: new THREE.Quaternion() };
    const v = new THREE.Vector3();
    for (let k = 0; k < n; k++) {
      v.set(r[0], r[1], r[2]);
      if (this.poses[link]) { linkPose(this.poses[link], k, 0, pose); v.applyQuaternion(pose.q).add(pose.p); }
      out.set([v.x, v.y, v.z], 3 * k);
    }
    return out;
  }

  buildTrails() {
    this.trails = (this.data.trails || []).map((tr) => {
      const path = this.pointPath(tr.link, tr.r);
      const geo = new THREE.BufferGeometry();
      const buf = new Float32Array(path.length + 3);
      geo.setAttribute("position", new THREE.BufferAttribute(buf, 3));
      const line = new THREE.Line(geo, new THREE.LineBasicMaterial({ color: tr.color }));
      line.frustumCulled = false;
      this.three.add(line);
      return { tr, path, buf, geo };
    });
  }

  pointAt(link, r, target) {
    target.set(r[0], r[1], r[2]);
    return this.groups[link].localToWorld(target);
  }

  // everything at time t (s), interpolated between output times
  pose(t) {
    const n = this.times.length;
    this.t = Math.min(Math.max(t, this.times[0]), this.times[n - 1]);
    const [k, a] = locate(this.times, this.t);
    const pose = { p: new THREE.Vector3(), q: new THREE.Quaternion() };
    this.poses.forEach((P, i) => {
      if (!P) return;
      linkPose(P, k, a, pose);
      this.groups[i].position.copy(pose.p);
      this.groups[i].quaternion.copy(pose.q);
    });
    this.three.updateMatrixWorld(true);
    const A = new THREE.Vector3(), B = new THREE.Vector3();
    for (const s of this.spans) s.update(this.pointAt(s.v.link, s.v.r, A), this.pointAt(s.v.to.link, s.v.to.r, B));
    for (const T of this.trails) {
      T.buf.set(T.path.subarray(0, 3 * (k + 1)));
      const c = this.pointAt(T.tr.link, T.tr.r, A);
      T.buf.set([c.x, c.y, c.z], 3 * (k + 1));
      T.geo.setDrawRange(0, k + 2);
      T.geo.attributes.position.needsUpdate = true;
    }
    const col = new THREE.Color();
    for (const c of this.colors) {
      const v = a === 0 ? c.values[k] : c.values[k] + a * (c.values[k + 1] - c.values[k]);
      colormap(c.max > c.min ? (v - c.min) / (c.max - c.min) : 0.5, col);
      for (const o of this.byComponent[c.component] || []) if (o.material && o.material.color) o.material.color.copy(col);
    }
    this.three.updateMatrixWorld(true);
    if (this.follow) {
      const c = this.centroid(), d = c.clone().sub(this.anchor);
      this.anchor.copy(c);
      this.camera.position.add(d);
      this.controls.target.add(d);
      this.controls.update();
    }
    if (this.onTime) this.onTime(this.t);
  }

  // the camera on the mechanism: the box of its shapes (not the ground) and of the motion
  // the box of the mechanism's shapes now (not the ground) and, with motion, of every link origin
  // and trail point over the run
  bounds(motion) {
    const box = new THREE.Box3();
    for (const g of this.groups) for (const o of g.children) if (!o.userData.grid && o.isMesh) box.expandByObject(o);
    for (const s of this.spans) box.expandByObject(s.obj);
    const v = new THREE.Vector3();
    if (motion) {
      this.poses.forEach((P) => {
        if (P) for (let i = 0; i < P.length; i += 7) box.expandByPoint(v.set(P[i], P[i + 1], P[i + 2]));
      });
      for (const T of this.trails) for (let i = 0; i < T.path.length; i += 3) box.expandByPoint(v.fromArray(T.path, i));
    }
    if (box.isEmpty()) box.setFromCenterAndSize(new THREE.Vector3(), new THREE.Vector3(1, 1, 1).multiplyScalar(this.data.scale));
    return box;
  }

  // the mean origin of the moving links at the current time (m, world)
  centroid() {
    const c = new THREE.Vector3();
    let n = 0;
    this.groups.forEach((g, i) => { if (this.poses[i]) { c.add(g.position); n++; } });
    return n ? c.divideScalar(n) : c;
  }

  // a mechanism that travels far (a vehicle) is framed as it is now and followed; one that
  // stays in place is framed with all of its motion
  frame() {
    const still = this.bounds(false), all = this.bounds(true);
    const reach = still.getSize(new THREE.Vector3()).length();
    this.follow = all.getSize(new THREE.Vector3()).length() > 2.5 * Math.max(reach, 1e-9);
    this.anchor = this.centroid();
    const box = this.follow ? still : all, size = box.getSize(new THREE.Vector3()), centre = box.getCenter(new THREE.Vector3());
    const up = new THREE.Vector3().fromArray(this.data.up).normalize();
    const axes = [new THREE.Vector3(1, 0, 0), new THREE.Vector3(0, 1, 0), new THREE.Vector3(0, 0, 1)];
    const sizes = [size.x, size.y, size.z];
    // look along the thinnest extent of the mechanism (its plane's normal), unless that is up
    let order = [0, 1, 2].sort((i, j) => sizes[i] - sizes[j]);
    let n = axes[order.find((i) => Math.abs(axes[i].dot(up)) < 0.9) ?? order[0]].clone();
    const right = new THREE.Vector3().crossVectors(up, n);
    const big = Math.max(Math.abs(right.x), Math.abs(right.y), Math.abs(right.z));
    if ([right.x, right.y, right.z].find((c) => Math.abs(c) === big) < 0) { n.negate(); right.negate(); }
    const dir = n.clone().addScaledVector(up, 0.45).addScaledVector(right, 0.3).normalize();
    const dist = this.fitDistance(box, centre, dir, up);
    this.camera.up.copy(up);
    this.camera.position.copy(centre).addScaledVector(dir, dist);
    this.camera.near = dist / 100;
    this.camera.far = dist * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.home = { centre, dir, dist, up };
  }

  // the distance along dir from centre at which the camera sees all of the box, with a margin
  fitDistance(box, centre, dir, up) {
    const right = new THREE.Vector3().crossVectors(dir, up).normalize(), top = new THREE.Vector3().crossVectors(right, dir);
    const tv = Math.tan(THREE.MathUtils.degToRad(this.camera.fov) / 2), th = tv * this.camera.aspect;
    let dist = 1e-6 * this.data.scale;
    const c = new THREE.Vector3();
    for (let i = 0; i < 8; i++) {
      c.set(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z).sub(centre);
      const z = c.dot(dir);
      dist = Math.max(dist, z + Math.abs(c.dot(right)) / th, z + Math.abs(c.dot(top)) / tv);
    }
    return 1.25 * dist;
  }

  lights() {
    const { centre, dir, dist, up } = this.home;
    const hemi = new THREE.HemisphereLight(0xffffff, 0x8d8d8d, 1.6);
    hemi.position.copy(up);
    this.three.add(hemi);
    const key = new THREE.DirectionalLight(0xffffff, 2.2);
    key.position.copy(centre).addScaledVector(dir, dist).addScaledVector(up, dist);
    key.target.position.copy(centre);
    const fill = new THREE.DirectionalLight(0xffffff, 0.8);
    fill.position.copy(centre).addScaledVector(dir, -dist).addScaledVector(up, 0.5 * dist);
    fill.target.position.copy(centre);
    this.three.add(key, key.target, fill, fill.target);
  }

  resize() {
    const w = window.innerWidth, h = window.innerHeight;
    this.renderer.setSize(w, h);
    this.camera.aspect = w / Math.max(h, 1);
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() { if (this.camera) this.renderer.render(this.three, this.camera); }

  tick(now) {
    if (!this.playing) return;
    const t0 = this.times[0], t1 = this.times[this.times.length - 1];
    let t = this.t + this.speed * (now - this.last) / 1000;
    this.last = now;
    if (t > t1) t = t0 + ((t - t0) % Math.max(t1 - t0, 1e-12));
    this.pose(t);
    this.render();
    requestAnimationFrame((x) => this.tick(x));
  }

  play() {
    if (this.playing) return;
    if (this.t >= this.times[this.times.length - 1]) this.pose(this.times[0]);
    this.playing = true;
    this.last = performance.now();
    requestAnimationFrame((x) => this.tick(x));
    if (this.onPlay) this.onPlay(true);
  }

  pause() { this.playing = false; if (this.onPlay) this.onPlay(false); }
}

// ---------------------------------------------------------------- page controls
function controls(player, panel) {
  const t0 = player.times[0], t1 = player.times[player.times.length - 1];
  const bar = document.getElementById("mbcomp-controls");
  const button = bar.querySelector("#play"), slider = bar.querySelector("#slider");
  const label = bar.querySelector("#time"), speed = bar.querySelector("#speed");
  slider.min = t0; slider.max = t1; slider.step = "any";
  const digits = Math.max(0, Math.min(6, 2 - Math.floor(Math.log10(Math.max(t1 - t0, 1e-9) / 100))));
  player.onTime = (t) => { slider.value = t; label.textContent = `t = ${t.toFixed(digits)} s / ${t1.toFixed(digits)} s`; };
  player.onPlay = (on) => { button.textContent = on ? "\u23F8 pause" : "\u25B6 play"; };
  button.addEventListener("click", () => (player.playing ? player.pause() : player.play()));
  slider.addEventListener("input", () => { player.pause(); player.pose(Number(slider.value)); player.render(); });
  for (const s of [0.1, 0.25, 0.5, 1, 2, 4, 10]) {
    const o = document.createElement("option");
    o.value = s; o.textContent = `${s}\u00D7`;
    speed.appendChild(o);
  }
  if (![...speed.options].some((o) => Number(o.value) === player.speed)) {
    const o = document.createElement("option"); o.value = player.speed; o.textContent = `${player.speed}\u00D7`; speed.appendChild(o);
  }
  speed.value = player.speed;
  speed.addEventListener("change", () => { player.speed = Number(speed.value); });
  window.addEventListener("keydown", (e) => { if (e.code === "Space") { e.preventDefault(); button.click(); } });
  for (const c of player.colors) legend(c, panel);
  player.onTime(player.t);
  player.onPlay(false);
}

function digest(renderer) {
  const gl = renderer.getContext(), w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(4 * w * h);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const br = (BACKGROUND >> 16) & 255, bgc = (BACKGROUND >> 8) & 255, bb = BACKGROUND & 255;  // sRGB bytes
  let count = 0, hash = 2166136261;
  for (let i = 0; i < px.length; i += 4) {
    if (Math.abs(px[i] - br) > 2 || Math.abs(px[i + 1] - bgc) > 2 || Math.abs(px[i + 2] - bb) > 2) count++;
    if ((i >> 2) % 7 === 0) hash = Math.imul(hash ^ (px[i] ^ (px[i + 1] << 8) ^ (px[i + 2] << 16)), 16777619) >>> 0;
  }
  return { width: w, height: h, nonBackground: count, hash: hash.toString(16) };
}

function start() {
  const data = JSON.parse(document.getElementById("mbcomp-scene").textContent);
  const player = new Player(data, document.getElementById("mbcomp-view"));
  const panel = document.getElementById("mbcomp-legends");
  controls(player, panel);
  window.addEventListener("resize", () => player.resize());
  Object.assign(api, {
    player, THREE,
    setTime(t) { player.pause(); player.pose(Number(t)); player.render(); return player.t; },
    play() { player.play(); },
    pause() { player.pause(); },
    time() { return player.t; },
    duration() { return player.times[player.times.length - 1] - player.times[0]; },
    times() { return Array.from(player.times); },
    bodies() { return Object.keys(player.bodies); },
    bodyPose(name) {
      const o = player.bodies[name];
      if (!o) throw new Error(`no body ${name}: the scene has ${Object.keys(player.bodies).join(", ")}`);
      const p = o.getWorldPosition(new THREE.Vector3()), q = o.getWorldQuaternion(new THREE.Quaternion());
      return { r: [p.x, p.y, p.z], q: [q.w, q.x, q.y, q.z] };
    },
    pixels() { player.render(); return digest(player.renderer); },
  });
  player.render();
  requestAnimationFrame(() => resolveReady(api));
}

try { start(); } catch (err) {
  const box = document.getElementById("mbcomp-error");
  box.textContent = `The player could not start: ${err.message}`;
  box.style.display = "block";
  rejectReady(err);
}
