// The 3D view: the program's path (rapids dashed, feed moves coloured by speed on a scale of
// their own), the machine's travel box, the stock (a box, or the cutting simulation's height map
// as a surface), the tool at its live position with a trail.
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

// The height ramp of `cncore run --heightmap` (u = 0 stock bottom … 1 top: dark blue, teal, warm
// white), times a shading factor, into out[k…k+2] as 0…1.
function heightColor(u, out, k, shade) {
  u = Math.min(Math.max(u, 0), 1);
  const r = u < 0.5 ? 20 + u * 2 * 40 : 60 + (u - 0.5) * 2 * 180;
  const g = u < 0.5 ? 30 + u * 2 * 120 : 150 + (u - 0.5) * 2 * 85;
  const b = u < 0.5 ? 110 + u * 2 * 70 : 180 + (u - 0.5) * 2 * 30;
  out[k] = Math.min(r * shade / 255, 1);
  out[k + 1] = Math.min(g * shade / 255, 1);
  out[k + 2] = Math.min(b * shade / 255, 1);
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
    this.setTravel(machine);
    if (machine.stock) {  // [stock]: the raw part, translucent
      const [sx, sy, sz] = machine.stock.size_mm, [mx, my, mz] = machine.stock.min_mm;
      const g = new THREE.BoxGeometry(sx, sy, sz);
      g.translate(mx + sx / 2, my + sy / 2, mz + sz / 2);
      this.stock = new THREE.Mesh(g, new THREE.MeshBasicMaterial(
          { color: 0x8d9bb0, transparent: true, opacity: 0.18, depthWrite: false }));
      this.scene.add(this.stock);
      this.stockZ = [mz, mz + sz];
    }
    this.setView('iso');
  }

  // The travel box, again when a sender has written the travel ($130…).
  setTravel(machine) {
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

  // The cutting simulation's height map (GET /api/heightmap: nx × ny heights at cell centres
  // x0 + (i + ½)·cell, y0 + (j + ½)·cell) as a surface in place of the stock box: one vertex per
  // cell, coloured by height on the ramp of the run's PNG (dark blue, teal, light) and shaded by
  // its slope under a light from the north-west.
  setHeightmap(g) {
    const n = g.nx * g.ny;
    if (!this.surface || this.surface.userData.nx !== g.nx || this.surface.userData.ny !== g.ny) {
      if (this.surface) {
        this.surface.geometry.dispose();
        this.scene.remove(this.surface);
      }
      const geo = new THREE.BufferGeometry();
      const pos = new Float32Array(n * 3);
      for (let j = 0; j < g.ny; ++j) {
        for (let i = 0; i < g.nx; ++i) {
          const k = 3 * (j * g.nx + i);
          pos[k] = g.x0 + (i + 0.5) * g.cell;
          pos[k + 1] = g.y0 + (j + 0.5) * g.cell;
        }
      }
      const idx = new Uint32Array(Math.max(g.nx - 1, 0) * Math.max(g.ny - 1, 0) * 6);
      let t = 0;
      for (let j = 0; j + 1 < g.ny; ++j) {
        for (let i = 0; i + 1 < g.nx; ++i) {
          const a = j * g.nx + i;
          idx.set([a, a + 1, a + g.nx + 1, a, a + g.nx + 1, a + g.nx], t);
          t += 6;
        }
      }
      geo.setAttribute('position', new THREE.BufferAttribute(pos, 3));
      geo.setAttribute('color', new THREE.BufferAttribute(new Float32Array(n * 3), 3));
      geo.setIndex(new THREE.BufferAttribute(idx, 1));
      // Slightly translucent: the program's path inside the stock shows through.
      this.surface = new THREE.Mesh(geo, new THREE.MeshBasicMaterial(
          { vertexColors: true, side: THREE.DoubleSide, transparent: true, opacity: 0.85 }));
      this.surface.userData = { nx: g.nx, ny: g.ny };
      this.scene.add(this.surface);
    }
    const geo = this.surface.geometry;
    const pos = geo.attributes.position.array, col = geo.attributes.color.array;
    // Coloured from the deepest cell so far (dark blue) to the stock's top (light): a shallow cut
    // in a tall stock still stands out.
    const hi = this.stockZ ? this.stockZ[1] : 1;
    let lo = hi;
    for (let k = 0; k < n; ++k) lo = Math.min(lo, g.z[k]);
    const span = hi > lo ? hi - lo : 1;
    const h = (i, j) => g.z[Math.min(Math.max(j, 0), g.ny - 1) * g.nx + Math.min(Math.max(i, 0), g.nx - 1)];
    for (let j = 0; j < g.ny; ++j) {
      for (let i = 0; i < g.nx; ++i) {
        const k = j * g.nx + i, z = g.z[k];
        pos[3 * k + 2] = z;
        // Slope shading: n = (−dz/dx, −dz/dy, 1) against L = (−1, 1, √2)/2.
        const dx = (h(i + 1, j) - h(i - 1, j)) / (2 * g.cell), dy = (h(i, j + 1) - h(i, j - 1)) / (2 * g.cell);
        const shade = Math.max(0.35, (dx * 0.5 - dy * 0.5 + Math.SQRT1_2) / Math.sqrt(dx * dx + dy * dy + 1));
        heightColor(hi > lo ? (z - lo) / span : 1, col, 3 * k, shade / Math.SQRT1_2 * 0.8);
      }
    }
    geo.attributes.position.needsUpdate = true;
    geo.attributes.color.needsUpdate = true;
    geo.computeBoundingBox();
    geo.computeBoundingSphere();
    this.surfaceVersion = g.version;
    if (this.stock) this.stock.visible = false;
    this.dirty = true;
  }

  // The canvas colour (0–255 each) at the screen point of machine position p, null off the
  // canvas (the test's check that the surface shows a cut where the program cuts).
  colorAt(p) {
    const v = new THREE.Vector3(...p).project(this.camera);
    this.renderer.render(this.scene, this.camera);
    const gl = this.renderer.getContext();
    const x = Math.round((v.x + 1) / 2 * gl.drawingBufferWidth);
    const y = Math.round((v.y + 1) / 2 * gl.drawingBufferHeight);
    if (x < 0 || y < 0 || x >= gl.drawingBufferWidth || y >= gl.drawingBufferHeight) return null;
    const px = new Uint8Array(4);
    gl.readPixels(x, y, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    return [px[0], px[1], px[2]];
  }

  // The surface's height at the vertex nearest to (x, y), null without a surface.
  surfaceHeightAt(x, y) {
    if (!this.surface) return null;
    const p = this.surface.geometry.attributes.position.array;
    let best = Infinity, z = null;
    for (let k = 0; k < p.length; k += 3) {
      const d = (p[k] - x) ** 2 + (p[k + 1] - y) ** 2;
      if (d < best) { best = d; z = p[k + 2]; }
    }
    return z;
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
