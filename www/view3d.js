// The 3D view: the scene as the fit sees it, drawn with three.js (www/vendor/three,
// copied there by scripts/build-vendor.sh; the import map of index.html names it).
// The views' cameras as frusta in the world (OpenCV: x right, y down, z forward), each
// with its picture — the photograph, or the mask — on its image plane; the object's
// mesh at the current pose (X_w = R·(s⊙X_o) + t), following the fit; the pose's
// uncertainty as translucent ghosts sampled from the result's covariance; the
// suggested next view as a distinct (orange) frustum, with its camera JSON to copy.
// Orbit with the left mouse button, pan with the right, zoom with the wheel.
//
//   const view = await mountView3d(element);   // never throws: without WebGL (or
//   view.setScene(geometry, cameras, pictures); //   without three.js) it shows a note
//   view.setPose(pose); view.setUncertainty(covariance); view.setSuggestion(cameras);
//
// The page (main.js) sends what the worker posts through view.apply(msg). Tests read
// view.info() (element.view3d is the instance).

export const BACKGROUND = 0x1d2127;
const OBJECT_COLOUR = 0xd8cfc0; // clay: apart from the suggestion's orange
const GHOST_COLOUR = 0x5fb3ff;
const CAMERA_COLOUR = 0x9fb4c8;
const SUGGESTION_COLOUR = 0xff7a00;
export const GHOSTS = 12;

// ---- small linear algebra (row-major arrays) ----------------------------------
const matVec3 = (m, v) => [0, 1, 2].map((i) => m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2]);
const matMul3 = (a, b) => [0, 1, 2].map((i) => [0, 1, 2].map((j) => a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j]));
const sub = (a, b) => a.map((x, i) => x - b[i]);
const add = (a, b) => a.map((x, i) => x + b[i]);
const scaleV = (a, k) => a.map((x) => x * k);
const dot = (a, b) => a.reduce((s, x, i) => s + x * b[i], 0);
const norm = (a) => Math.hypot(...a);
const unit = (a) => {
  const n = norm(a);
  return n > 0 ? scaleV(a, 1 / n) : a;
};
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];

/** exp([ω]×), Rodrigues' formula (ω in radians). */
export function expSo3(w) {
  const th = norm(w);
  const K = [[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]];
  const K2 = matMul3(K, K);
  const a = th < 1e-8 ? 1 - (th * th) / 6 : Math.sin(th) / th;
  const b = th < 1e-8 ? 0.5 - (th * th) / 24 : (1 - Math.cos(th)) / (th * th);
  return [0, 1, 2].map((i) => [0, 1, 2].map((j) => (i === j ? 1 : 0) + a * K[i][j] + b * K2[i][j]));
}

/** The lower Cholesky factor of a symmetric positive definite matrix, or null. */
function choleskyStrict(a) {
  const n = a.length;
  const L = a.map(() => new Array(n).fill(0));
  for (let j = 0; j < n; j++) {
    let d = a[j][j];
    for (let k = 0; k < j; k++) d -= L[j][k] * L[j][k];
    if (!(d > 0)) return null;
    L[j][j] = Math.sqrt(d);
    for (let i = j + 1; i < n; i++) {
      let s = a[i][j];
      for (let k = 0; k < j; k++) s -= L[i][k] * L[j][k];
      L[i][j] = s / L[j][j];
    }
  }
  return L;
}

/** Eigenvalues and eigenvectors (columns of V) of a symmetric matrix, by Jacobi rotations. */
function symmetricEigen(a) {
  const n = a.length;
  const A = a.map((r) => [...r]);
  const V = a.map((_, i) => a.map((_, j) => (i === j ? 1 : 0)));
  for (let sweep = 0; sweep < 60; sweep++) {
    let off = 0;
    for (let p = 0; p < n; p++) for (let q = p + 1; q < n; q++) off += A[p][q] * A[p][q];
    if (off < 1e-30) break;
    for (let p = 0; p < n; p++) {
      for (let q = p + 1; q < n; q++) {
        if (A[p][q] === 0) continue;
        const th = (A[q][q] - A[p][p]) / (2 * A[p][q]);
        const t = Math.sign(th || 1) / (Math.abs(th) + Math.sqrt(th * th + 1));
        const c = 1 / Math.sqrt(t * t + 1);
        const s = t * c;
        for (let k = 0; k < n; k++) {
          const akp = A[k][p], akq = A[k][q];
          A[k][p] = c * akp - s * akq;
          A[k][q] = s * akp + c * akq;
        }
        for (let k = 0; k < n; k++) {
          const apk = A[p][k], aqk = A[q][k];
          A[p][k] = c * apk - s * aqk;
          A[q][k] = s * apk + c * aqk;
        }
        for (let k = 0; k < n; k++) {
          const vkp = V[k][p], vkq = V[k][q];
          V[k][p] = c * vkp - s * vkq;
          V[k][q] = s * vkp + c * vkq;
        }
      }
    }
  }
  return { values: A.map((r, i) => r[i]), vectors: V };
}

