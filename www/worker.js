// The fit's home: a module Web Worker that owns the wasm Session, so the page never
// waits for it. Which dropped file is the scene, the mesh, a mask or an image is
// decided in Rust (Session.fromFiles); this file only moves bytes and messages.
// Messages in: load {files}, example {path}, start, pause, step, reset, result,
// view {full}, cameras {on}. Messages out: loaded {views, warnings},
// frame {progress, losses, overlays, size, running},
// result {json}, error {message, fatal}, view3d {scene | covariance, suggestions}
// (the 3D view's, at the end of this file). Every error — a load, a command, or a slice
// of the fitting loop — is caught and posted as an error, and the loop stops.
import init, { FileSet, Session, sceneFiles, meshFiles } from './pkg/localisebot.js';

const BUDGET_MS = 30; // work per frame: about 30 frames a second while fitting
const WINDOW_PX = 256; // side of an object-window overlay
const ready = init();
let session = null;
let running = false;
let fullFrame = false; // overlays of the whole image instead of each view's object window
let refineCameras = false; // correct each view's camera jointly with the pose

const post = (msg, transfer = []) => postMessage(msg, transfer);

// Stops the loop and tells the page. A WebAssembly.RuntimeError is a bug (a trap):
// the page then starts a fresh worker rather than trust this instance.
function fail(e) {
  running = false;
  const fatal = e instanceof WebAssembly.RuntimeError;
  post({ type: 'error', message: e?.message ?? String(e), fatal, running: false });
}

// Sends the current state: progress, loss trace and every view's overlay — its
// object window (WINDOW_PX square) or, when asked, the whole image.
function frame(progress = session.progress()) {
  const losses = session.losses();
  const overlays = [];
  for (let i = 0; i < session.viewCount; i++) {
    overlays.push((fullFrame ? session.overlay(i) : session.overlayWindow(i, WINDOW_PX)).buffer);
  }
  const size = fullFrame ? null : WINDOW_PX;
  post({ type: 'frame', progress, losses, overlays, size, running }, [losses.buffer, ...overlays]);
  done3d(progress);
}

// files: [{ path, bytes }], as dropped or fetched.
function load(files) {
  running = false;
  const set = new FileSet();
  try {
    for (const f of files) set.add(f.path, f.bytes);
    const next = Session.fromFiles(set); // throws an Error naming what is missing
    session?.free();
    session = next;
    session.setRefineCameras(refineCameras);
  } finally {
    set.free();
  }
  post({ type: 'loaded', views: session.views(), warnings: session.warnings() });
  scene3d();
  frame();
}

// An example of www/examples/ (see scripts/build-examples.sh): its scene.json, at
// `path` relative to examples/, and the files the scene and its mesh name.
async function example(path) {
  const base = new URL('./examples/', import.meta.url);
  const get = async (p) => {
    const res = await fetch(new URL(p, base));
    if (!res.ok) throw new Error(`examples/${p}: HTTP ${res.status}`);
    return { path: p, bytes: new Uint8Array(await res.arrayBuffer()) };
  };
  const scene = await get(path);
  const [meshPath, ...others] = sceneFiles(path, new TextDecoder().decode(scene.bytes));
  const mesh = await get(meshPath);
  const rest = await Promise.all([...meshFiles(meshPath, mesh.bytes), ...others].map(get));
  return [scene, mesh, ...rest];
}

// Runs the fit in slices of BUDGET_MS, yielding between them so that pause and
// step messages get in. A slice that throws ends the run with an error message.
function run() {
  if (!running || !session) return;
  try {
    const progress = session.stepFor(BUDGET_MS);
    if (progress.done) running = false;
    frame(progress);
  } catch (e) {
    fail(e);
    return;
  }
  if (running) setTimeout(run, 0);
}

const handlers = {
  load: (msg) => load(msg.files),
  example: async (msg) => load(await example(msg.path)),
  start: () => {
    if (!session || session.done || running) return;
    running = true;
    run();
  },
  pause: () => {
    running = false;
    if (session) frame();
  },
  step: () => {
    running = false;
    if (!session) return;
    frame(session.step(1));
  },
  reset: () => {
    running = false;
    if (!session) return;
    session.reset();
    frame();
  },
  cameras: (msg) => {
    refineCameras = Boolean(msg.on);
    if (session && !session.done) session.setRefineCameras(refineCameras);
  },
  result: () => session && post({ type: 'result', json: session.resultJson() }),
  view: (msg) => {
    fullFrame = Boolean(msg.full);
    if (session) frame();
  },
};

// ---- 3D view (www/view3d.js) --------------------------------------------------------
// After a load: the mesh for display, the cameras and each view's picture. When the
// fit is done: the result's covariance (null until the result has one) and, when the
// wasm has Session.suggestViews, the 3 best next views. When it is no longer done
// (Reset), both are cleared. A failure here is reported to the page's 3D view only.
const PICTURE_PX = 512; // longest side of a view's picture on its image plane
let finished3d = false;

function scene3d() {
  finished3d = false;
  try {
    const geometry = session.geometry();
    const cameras = session.cameras();
    const pictures = cameras.map((_, i) => session.viewPicture(i, PICTURE_PX));
    post({ type: 'view3d', scene: { geometry, cameras, pictures } },
      [geometry.positions.buffer, geometry.indices.buffer, ...pictures.map((p) => p.rgba.buffer)]);
  } catch (e) {
    post({ type: 'view3d', error: e?.message ?? String(e) });
  }
}

function done3d(progress) {
  if (progress.done === finished3d) return;
  finished3d = progress.done;
  if (!progress.done) {
    post({ type: 'view3d', covariance: null, suggestions: null });
    post({ type: 'cameras', corrections: null, error: null });
    return;
  }
  const msg = { type: 'view3d', covariance: null, suggestions: null };
  try {
    const result = session.result();
    msg.covariance = result.covariance ?? null;
    post({ type: 'cameras', corrections: result.camera_corrections ?? null, error: result.camera_correction_error ?? null });
    if (typeof session.suggestViews === 'function') msg.suggestions = session.suggestViews(3);
  } catch (e) {
    msg.error = e?.message ?? String(e);
  }
  post(msg);
}

onmessage = async ({ data }) => {
  try {
    await ready;
    await handlers[data.type]?.(data);
  } catch (e) {
    fail(e);
  }
};
