// The 3D view: the scene as the fit sees it, drawn with three.js (www/vendor/three,
// copied there by scripts/build-vendor.sh; the import map of index.html names it).
// The views' cameras as frusta in the world (OpenCV: x right, y down, z forward), each
// with its picture — the photograph, or the mask — on its image plane; the object's
// mesh at the current pose, following the fit; the pose's uncertainty as translucent
// ghosts; the suggested next view as a distinct (orange) frustum, with its camera JSON
// to copy. Orbit with the left mouse button, pan with the right, zoom with the wheel.
// This file only draws: every frame, matrix and ghost is computed in Rust
// (Session.cameraFrames, framesOfCameras, Session.ghosts, the progress's matrix;
// src/wasm/scene_view.rs) and posted by the worker.
//
//   const view = await mountView3d(element);           // never throws: without WebGL
//   view.setScene(geometry, cameras, pictures, frames); //   (or three.js) it is a note
//   view.setPose(matrix); view.setGhosts(matrices); view.setSuggestion(suggestions);
//
// The page (main.js) sends what the worker posts through view.apply(msg). Tests read
// view.info() (element.view3d is the instance).

export const BACKGROUND = 0x1d2127;
const OBJECT_COLOUR = 0xd8cfc0; // clay: apart from the suggestion's orange
const GHOST_COLOUR = 0x5fb3ff;
const ALTERNATIVE_COLOUR = 0xe040c0; // an ambiguous fit's competing poses
const CAMERA_COLOUR = 0x9fb4c8;
const SUGGESTION_COLOUR = 0xff7a00;

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
    this.sceneFrames = null; // Session.cameraFrames(): every view's frame, the target, the viewer's start
    this.matrix = null; // the object's pose, object-to-world rows
    this.ghosts = []; // the ghosts' object-to-world matrices, 16 numbers row-major each
    this.alternatives = []; // an ambiguous fit's alternative poses, the same way
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

  /** The view's width/height (1 without WebGL). */
  aspect() {
    return this.gl ? this.camera.aspect : 1;
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
    const f = this.sceneFrames?.frames[index];
    if (!this.gl || !cam || !f) return;
    const THREE = this.THREE;
    // three's camera looks down −z with y up: the frame's viewer_to_world (OpenCV's axes
    // with y and z negated), orbiting a point on its axis.
    new THREE.Matrix4().set(...f.viewer_to_world.flat()).decompose(this.camera.position, this.camera.quaternion, new THREE.Vector3());
    this.camera.updateMatrixWorld();
    this.controls.target.set(...f.look_at);
    this.through = index;
    this.lookFrom.value = String(index);
    this.throughProjection(cam);
    this.requestRender();
  }

  // OpenCV intrinsics as three's projection matrix, the image (pixel edges −½ … w − ½)
  // fitted into the W×H canvas at scale k, centred: drawing, for the canvas's size now.
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
    if (this.alternativeGroup) this.alternativeGroup.visible = this.visible.ghosts;
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
  // { scene: {geometry, cameras, pictures, frames}, pose (a matrix), ghosts, alternatives,
  // suggestions },
  // any subset.
  apply(msg) {
    if (msg.scene) this.setScene(msg.scene.geometry, msg.scene.cameras, msg.scene.pictures, msg.scene.frames);
    if (msg.pose) this.setPose(msg.pose);
    if ('ghosts' in msg) this.setGhosts(msg.ghosts);
    if ('alternatives' in msg) this.setAlternatives(msg.alternatives);
    if ('suggestions' in msg) this.setSuggestion(msg.suggestions);
  }

  /**
   * The scene: the mesh (`{positions, indices}`, model frame), the views' cameras
   * (scene-file form), their pictures (`{width, height, rgba}` each, or null) and
   * `Session.cameraFrames()` (each view's frame and frustum, the target, the orbit's
   * up, the viewer's start). Clears the pose, the ghosts and the suggestion.
   */
  setScene(geometry, cameras, pictures = [], frames = null) {
    this.cameras = cameras.map(clean);
    this.sceneFrames = frames;
    this.geometryInfo = { vertices: geometry.positions.length / 3, triangles: geometry.indices.length / 3 };
    this.matrix = null;
    this.ghosts = [];
    this.alternatives = [];
    this.setSuggestion(null);
    if (!this.gl) {
      this.pending = [geometry, cameras, pictures, frames];
      return;
    }
    const THREE = this.THREE;
    this.clearWorld();
    this.mesh = new THREE.BufferGeometry();
    this.mesh.setAttribute('position', new THREE.BufferAttribute(geometry.positions, 3));
    this.mesh.setIndex(new THREE.BufferAttribute(geometry.indices, 1));
    this.mesh.computeVertexNormals();

    // The views: frusta with their pictures (each needs its frame).
    this.cameraGroup = new THREE.Group();
    this.cameras.forEach((cam, i) => {
      const frame = frames?.frames[i];
      if (!frame) return;
      const g = this.frustum(frame, CAMERA_COLOUR, pictures[i] ?? null, false);
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
    this.alternativeMaterial = new THREE.MeshStandardMaterial({ color: ALTERNATIVE_COLOUR, transparent: true, opacity: 0.4, depthWrite: false, flatShading: true, side: THREE.DoubleSide });
    this.alternativeGroup = new THREE.Group();
    this.alternativeGroup.name = 'alternatives';
    this.world.add(this.alternativeGroup);

    // The viewer: where Rust placed it (from above the cameras' side, just far enough
    // to see every camera and the object), looking at the cameras' target.
    if (frames) {
      const { home, target, up } = frames;
      this.camera.fov = home.fov_deg;
      this.camera.up.set(...up);
      this.camera.position.set(...home.position);
      this.camera.near = home.near;
      this.camera.far = home.far;
      this.camera.updateProjectionMatrix();
      this.controls.target.set(...target);
      this.controls.update();
      this.homePose = { position: this.camera.position.toArray(), target };
    }
    this.through = null;
    this.lookFrom.replaceChildren(new Option('free orbit', '-1'), ...this.cameras.map((c, i) => new Option(c.name, String(i))));
    this.toolbar.hidden = false;
    this.setVisible({});
  }

  // A camera's frustum from its frame (Rust's CameraFrame): apex at its centre, the
  // image plane's corners, a small triangle over the image's top edge; optionally its
  // picture on the plane, and for the suggestion translucent faces.
  frustum(frame, colour, picture, filled) {
    const THREE = this.THREE;
    const g = new THREE.Group();
    g.matrixAutoUpdate = false;
    g.matrix.set(...frame.camera_to_world.flat());
    const c = frame.corners; // TL TR BR BL, camera frame
    const [left, tip, right] = frame.marker;
    const o = [0, 0, 0];
    const segs = [o, c[0], o, c[1], o, c[2], o, c[3], c[0], c[1], c[1], c[2], c[2], c[3], c[3], c[0],
      left, tip, tip, right];
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

  /** The object at a pose: its object-to-world matrix `[R·diag(s) | t]` as 4×4 rows or 16 numbers row-major (the progress's `matrix`). */
  setPose(matrix) {
    if (!matrix) return;
    this.matrix = [matrix].flat(2);
    this.poseUpdates++;
    if (!this.gl || !this.object) return;
    this.object.matrix.set(...this.matrix);
    this.object.matrixWorldNeedsUpdate = true;
    this.object.visible = true;
    this.requestRender();
  }

  /**
   * The pose's uncertainty: ghosts at the given object-to-world matrices (16 numbers
   * row-major, or 4×4 rows, each; `Session.ghosts`, poses drawn in Rust from the
   * finished fit's covariance), or null (none). Entries that are not 16 finite numbers
   * are left out.
   */
  setGhosts(matrices) {
    this.ghosts = Array.isArray(matrices)
      ? matrices.map((m) => [m].flat(2)).filter((m) => m.length === 16 && m.every(Number.isFinite))
      : [];
    this.placeGhosts();
    this.requestRender();
  }

  /**
   * An ambiguous fit's alternative poses (the result's `alternatives`, their
   * `matrix` each: 4×4 rows or 16 numbers row-major), drawn as magenta ghosts; or null.
   */
  setAlternatives(matrices) {
    this.alternatives = Array.isArray(matrices)
      ? matrices.map((m) => [m].flat(2)).filter((m) => m.length === 16 && m.every(Number.isFinite))
      : [];
    this.placeGhosts();
    this.requestRender();
  }

  placeGhosts() {
    if (!this.gl || !this.ghostGroup) return;
    const THREE = this.THREE;
    const fill = (group, matrices, material) => {
      const want = matrices.length;
      while (group.children.length > want) group.remove(group.children.at(-1));
      while (group.children.length < want) {
        const m = new THREE.Mesh(this.mesh, material);
        m.matrixAutoUpdate = false;
        group.add(m);
      }
      group.children.forEach((m, i) => {
        m.matrix.set(...matrices[i]);
        m.matrixWorldNeedsUpdate = true;
      });
    };
    fill(this.ghostGroup, this.ghosts, this.ghostMaterial);
    fill(this.alternativeGroup, this.alternatives ?? [], this.alternativeMaterial);
  }

  /**
   * The suggested next views, best first: `{camera, frame, ...}` each (the camera in
   * scene-file form; its frame from Rust, `framesOfCameras`), or bare cameras; or null.
   * The best is drawn as an orange frustum with faces, the others as thin orange
   * frusta (those with a frame); the best's JSON is shown to copy.
   */
  setSuggestion(suggestions) {
    const list = (Array.isArray(suggestions) ? suggestions : suggestions?.cameras ?? suggestions?.views ?? [])
      .map((c) => (c?.camera ? c : { camera: c }))
      .filter((c) => c.camera && Array.isArray(c.camera.world_to_camera));
    this.suggestion = list.length ? list.map((c) => clean(c.camera)) : null;
    this.suggestionFrames = list.map((c) => c.frame ?? null);
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
      this.suggestionFrames.forEach((frame, i) => {
        if (!frame) return;
        const g = this.frustum(frame, i === 0 ? SUGGESTION_COLOUR : 0x8a5a2b, null, i === 0);
        g.name = i === 0 ? 'suggestion:best' : `suggestion:${i}`;
        this.suggestionGroup.add(g);
      });
      this.world.add(this.suggestionGroup);
    }
    this.setVisible({});
  }

  /** What is drawn, for tests: counts, the object's matrix (row-major, 16) and the frames rendered. */
  info() {
    const rows = (m) => m.clone().transpose().toArray(); // three's elements are column-major
    return {
      webgl: this.gl,
      note: this.note.hidden ? null : this.note.textContent,
      cameras: this.gl ? this.cameraGroup?.children.length ?? 0 : this.cameras.length,
      pictures: this.gl ? this.cameraGroup?.children.filter((g) => g.getObjectByName('picture')).length ?? 0 : 0,
      triangles: this.geometryInfo?.triangles ?? 0,
      objectVisible: Boolean(this.object?.visible),
      objectMatrix: this.object ? rows(this.object.matrix) : null,
      ghosts: this.ghostGroup?.children.length ?? this.ghosts.length,
      ghostMatrices: this.ghostGroup?.children.map((g) => rows(g.matrix)) ?? [],
      alternatives: this.alternativeGroup?.children.length ?? this.alternatives.length,
      alternativeMatrices: this.alternativeGroup?.children.map((g) => rows(g.matrix)) ?? [],
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
      if (child !== this.object && child !== this.ghostGroup && child !== this.alternativeGroup) disposeTree(child);
    }
    this.mesh?.dispose();
    this.objectMaterial?.dispose();
    this.ghostMaterial?.dispose();
    this.alternativeMaterial?.dispose();
    this.cameraGroup = this.object = this.ghostGroup = this.alternativeGroup = this.suggestionGroup = null;
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