/**
 * A factor L (L·Lᵀ = the covariance, symmetrised) for sampling: its Cholesky factor;
 * when it is not positive definite (a flat direction, rounding), that of it plus a tiny
 * ridge ε·I (ε from 1e-12 up to 1e-6 of its mean diagonal); when it has clearly
 * negative eigenvalues, the square root of its nearest positive semi-definite matrix
 * (negative eigenvalues set to zero). Null for a matrix that is not square, holds a
 * non-finite number or is zero.
 */
export function choleskyFactor(cov) {
  const n = cov?.length ?? 0;
  if (n === 0 || !cov.every((r) => Array.isArray(r) && r.length === n && r.every(Number.isFinite))) return null;
  const a = cov.map((r, i) => r.map((x, j) => 0.5 * (x + cov[j][i])));
  const L = choleskyStrict(a);
  if (L) return L;
  const meanDiag = a.reduce((s, r, i) => s + Math.abs(r[i]), 0) / n;
  if (!(meanDiag > 0)) return null;
  for (let eps = meanDiag * 1e-12; eps <= meanDiag * 1e-6; eps *= 10) {
    const L2 = choleskyStrict(a.map((r, i) => r.map((x, j) => (i === j ? x + eps : x))));
    if (L2) return L2;
  }
  const { values, vectors } = symmetricEigen(a);
  const roots = values.map((v) => Math.sqrt(Math.max(v, 0)));
  return vectors.map((row) => row.map((x, k) => x * roots[k]));
}

