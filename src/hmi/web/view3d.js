// The 3D view: the program's path (rapids dashed, feed moves coloured by speed on a scale of
// their own), the machine's travel box, the tool at its live position with a trail.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const TRAIL_POINTS = 20000;  // fixed buffer: the page's memory does not grow with the run
const RENDER_FPS = 15;

// Blue → cyan → green → yellow → red for f in 0…1 (the legend's gradient).
export function speedColor(f, out) {
  const stops = [[0.19, 0.25, 1], [0, 0.75, 1], [0, 0.88, 0.38], [0.94, 0.88, 0], [1, 0.19, 0]];
  const x = Math.min(Math.max(f, 0), 1) * (stops.length - 1);
  const i = Math.min(Math.floor(x), stops.length - 2);
  const t = x - i;
  for (let k = 0; k < 3; ++k) out[k] = stops[i][k] + (stops[i + 1][k] - stops[i][k]) * t;
  return out;
}

export class View3D {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.renderer.setClearColor(0x15181c);
    container.appendChild(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(40, 1, 0.1, 100000);
    this.camera.up.set(0, 0, 1);  // machine Z up
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.dirty = true);
    this.pathGroup = new THREE.Group();
    this.scene.add(this.pathGroup);
    this.box = new THREE.Box3(new THREE.Vector3(-100, -100, -100), new THREE.Vector3(100, 100, 100));
    this.pathBox = null;
    this.makeTool();
    this.makeTrail();
    this.scene.add(new THREE.AxesHelper(30));
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
    this.dirty = true;
    // At most RENDER_FPS frames a second, and only when something changed: a path of 100 000
    // segments drawn in software GL must not take the time the status events need.
    let last = 0;
    const loop = (now) => {
      if (this.dirty && now - last >= 1000 / RENDER_FPS) {
        this.renderer.render(this.scene, this.camera);
        this.dirty = false;
        last = now;
      }
      requestAnimationFrame(loop);
    };
    requestAnimationFrame(loop);
  }

  resize() {
    const w = Math.max(this.container.clientWidth, 10), h = Math.max(this.container.clientHeight, 10);
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.dirty = true;
  }

  makeTool() {
    const cone = new THREE.ConeGeometry(3, 12, 16);
    cone.rotateX(-Math.PI / 2);   // tip along −Z
    cone.translate(0, 0, 6);      // tip at the origin: the tool's point
    this.tool = new THREE.Mesh(cone, new THREE.MeshBasicMaterial({ color: 0xff9800 }));
    this.scene.add(this.tool);
  }

  makeTrail() {
    this.trailPos = new Float32Array(TRAIL_POINTS * 3);
    this.trailCol = new Float32Array(TRAIL_POINTS * 3);
    this.trailCount = 0;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(this.trailPos, 3));
    g.setAttribute('color', new THREE.BufferAttribute(this.trailCol, 3));
    g.setDrawRange(0, 0);
    this.trail = new THREE.Line(g, new THREE.LineBasicMaterial({ vertexColors: true }));
    this.trail.frustumCulled = false;
    this.scene.add(this.trail);
    this.trailColor = [0, 0, 0];
  }

  setMachine(machine) {
    const min = new THREE.Vector3(), max = new THREE.Vector3();
    const idx = { X: 'x', Y: 'y', Z: 'z' };
    for (const a of machine.axes) {
      if (!(a.name in idx)) continue;
      min[idx[a.name]] = a.min_mm;
      max[idx[a.name]] = a.max_mm;
    }
    this.box.set(min, max);
    if (this.boxHelper) this.scene.remove(this.boxHelper);
    this.boxHelper = new THREE.Box3Helper(this.box, 0x4a5260);
    this.scene.add(this.boxHelper);
    if (machine.stock) {  // [stock]: the raw part, translucent
      const [sx, sy, sz] = machine.stock.size_mm, [mx, my, mz] = machine.stock.min_mm;
      const g = new THREE.BoxGeometry(sx, sy, sz);
      g.translate(mx + sx / 2, my + sy / 2, mz + sz / 2);
      this.stock = new THREE.Mesh(g, new THREE.MeshBasicMaterial(
          { color: 0x8d9bb0, transparent: true, opacity: 0.18, depthWrite: false }));
      this.scene.add(this.stock);
    }
    this.setView('iso');
  }

  // The program as /api/program gives it; returns [lo, hi], the feed range of the colour scale.
  setPath(program) {
    this.program = program;
    for (const c of [...this.pathGroup.children]) {
      c.geometry.dispose();
      c.material.dispose();
      this.pathGroup.remove(c);
    }
    const n = program.vertices || 0;
    const xyz = program.xyz || [], kind = program.kind || [], feed = program.feed || [];
    let lo = Infinity, hi = -Infinity;
    for (let i = 1; i < n; ++i) {
      if (kind[i] === 1) { lo = Math.min(lo, feed[i]); hi = Math.max(hi, feed[i]); }
    }
    if (!(hi >= lo)) { lo = 0; hi = 1; }
    if (hi - lo < 1) hi = lo + 1;
    this.feedRange = [lo, hi];
    // Typed arrays sized first: a path of 400 000 vertices builds without growing JS arrays.
    let nCut = 0, nRapid = 0;
    for (let i = 1; i < n; ++i) {
      if (kind[i] === 1) ++nCut; else if (kind[i] === 0) ++nRapid;
    }
    const cut = new Float32Array(nCut * 6), cutCol = new Float32Array(nCut * 6);
    const rapid = new Float32Array(nRapid * 6);
    const c = [0, 0, 0];
    let ic = 0, ir = 0;
    for (let i = 1; i < n; ++i) {
      if (kind[i] === 2) continue;
      const a = 3 * (i - 1);
      const dst = kind[i] === 0 ? rapid : cut;
      const k = kind[i] === 0 ? ir : ic;
      for (let j = 0; j < 6; ++j) dst[k + j] = xyz[a + j];
      if (kind[i] === 0) {
        ir += 6;
      } else {
        speedColor((feed[i] - lo) / (hi - lo), c);
        cutCol.set(c, ic);
        cutCol.set(c, ic + 3);
        ic += 6;
      }
    }
    this.cuts = null;
    if (cut.length) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(cut, 3));
      g.setAttribute('color', new THREE.BufferAttribute(cutCol, 3));
      this.cuts = new THREE.LineSegments(g, new THREE.LineBasicMaterial({ vertexColors: true }));
      this.pathGroup.add(this.cuts);
    }
    if (rapid.length) {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(rapid, 3));
      const l = new THREE.LineSegments(g, new THREE.LineDashedMaterial(
          { color: 0x9aa3ad, dashSize: 2, gapSize: 2 }));
      l.computeLineDistances();
      this.pathGroup.add(l);
    }
    this.pathBox = n > 1 ? new THREE.Box3().setFromObject(this.pathGroup) : null;
    // The tool's marker in proportion to the part (12 mm tall on a part of 150 mm).
    const extent = (this.pathBox || this.box).getSize(new THREE.Vector3()).length();
    this.tool.scale.setScalar(Math.min(Math.max(extent / 150, 0.1), 3));
    this.trailCount = 0;
    this.trail.geometry.setDrawRange(0, 0);
    this.setView(this.lastView || 'iso');
    return this.feedRange;
  }

  // The tool's live position; `speedFraction` colours the trail (actual speed on the scale).
  setTool(p, speedFraction) {
    if (this.tool.position.x === p[0] && this.tool.position.y === p[1] &&
        this.tool.position.z === p[2]) return;
    this.tool.position.set(p[0], p[1], p[2]);
    if (this.trailCount === TRAIL_POINTS) {  // drop the older half, keep the buffer
      const half = (TRAIL_POINTS / 2) * 3;
      this.trailPos.copyWithin(0, half);
      this.trailCol.copyWithin(0, half);
      this.trailCount = TRAIL_POINTS / 2;
    }
    const k = 3 * this.trailCount++;
    this.trailPos.set(p, k);
    this.trailCol.set(speedColor(speedFraction, this.trailColor), k);
    const g = this.trail.geometry;
    g.attributes.position.needsUpdate = true;
    g.attributes.color.needsUpdate = true;
    g.setDrawRange(0, this.trailCount);
    this.dirty = true;
  }

  setView(name) {
    this.lastView = name;
    const box = this.pathBox && !this.pathBox.isEmpty() ? this.pathBox : this.box;
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3()).length() || 100;
    const d = size * 1.3;
    const dirs = { top: [0, -0.001, 1], front: [0, -1, 0.001], side: [1, 0, 0.001],
                   iso: [0.8, -1, 0.9] };
    const v = new THREE.Vector3(...(dirs[name] || dirs.iso)).normalize().multiplyScalar(d);
    this.camera.position.copy(centre).add(v);
    this.camera.near = d / 1000;
    this.camera.far = d * 20;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.dirty = true;
  }

  // How many canvas pixels differ from the background (the test's check of a non-blank view).
  litPixels() {
    const gl = this.renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    this.renderer.render(this.scene, this.camera);
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let lit = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - 0x15) + Math.abs(px[i + 1] - 0x18) + Math.abs(px[i + 2] - 0x1c) > 30) ++lit;
    }
    return lit;
  }
}

// 'programmed': the feed moves in the colours of their programmed feed; 'actual': dimmed, so
// that the trail's colours (the actual speed) stand out.
View3D.prototype.setColorMode = function (mode) {
  if (!this.cuts) return;
  const m = this.cuts.material;
  m.vertexColors = mode !== 'actual';
  m.color.set(mode === 'actual' ? 0x3a404a : 0xffffff);
  m.needsUpdate = true;
  this.dirty = true;
};