/** A seeded generator of standard normal numbers (mulberry32 and Box–Muller). */
function normals(seed) {
  let s = seed >>> 0;
  const uniform = () => {
    s = (s + 0x6d2b79f5) >>> 0;
    let t = s;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  return () => Math.sqrt(-2 * Math.log(1 - uniform())) * Math.cos(2 * Math.PI * uniform());
}

/** `count` draws δ = L·z, z ~ N(0, I), from the covariance's factor (9-vectors). */
export function sampleDeltas(cov, count = GHOSTS, seed = 1) {
  const L = choleskyFactor(cov);
  if (!L || L.length !== 9) return [];
  const z = normals(seed);
  return Array.from({ length: count }, () => {
    const e = Array.from({ length: 9 }, z);
    return L.map((row) => row.reduce((s, x, k) => s + x * e[k], 0));
  });
}

/** The pose moved by δ = [ω, δt, δ log s]: R·exp([ω]×), t + δt, s·exp(δ log s). */
export function perturbPose(pose, d) {
  return {
    rotation: matMul3(pose.rotation, expSo3(d.slice(0, 3))),
    translation: add(pose.translation, d.slice(3, 6)),
    scale: pose.scale.map((s, i) => s * Math.exp(d[6 + i])),
  };
}

/** The object-to-world matrix [R·diag(s) | t] of a pose, row-major 4×4. */
export function poseMatrix(pose) {
  const { rotation: R, translation: t, scale: s } = pose;
  return [
    [R[0][0] * s[0], R[0][1] * s[1], R[0][2] * s[2], t[0]],
    [R[1][0] * s[0], R[1][1] * s[1], R[1][2] * s[2], t[1]],
    [R[2][0] * s[0], R[2][1] * s[1], R[2][2] * s[2], t[2]],
    [0, 0, 0, 1],
  ];
}

// A camera of the scene file: its centre, axes (world) and camera-to-world rows.
function cameraFrame(cam) {
  const m = cam.world_to_camera;
  const R = [0, 1, 2].map((i) => m[i].slice(0, 3));
  const t = [m[0][3], m[1][3], m[2][3]];
  const Rt = [0, 1, 2].map((i) => [R[0][i], R[1][i], R[2][i]]);
  const centre = scaleV(matVec3(Rt, t), -1);
  return { centre, x: R[0], y: R[1], z: R[2], toWorld: [...Rt.map((r, i) => [...r, centre[i]]), [0, 0, 0, 1]] };
}

// The point closest to every camera's optical axis (least squares), or null when the
// axes are (nearly) parallel.
function axesMeet(frames) {
  const A = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  const b = [0, 0, 0];
  for (const f of frames) {
    const d = unit(f.z);
    for (let i = 0; i < 3; i++) {
      for (let j = 0; j < 3; j++) {
        const p = (i === j ? 1 : 0) - d[i] * d[j];
        A[i][j] += p;
        b[i] += p * f.centre[j];
      }
    }
  }
  const det = dot(A[0], cross(A[1], A[2]));
  if (!(Math.abs(det) > 1e-6 * frames.length ** 3)) return null;
  // Cramer's rule.
  const col = (k) => A.map((r, i) => r.map((x, j) => (j === k ? b[i] : x)));
  return [0, 1, 2].map((k) => {
    const M = col(k);
    return dot(M[0], cross(M[1], M[2])) / det;
  });
}

// A camera's JSON as scene.json writes it, one matrix row a line.
export function cameraText(cam) {
  const rows = cam.world_to_camera.map((r) => `    ${JSON.stringify(r)}`).join(',\n');
  return JSON.stringify({ ...cam, world_to_camera: '@rows' }, null, 2).replace('"@rows"', `[\n${rows}\n  ]`);
}

const clean = (cam) => ({
  name: cam.name, width: cam.width, height: cam.height, fx: cam.fx, fy: cam.fy, cx: cam.cx, cy: cam.cy,
  world_to_camera: cam.world_to_camera,
});

// ---- the view ---------------------------------------------------------------------
export class View3D {
  constructor(container) {
    this.container = container;
    container.view3d = this;
    container.classList.add('view3d');
    this.holder = Object.assign(document.createElement('div'), { className: 'view3d-canvas' });
    this.note = Object.assign(document.createElement('p'), { className: 'view3d-note', hidden: true });
    this.note.dataset.testid = 'view3d-note';
    this.readout = this.buildReadout();
    this.toolbar = this.buildToolbar();
    container.append(this.holder, this.toolbar, this.note, this.readout);
    this.gl = false;
    this.cameras = [];
    this.pose = null;
    this.deltas = [];
    this.suggestion = null;
    this.frames = 0;
    this.poseUpdates = 0;
  }

  // "Look from": free orbit, or through one of the views' cameras; what is shown.
  buildToolbar() {
    const bar = Object.assign(document.createElement('div'), { className: 'view3d-toolbar', hidden: true });
    const label = Object.assign(document.createElement('label'), { textContent: 'look from ' });
    this.lookFrom = document.createElement('select');
    this.lookFrom.dataset.testid = 'view3d-look';
    this.lookFrom.addEventListener('change', () => {
      const i = Number(this.lookFrom.value);
      if (i >= 0) this.lookThrough(i);
      else this.home();
    });
    label.append(this.lookFrom);
    const toggle = (text, key) => {
      const l = Object.assign(document.createElement('label'), { className: 'toggle' });
      const box = Object.assign(document.createElement('input'), { type: 'checkbox', checked: true });
      box.addEventListener('change', () => this.setVisible({ [key]: box.checked }));
      l.append(box, ` ${text}`);
      return l;
    };
    bar.append(label, toggle('pictures', 'pictures'), toggle('ghosts', 'ghosts'));
    return bar;
  }

  // "Suggested next view": the best camera's JSON (scene-file form), with a copy button.
  buildReadout() {
    const box = Object.assign(document.createElement('details'), { className: 'view3d-suggestion', open: true, hidden: true });
    box.dataset.testid = 'suggestion';
    const summary = document.createElement('summary');
    summary.textContent = 'Suggested next view';
    const copy = Object.assign(document.createElement('button'), { type: 'button', textContent: 'Copy' });
    copy.dataset.testid = 'suggestion-copy';
    this.suggestionText = Object.assign(document.createElement('pre'), { tabIndex: 0 });
    this.suggestionText.dataset.testid = 'suggestion-json';
    copy.addEventListener('click', async () => {
      try {
        await navigator.clipboard.writeText(this.suggestionText.textContent);
        copy.textContent = 'Copied';
      } catch {
        getSelection().selectAllChildren(this.suggestionText); // copy by hand
        copy.textContent = 'Selected';
      }
      setTimeout(() => (copy.textContent = 'Copy'), 1500);
    });
    summary.append(' ', copy);
    box.append(summary, this.suggestionText);
    return box;
  }

  showNote(text) {
    this.note.textContent = text;
    this.note.hidden = false;
    this.holder.hidden = true;
  }

  // Loads three.js and makes the renderer; on failure the view is a note and every
  // method below still works (without drawing).
  async init() {
    let THREE, OrbitControls;
    try {
      THREE = await import('three');
      ({ OrbitControls } = await import('three/addons/controls/OrbitControls.js'));
    } catch (e) {
      this.showNote(`3D view unavailable: three.js did not load (${e.message}); run scripts/build-vendor.sh.`);
      return this;
    }
    const canvas = document.createElement('canvas');
    canvas.dataset.testid = 'view3d-canvas';
    canvas.setAttribute('aria-label', '3D view: cameras, object and its uncertainty (drag to orbit, wheel to zoom)');
    // The context is asked for here, so that a browser without WebGL 2 gets a note, not an error.
    const attrs = { antialias: true, alpha: false, depth: true, stencil: false, preserveDrawingBuffer: true };
    let context = null;
    try {
      context = canvas.getContext('webgl2', attrs);
    } catch {
      context = null;
    }
    if (!context) {
      this.showNote('3D view unavailable: this browser gives no WebGL 2 context. The fit and the views are not affected.');
      return this;
    }
    try {
      this.THREE = THREE;
      this.renderer = new THREE.WebGLRenderer({ canvas, context, antialias: true, preserveDrawingBuffer: true });
    } catch (e) {
      this.showNote(`3D view unavailable: ${e.message}`);
      return this;
    }
    this.holder.append(canvas);
    this.canvas = canvas;
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    this.renderer.setClearColor(BACKGROUND, 1);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(45, 1, 0.01, 100);
    this.scene.add(this.camera);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x445566, 1.6));
    const sun = new THREE.DirectionalLight(0xffffff, 1.8);
    sun.position.set(0.5, 1, 0.8);
    this.camera.add(sun); // lit from the viewer's side, wherever it orbits
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.addEventListener('change', () => this.requestRender());
    // Any orbit or zoom leaves a view's camera for the free perspective.
    this.controls.addEventListener('start', () => {
      if (this.through === null) return;
      this.through = null;
      this.lookFrom.value = '-1';
      this.camera.updateProjectionMatrix();
    });
    this.through = null;
    this.visible = { cameras: true, pictures: true, ghosts: true, suggestion: true };
    this.world = new THREE.Group(); // cameras, object, ghosts, suggestion: rebuilt by setScene
    this.scene.add(this.world);
    this.resizer = new ResizeObserver(() => this.resize());
    this.resizer.observe(this.holder);
    this.gl = true;
    this.resize();
    if (this.pending) this.setScene(...this.pending);
    this.pending = null;
    return this;
  }

  resize() {
    if (!this.gl) return;
    const w = Math.max(1, this.holder.clientWidth);
    const h = Math.max(1, this.holder.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    if (this.through !== null) this.throughProjection(this.cameras[this.through]);
    this.requestRender();
  }

  /** The drawing buffer's size in pixels. */
  bufferSize() {
    return this.gl ? [this.canvas.width, this.canvas.height] : [0, 0];
  }

  /**
   * Looks through view `index`'s camera: the viewer at its centre with its axes, and a
   * projection made from its intrinsics, the image fitted (letterboxed) into the
   * canvas — the object's silhouette then falls on the view's mask. Orbiting leaves it.
   */
  lookThrough(index) {
    const cam = this.cameras[index];
    if (!this.gl || !cam) return;
    const THREE = this.THREE;
    const f = cameraFrame(cam);
    // three's camera looks down −z with y up: OpenCV's axes with y and z negated.
    const basis = new THREE.Matrix4().makeBasis(new THREE.Vector3(...f.x), new THREE.Vector3(...scaleV(f.y, -1)), new THREE.Vector3(...scaleV(f.z, -1)));
    this.camera.position.set(...f.centre);
    this.camera.quaternion.setFromRotationMatrix(basis);
    this.camera.updateMatrixWorld();
    this.controls.target.set(...add(f.centre, scaleV(f.z, Math.max(norm(sub(this.target, f.centre)), 1e-9))));
    this.through = index;
    this.lookFrom.value = String(index);
    this.throughProjection(cam);
    this.requestRender();
  }

  // OpenCV intrinsics as a projection matrix, the image (pixel edges −½ … w − ½) fitted
  // into the W×H canvas at scale k, centred.
  throughProjection(cam) {
    const [W, H] = this.bufferSize();
    const k = Math.min(W / cam.width, H / cam.height);
    const n = this.camera.near;
    const fa = this.camera.far;
    this.camera.projectionMatrix.set(
      (2 * k * cam.fx) / W, 0, (k * cam.width - 2 * k * (cam.cx + 0.5)) / W, 0,
      0, (2 * k * cam.fy) / H, (2 * k * (cam.cy + 0.5) - k * cam.height) / H, 0,
      0, 0, -(fa + n) / (fa - n), (-2 * fa * n) / (fa - n),
      0, 0, -1, 0,
    );
    this.camera.projectionMatrixInverse.copy(this.camera.projectionMatrix).invert();
  }

  /** The free perspective chosen when the scene was set. */
  home() {
    if (!this.gl || !this.homePose) return;
    this.through = null;
    this.lookFrom.value = '-1';
    this.camera.position.set(...this.homePose.position);
    this.controls.target.set(...this.homePose.target);
    this.camera.updateProjectionMatrix();
    this.controls.update();
    this.requestRender();
  }

  /** Shows or hides parts: `{cameras, pictures, ghosts, suggestion}` (booleans; others kept). */
  setVisible(parts) {
    Object.assign(this.visible, parts);
    if (!this.gl) return;
    if (this.cameraGroup) this.cameraGroup.visible = this.visible.cameras;
    this.cameraGroup?.traverse((o) => o.name === 'picture' && (o.visible = this.visible.pictures));
    if (this.ghostGroup) this.ghostGroup.visible = this.visible.ghosts;
    if (this.suggestionGroup) this.suggestionGroup.visible = this.visible.suggestion;
    this.requestRender();
  }

  requestRender() {
    if (!this.gl || this.renderQueued) return;
    this.renderQueued = true;
    requestAnimationFrame(() => {
      this.renderQueued = false;
      this.render();
    });
  }

  render() {
    if (!this.gl) return;
    this.renderer.render(this.scene, this.camera);
    this.frames++;
  }

  // Every message the page receives from the worker for the 3D view:
  // { scene: {geometry, cameras, pictures}, pose, covariance, suggestions }, any subset.
  apply(msg) {
    if (msg.scene) this.setScene(msg.scene.geometry, msg.scene.cameras, msg.scene.pictures);
    if (msg.pose) this.setPose(msg.pose);
    if ('covariance' in msg) this.setUncertainty(msg.covariance);
    if ('suggestions' in msg) this.setSuggestion(msg.suggestions);
  }

  /**
   * The scene: the mesh (`{positions, indices}`, model frame), the views' cameras
   * (scene-file form) and their pictures (`{width, height, rgba}` each, or null).
   * Clears the pose, the ghosts and the suggestion.
   */
  setScene(geometry, cameras, pictures = []) {
    this.cameras = cameras.map(clean);
    this.geometryInfo = { vertices: geometry.positions.length / 3, triangles: geometry.indices.length / 3 };
    this.pose = null;
    this.deltas = [];
    this.setSuggestion(null);
    if (!this.gl) {
      this.pending = [geometry, cameras, pictures];
      return;
    }
    const THREE = this.THREE;
    this.clearWorld();
    const frames = this.cameras.map(cameraFrame);
    // Where the cameras look: their axes' meeting point, else in front of their centroid.
    const centroid = scaleV(frames.reduce((s, f) => add(s, f.centre), [0, 0, 0]), 1 / Math.max(frames.length, 1));
    const meanAxis = unit(frames.reduce((s, f) => add(s, f.z), [0, 0, 0]));
    const spread = Math.max(...frames.map((f) => norm(sub(f.centre, centroid))), 0);
    let target = frames.length > 1 ? axesMeet(frames) : null;
    this.mesh = new THREE.BufferGeometry();
    this.mesh.setAttribute('position', new THREE.BufferAttribute(geometry.positions, 3));
    this.mesh.setIndex(new THREE.BufferAttribute(geometry.indices, 1));
    this.mesh.computeVertexNormals();
    this.mesh.computeBoundingSphere();
    const radius = this.mesh.boundingSphere?.radius || 1;
    if (!target) target = add(centroid, scaleV(meanAxis, Math.max(spread, radius * 4)));
    const dist = frames.length ? frames.map((f) => norm(sub(f.centre, target))).sort((a, b) => a - b)[frames.length >> 1] : radius * 4;
    this.target = target;
    this.depth = 0.3 * (dist || 1); // image planes at 30 % of the (median) camera distance
    // Up: against the cameras' mean y axis (OpenCV y points down in the image).
    let up = scaleV(frames.reduce((s, f) => add(s, f.y), [0, 0, 0]), -1);
    if (norm(up) < 1e-6 * Math.max(frames.length, 1)) up = [0, 0, 1];
    up = unit(up);

    // The views: frusta with their pictures.
    this.cameraGroup = new THREE.Group();
    this.cameras.forEach((cam, i) => {
      const g = this.frustum(cam, CAMERA_COLOUR, pictures[i] ?? null, false);
      g.name = `camera:${cam.name}`;
      this.cameraGroup.add(g);
    });
    this.world.add(this.cameraGroup);

    // The object (hidden until a pose arrives) and its ghosts.
    this.objectMaterial = new THREE.MeshStandardMaterial({ color: OBJECT_COLOUR, roughness: 0.65, metalness: 0.05, flatShading: true, side: THREE.DoubleSide });
    this.object = new THREE.Mesh(this.mesh, this.objectMaterial);
    this.object.name = 'object';
    this.object.matrixAutoUpdate = false;
    this.object.visible = false;
    this.world.add(this.object);
    this.ghostMaterial = new THREE.MeshStandardMaterial({ color: GHOST_COLOUR, transparent: true, opacity: 0.22, depthWrite: false, flatShading: true, side: THREE.DoubleSide });
    this.ghostGroup = new THREE.Group();
    this.ghostGroup.name = 'ghosts';
    this.world.add(this.ghostGroup);

    // The viewer: from above the cameras' side, just far enough to see every camera
    // and the object (each point p needs a distance D ≥ along + lateral / tan(half-angle)).
    let side = sub(centroid, target);
    side = sub(side, scaleV(up, dot(side, up)));
    if (norm(side) < 1e-9 * (dist || 1)) side = cross(up, Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0]);
    const dir = unit(add(unit(side), scaleV(up, 0.8)));
    const right = unit(cross(scaleV(dir, -1), up));
    const upView = cross(right, scaleV(dir, -1));
    const tanV = Math.tan((this.camera.fov * Math.PI) / 360);
    const tanH = tanV * this.camera.aspect;
    const points = [...frames.map((f) => f.centre), ...frames.map((f) => add(f.centre, scaleV(f.z, this.depth)))];
    for (const a of [right, upView, dir]) points.push(add(target, scaleV(a, radius)), sub(target, scaleV(a, radius)));
    const range = 1.1 * Math.max(...points.map((p) => {
      const q = sub(p, target);
      return dot(q, dir) + Math.max(Math.abs(dot(q, right)) / tanH, Math.abs(dot(q, upView)) / tanV);
    }));
    this.camera.up.set(...up);
    this.camera.position.set(...add(target, scaleV(dir, range)));
    this.camera.near = range / 1000;
    this.camera.far = range * 20;
    this.camera.updateProjectionMatrix();
    this.controls.target.set(...target);
    this.controls.update();
    this.homePose = { position: this.camera.position.toArray(), target };
    this.through = null;
    this.lookFrom.replaceChildren(new Option('free orbit', '-1'), ...this.cameras.map((c, i) => new Option(c.name, String(i))));
    this.toolbar.hidden = false;
    this.setVisible({});
  }

  // A camera's frustum: apex at its centre, image plane at this.depth, a small
  // triangle over the image's top edge; optionally its picture on the plane, and for
  // the suggestion translucent faces.
  frustum(cam, colour, picture, filled) {
    const THREE = this.THREE;
    const d = this.depth;
    const g = new THREE.Group();
    const f = cameraFrame(cam);
    const M = new THREE.Matrix4().set(...f.toWorld.flat());
    g.matrixAutoUpdate = false;
    g.matrix.copy(M);
    // Pixel edges: u from −½ to width − ½ (pixel centres at integers).
    const corner = (u, v) => [((u - cam.cx) / cam.fx) * d, ((v - cam.cy) / cam.fy) * d, d];
    const [u0, u1, v0, v1] = [-0.5, cam.width - 0.5, -0.5, cam.height - 0.5];
    const c = [corner(u0, v0), corner(u1, v0), corner(u1, v1), corner(u0, v1)]; // TL TR BR BL
    const o = [0, 0, 0];
    const mid = scaleV(add(c[0], c[1]), 0.5);
    const tip = sub(mid, [0, 0.25 * (c[3][1] - c[0][1]), 0]); // up in the image is −y
    const half = 0.15 * (c[1][0] - c[0][0]);
    const segs = [o, c[0], o, c[1], o, c[2], o, c[3], c[0], c[1], c[1], c[2], c[2], c[3], c[3], c[0],
      add(mid, [-half, 0, 0]), tip, tip, add(mid, [half, 0, 0])];
    const lines = new THREE.BufferGeometry().setAttribute('position', new THREE.Float32BufferAttribute(segs.flat(), 3));
    g.add(new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: colour })));
    if (picture) {
      const plane = new THREE.BufferGeometry();
      plane.setAttribute('position', new THREE.Float32BufferAttribute(c.flat(), 3));
      plane.setAttribute('uv', new THREE.Float32BufferAttribute([0, 0, 1, 0, 1, 1, 0, 1], 2)); // row 0 at v = 0 (DataTexture, no flip)
      plane.setIndex([0, 2, 1, 0, 3, 2]);
      const tex = new THREE.DataTexture(new Uint8Array(picture.rgba.buffer, picture.rgba.byteOffset, picture.rgba.byteLength), picture.width, picture.height, THREE.RGBAFormat);
      tex.colorSpace = THREE.SRGBColorSpace;
      tex.magFilter = THREE.LinearFilter;
      tex.minFilter = THREE.LinearFilter;
      tex.needsUpdate = true;
      const m = new THREE.MeshBasicMaterial({ map: tex, side: THREE.DoubleSide, transparent: true, opacity: 0.85, depthWrite: false });
      const mesh = new THREE.Mesh(plane, m);
      mesh.name = 'picture';
      g.add(mesh);
    }
    if (filled) {
      const faces = new THREE.BufferGeometry();
      faces.setAttribute('position', new THREE.Float32BufferAttribute([o, ...c].flat(), 3));
      faces.setIndex([0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 1, 2, 3, 1, 3, 4]);
      g.add(new THREE.Mesh(faces, new THREE.MeshBasicMaterial({ color: colour, transparent: true, opacity: 0.28, side: THREE.DoubleSide, depthWrite: false })));
    }
    return g;
  }

  /** The object at a pose `{rotation: 3×3 rows, translation, scale}`; its ghosts follow. */
  setPose(pose) {
    if (!pose) return;
    this.pose = { rotation: pose.rotation, translation: pose.translation, scale: pose.scale };
    this.poseUpdates++;
    if (!this.gl || !this.object) return;
    this.object.matrix.set(...poseMatrix(this.pose).flat());
    this.object.matrixWorldNeedsUpdate = true;
    this.object.visible = true;
    this.placeGhosts();
    this.requestRender();
  }

  /**
   * The pose's uncertainty: a 9×9 covariance (rows) in [ω (rad, right tangent), t,
   * log s], or null (no ghosts). GHOSTS poses are drawn from it (a tiny ridge is added
   * when it is not positive definite) and shown about the current pose.
   */
  setUncertainty(covariance, { samples = GHOSTS, seed = 1 } = {}) {
    this.deltas = covariance ? sampleDeltas(covariance, samples, seed) : [];
    this.placeGhosts();
    this.requestRender();
  }

  placeGhosts() {
    if (!this.gl || !this.ghostGroup) return;
    const THREE = this.THREE;
    const want = this.pose ? this.deltas.length : 0;
    while (this.ghostGroup.children.length > want) this.ghostGroup.remove(this.ghostGroup.children.at(-1));
    while (this.ghostGroup.children.length < want) {
      const m = new THREE.Mesh(this.mesh, this.ghostMaterial);
      m.matrixAutoUpdate = false;
      this.ghostGroup.add(m);
    }
    this.ghostGroup.children.forEach((m, i) => {
      m.matrix.set(...poseMatrix(perturbPose(this.pose, this.deltas[i])).flat());
      m.matrixWorldNeedsUpdate = true;
    });
  }

  /**
   * The suggested next views (scene-form cameras, best first; entries may also be
   * `{camera, ...}`), or null. The best is drawn as an orange frustum with faces, the
   * others as thin orange frusta; the best's JSON is shown to copy.
   */
  setSuggestion(cameras) {
    const list = (Array.isArray(cameras) ? cameras : cameras?.cameras ?? cameras?.views ?? [])
      .map((c) => c?.camera ?? c)
      .filter((c) => c && Array.isArray(c.world_to_camera));
    this.suggestion = list.length ? list.map(clean) : null;
    this.readout.hidden = !this.suggestion;
    this.suggestionText.textContent = this.suggestion ? cameraText(this.suggestion[0]) : '';
    if (!this.gl || !this.world) return;
    if (this.suggestionGroup) {
      this.world.remove(this.suggestionGroup);
      disposeTree(this.suggestionGroup);
      this.suggestionGroup = null;
    }
    if (this.suggestion) {
      this.suggestionGroup = new this.THREE.Group();
      this.suggestionGroup.name = 'suggestion';
      this.suggestion.forEach((cam, i) => {
        const g = this.frustum(cam, i === 0 ? SUGGESTION_COLOUR : 0x8a5a2b, null, i === 0);
        g.name = i === 0 ? 'suggestion:best' : `suggestion:${i}`;
        this.suggestionGroup.add(g);
      });
      this.world.add(this.suggestionGroup);
    }
    this.setVisible({});
  }

  /** What is drawn, for tests: counts, the object's matrix (row-major, 16) and the frames rendered. */
  info() {
    const m = this.object?.matrix.elements; // column-major
    return {
      webgl: this.gl,
      note: this.note.hidden ? null : this.note.textContent,
      cameras: this.gl ? this.cameraGroup?.children.length ?? 0 : this.cameras.length,
      pictures: this.gl ? this.cameraGroup?.children.filter((g) => g.getObjectByName('picture')).length ?? 0 : 0,
      triangles: this.geometryInfo?.triangles ?? 0,
      objectVisible: Boolean(this.object?.visible),
      objectMatrix: m ? [0, 1, 2, 3].flatMap((i) => [0, 1, 2, 3].map((j) => m[j * 4 + i])) : null,
      ghosts: this.ghostGroup?.children.length ?? (this.pose ? this.deltas.length : 0),
      ghostMatrices: this.ghostGroup?.children.map((g) => [0, 1, 2, 3].flatMap((i) => [0, 1, 2, 3].map((j) => g.matrix.elements[j * 4 + i]))) ?? [],
      suggestion: Boolean(this.gl ? this.suggestionGroup?.getObjectByName('suggestion:best') : this.suggestion),
      suggestions: this.suggestion?.length ?? 0,
      poseUpdates: this.poseUpdates,
      frames: this.frames,
      through: this.through ?? null,
      viewer: this.gl ? { position: this.camera.position.toArray(), target: this.controls.target.toArray() } : null,
    };
  }

  clearWorld() {
    for (const child of [...this.world.children]) {
      this.world.remove(child);
      if (child !== this.object && child !== this.ghostGroup) disposeTree(child);
    }
    this.mesh?.dispose();
    this.objectMaterial?.dispose();
    this.ghostMaterial?.dispose();
    this.cameraGroup = this.object = this.ghostGroup = this.suggestionGroup = null;
  }

  dispose() {
    if (this.gl) {
      this.clearWorld();
      this.resizer.disconnect();
      this.controls.dispose();
      this.renderer.dispose();
      this.canvas.remove();
    }
    this.gl = false;
    this.container.replaceChildren();
    delete this.container.view3d;
  }
}

// Frees the GPU side of a group's geometries, materials and textures.
function disposeTree(root) {
  root.traverse((o) => {
    o.geometry?.dispose();
    for (const m of [o.material].flat().filter(Boolean)) {
      m.map?.dispose();
      m.dispose();
    }
  });
}

/** A 3D view in `container`: always resolves (a note explains what is missing). */
export async function mountView3d(container) {
  return new View3D(container).init();
}
