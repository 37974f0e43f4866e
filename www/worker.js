// The fit's home: a module Web Worker that owns the wasm Session, so the page never
// waits for it. Which dropped file is the scene, the mesh, a mask or an image is
// decided in Rust (Session.fromFiles); this file only moves bytes and messages.
// Messages in: load {files}, example {path}, start, pause, step, reset, result,
// view {full}, cameras {on}, aspect3d {aspect}, setBox {view, box}, point {view, x, y,
// object}. Messages out: loaded {views, warnings, pool, photo},
// frame {progress, losses, overlays, size, running, pool},
// result {json}, finished {json} (the result, as the fit ends), error {message, fatal},
// view3d {scene | ghosts, suggestions},
// cameras {corrections, error} (the 3D view's and the corrections, at the end of this
// file). Every error — a load, a command, or a slice
// of the fitting loop — is caught and posted as an error, and the loop stops.
//
// With more than one core this worker is the coordinator of a pool of module Workers
// (pool-worker.js), each holding a wasm Shard built once from the loaded files (and the
// wasm module compiled here): every step is request → split → post to the pool → gather
// → respond, and a frame is sent every FRAME_MS. Pool size: min(N, views, MAX_POOL),
// N from `?pool=N` in this worker's URL (main.js passes on the page's) or else
// hardwareConcurrency; no pool below 2 (`?pool=0` or `?pool=1`: none). Without a pool (one core, a pool that failed to start, or after a pool
// error until the next load) the Session steps here, with stepFor.
import init, { FileSet, Session, PhotoSession, sceneFiles, meshFiles, framesOfCameras } from './pkg/localisebot.js';
import { Segmenters } from './photo.js';
import { holdLifeline, lifelineName, watchLifeline, withLifeline } from './lifeline.js';

// The page watches this Worker's end through a lock it holds (lifeline.js).
holdLifeline();

const FRAME_MS = 60; // a frame every 60 ms at most while fitting (16 a second)
const WINDOW_PX = 256; // side of an object-window overlay
const MAX_POOL = 8; // more workers than this buy little: an iteration has few views
const POOL_START_MS = 30_000; // a pool not ready by then is given up (the fit runs here)
// The wasm module, compiled once here and posted to the pool's Workers, which
// instantiate it without compiling it again (and share its optimised code).
const wasmModule = (async () => {
  const url = new URL('./pkg/localisebot_bg.wasm', import.meta.url);
  try {
    return await WebAssembly.compileStreaming(fetch(url));
  } catch {
    const res = await fetch(url); // e.g. served without the application/wasm type
    if (!res.ok) throw new Error(`pkg/localisebot_bg.wasm: HTTP ${res.status}`);
    return WebAssembly.compile(await res.arrayBuffer());
  }
})();
const ready = wasmModule.then((module) => init({ module_or_path: module }));
let session = null;
let files = null; // the loaded files, for the pool's shards
let pool = null;
let running = false;
let runs = 0; // the current run loop's number (one loop at a time)
let fullFrame = false; // overlays of the whole image instead of each view's object window
let refineCameras = false; // correct each view's camera jointly with the pose
let suggestAbove = false; // next views from the upper half of the sphere only
let photo = null; // a PhotoSession, for a scene of photographs without masks
let roundOpen = false; // the session is a photo round's fit not yet handed to photo.advance
let segmenters = null; // the segmenter pool (photo.js), a promise while it starts

const poolParam = new URL(self.location.href).searchParams.get('pool');

const post = (msg, transfer = []) => postMessage(msg, transfer);

// Commands that step or replace the session run one at a time, and never during a
// pool round: `exclusive(fn)` runs fn after whatever is running.
let lock = Promise.resolve();
function exclusive(fn) {
  const p = lock.then(fn);
  lock = p.catch(() => {});
  return p;
}

// Stops the loop and tells the page. A WebAssembly.RuntimeError is a bug (a trap):
// the page then starts a fresh worker rather than trust this instance.
function fail(e) {
  running = false;
  const fatal = e instanceof WebAssembly.RuntimeError;
  post({ type: 'error', message: e?.message ?? String(e), fatal, running: false });
}

// Sends the current state: progress, loss trace and every view's overlay — its
// object window (WINDOW_PX square) or, when asked, the whole image — and, for a
// photograph session, the points clicked on each view in its overlay's pixels.
function frame(progress = session.progress()) {
  const losses = session.losses();
  const overlays = [];
  for (let i = 0; i < session.viewCount; i++) {
    overlays.push((fullFrame ? session.overlay(i) : session.overlayWindow(i, WINDOW_PX)).buffer);
  }
  const size = fullFrame ? null : WINDOW_PX;
  const marks = photo ? pointMarks() : null;
  // A photograph session is done when its rounds are, not when a round's fit is.
  if (photo) progress = { ...progress, done: progress.done && photo.done && !roundOpen, round: photo.rounds };
  post({ type: 'frame', progress, losses, overlays, size, running, pool: pool?.size ?? 0, marks },
    [losses.buffer, ...overlays]);
  done3d(progress);
}

// ---- the pool ------------------------------------------------------------------
// The number of pool workers for a session of `views` views (0: none).
function poolSize(views) {
  const cores = navigator.hardwareConcurrency || 1;
  const wanted = poolParam === null ? cores : Number.parseInt(poolParam, 10) || 0;
  const n = Math.min(wanted, views, MAX_POOL);
  return n >= 2 ? n : 0;
}

// n Workers, each with a Shard of the session owning views i, i + n, … (round robin);
// resolves once all are ready, rejects on the first failure (all then terminated).
class Pool {
  constructor(n) {
    this.size = n;
    this.workers = [];
    this.pending = new Map(); // id → { ok, fail }
    this.nextId = 0;
    this.broken = null;
    this.unwatch = []; // per worker: stops watching its lifeline
  }

  static async start(n, files, viewCount) {
    const pool = new Pool(n);
    const module = await wasmModule;
    try {
      await new Promise((ok, fail) => {
        let waiting = n;
        const timer = setTimeout(() => fail(new Error(`the pool did not start within ${POOL_START_MS / 1000} s`)),
          POOL_START_MS);
        for (let i = 0; i < n; i++) {
          const life = lifelineName('pool');
          const w = new Worker(withLifeline(new URL('./pool-worker.js', import.meta.url), life), { type: 'module' });
          pool.workers.push(w);
          // Its end, from when it holds its lifeline, fails the start or breaks the pool.
          pool.unwatch.push(watchLifeline(life, () => {
            const e = new Error(`pool worker ${i} stopped without a word (the browser ended it: out of memory, or a crash)`);
            clearTimeout(timer);
            fail(e);
            pool.breaks(e);
          }));
          const views = [];
          for (let v = i; v < viewCount; v += n) views.push(v);
          w.onmessage = ({ data }) => {
            if (data.type === 'ready' && data.views === viewCount) {
              if (--waiting === 0) {
                clearTimeout(timer);
                ok();
              }
            } else {
              clearTimeout(timer);
              fail(new Error(data.message ?? `pool worker ${i}: ${data.views} views, not ${viewCount}`));
            }
          };
          w.onerror = (e) => {
            e.preventDefault();
            clearTimeout(timer);
            fail(new Error(`pool worker ${i} failed to start: ${e.message || 'no message'}`));
          };
          // The compiled module and the files, once per worker (the files copied: each
          // worker keeps its own).
          w.postMessage({ type: 'init', module, files, views });
        }
      });
    } catch (e) {
      pool.terminate();
      throw e;
    }
    pool.workers.forEach((w, i) => {
      w.onmessage = ({ data }) => pool.answer(data, i);
      w.onerror = (e) => {
        e.preventDefault();
        pool.breaks(new Error(`pool worker ${i} failed: ${e.message || 'no message'}`));
      };
      w.onmessageerror = () => pool.breaks(new Error(`pool worker ${i}: a message could not be read`));
    });
    return pool;
  }

  answer(data, i) {
    const p = this.pending.get(data.id);
    if (!p) return;
    this.pending.delete(data.id);
    if (data.type === 'done') p.ok(data.response);
    else p.fail(new Error(`pool worker ${i}: ${data.message}`));
  }

  // A worker died: every request in flight fails, and so does every later one.
  breaks(e) {
    this.broken ??= e;
    for (const p of this.pending.values()) p.fail(e);
    this.pending.clear();
  }

  // Each worker's share of one step: parts[i] to worker i (fewer parts than workers:
  // the first ones); resolves to the responses in that order.
  work(parts) {
    if (this.broken) return Promise.reject(this.broken);
    return Promise.all(parts.map((request, i) => new Promise((ok, fail) => {
      const id = this.nextId++;
      this.pending.set(id, { ok, fail });
      this.workers[i].postMessage({ type: 'work', id, request });
    })));
  }

  terminate() {
    for (const stop of this.unwatch) stop();
    for (const w of this.workers) w.terminate();
    this.breaks(new Error('the pool was stopped'));
  }
}

function stopPool() {
  pool?.terminate();
  pool = null;
}

// A pool for the loaded session, if it wants one; on failure the fit runs here and the
// reason is returned as a notice.
async function startPool() {
  stopPool();
  const n = poolSize(session.viewCount);
  if (n === 0) return [];
  try {
    pool = await Pool.start(n, files, session.viewCount);
    return [];
  } catch (e) {
    return [`no worker pool (${e?.message ?? e}): the fit runs in one worker`];
  }
}

// One step through the pool: the same step as session.step(1), bit for bit; resolves
// to whether the fit is done (respond reports no Progress: the frame asks for it once).
// After an error the pool is not trusted: it is stopped, and the fit goes on here
// from the step that failed (the session never took its responses) until the next load.
async function poolStep() {
  try {
    const request = session.request();
    if (request === undefined) return true;
    const responses = await pool.work(session.splitRequest(request, pool.size));
    return session.respond(responses);
  } catch (e) {
    stopPool();
    if (e instanceof WebAssembly.RuntimeError) throw e; // a trap here: fatal, as without a pool
    throw new Error(`${e?.message ?? e} (the worker pool was stopped: the fit goes on in one worker)`);
  }
}

// ---- loading -------------------------------------------------------------------
// list: [{ path, bytes }], as dropped or fetched.
async function load(list) {
  running = false;
  runs++;
  const set = new FileSet();
  try {
    for (const f of list) set.add(f.path, f.bytes);
    if (set.needsSegmenter()) {
      // Photographs without masks: boxes first, then rounds of segmenting and fitting.
      const next = PhotoSession.fromFiles(set); // throws an Error naming what is missing
      stopPool();
      session?.free();
      session = null;
      photo?.free();
      photo = next;
      files = list;
      roundOpen = false;
      warmed.clear();
      segmenters?.then((pool) => pool.forget()).catch(() => {});
      loadedPhotos();
      return;
    }
    const next = Session.fromFiles(set); // throws an Error naming what is missing
    stopPool();
    session?.free();
    session = next;
    session.setRefineCameras(refineCameras);
    photo?.free();
    photo = null;
    files = list;
  } finally {
    set.free();
  }
  const notes = await startPool();
  // The 3D view's scene first: the page has it when it hears "loaded".
  scene3d();
  post({ type: 'loaded', views: session.views(), warnings: [...session.warnings(), ...notes], pool: pool?.size ?? 0 });
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

// ---- fitting -------------------------------------------------------------------
// A slice's fitting time: what is left of FRAME_MS after its frame (the views' IoUs
// and overlays, as long as the last one took), and at least twice the frame (on 12-MP
// views a frame costs more than FRAME_MS), so that the fit gets at least two thirds
// of the time whatever the size of the views, and more on small ones (drawing 30
// frames a second took a third of a photograph fit's time).
let overheadMs = 0;
const sliceMs = () => Math.max(FRAME_MS - overheadMs, 2 * overheadMs);

// Runs `work` (a slice: steps, then a frame) and measures the time it spent outside
// stepping the session.
async function measured(work) {
  const t0 = performance.now();
  const s0 = session.seconds;
  await work();
  if (session) overheadMs = Math.max(0, performance.now() - t0 - (session.seconds - s0) * 1000);
}

// One slice of fitting (sliceMs), then a frame.
async function slice() {
  if (!running || !session || session.done) return;
  if (photo && roundOpen && session.seconds === 0) session.setRefineCameras(refineCameras);
  await measured(async () => {
    let progress;
    const budget = sliceMs();
    if (pool) {
      const t0 = performance.now();
      let done;
      do done = await poolStep();
      while (running && !done && performance.now() - t0 < budget);
      progress = session.progress();
    } else {
      progress = session.stepFor(budget);
    }
    if (progress.done) running = false;
    frame(progress);
  });
}

// Runs the fit in slices, yielding between them so that pause and step messages get
// in. A slice that throws ends the run with an error message.
async function run() {
  if (photo) return runPhoto();
  const me = ++runs;
  while (running && me === runs && session && !session.done) {
    try {
      await exclusive(slice);
    } catch (e) {
      fail(e);
      return;
    }
    await new Promise((ok) => setTimeout(ok, 0));
  }
}

// Loads asked for: an example still being fetched when another load is asked for is
// dropped (the latest wins), and so is its error.
let loads = 0;

const handlers = {
  load: (msg) => {
    loads++;
    return exclusive(() => load(msg.files));
  },
  example: async (msg) => {
    const me = ++loads;
    let list;
    try {
      list = await example(msg.path);
    } catch (e) {
      if (me === loads) throw e;
      return;
    }
    if (me === loads) await exclusive(() => load(list));
  },
  start: () => {
    if (running) return;
    if (photo) {
      running = true;
      run();
      return;
    }
    if (!session || session.done) return;
    running = true;
    run();
  },
  setBox: (msg) => exclusive(() => {
    if (!photo) return;
    photo.setBox(msg.view, msg.box ? Float64Array.from(msg.box) : undefined);
    postBoxes();
    warm();
    resumeIfAsked();
  }),
  point: (msg) => exclusive(() => {
    if (!photo || !session) return;
    // By name: a view whose mask came back empty sits a round's fit out.
    const [x, y] = toImage(session.views().findIndex((v) => v.name === msg.name), msg.x, msg.y);
    photo.togglePoint(photo.views().findIndex((v) => v.name === msg.name), x, y, Boolean(msg.object));
    postBoxes();
    frame();
    resumeIfAsked();
  }),
  pause: () => {
    running = false;
    return exclusive(() => session && frame());
  },
  step: () => {
    running = false;
    return exclusive(async () => {
      if (!session || (photo && !roundOpen)) return;
      if (pool && !session.done) {
        await poolStep();
        frame();
      } else {
        frame(session.step(1));
      }
    });
  },
  reset: () => {
    running = false;
    // The pool's shards hold only the inputs: they serve the fit from the start again.
    return exclusive(() => {
      if (photo) return resetPhotos();
      if (!session) return;
      session.reset();
      frame();
    });
  },
  cameras: (msg) => {
    refineCameras = Boolean(msg.on);
    return exclusive(() => session && !session.done && session.setRefineCameras(refineCameras));
  },
  viewpoints: (msg) => {
    suggestAbove = Boolean(msg.above);
    return exclusive(() => session && session.done && suggest3d());
  },
  result: () => exclusive(() => session && post({
    type: 'result', json: photo ? photo.resultJson(session) : session.resultJson(),
  })),
  view: (msg) => {
    fullFrame = Boolean(msg.full);
    return exclusive(() => session && frame());
  },
  // The 3D view's width/height, for where its viewer starts (the next scene's).
  aspect3d: (msg) => {
    aspect3d = Number(msg.aspect) || 1;
  },
};

// ---- 3D view (www/view3d.js) --------------------------------------------------------
// After a load: the mesh for display, the cameras, each view's picture and the frames
// Rust computes for drawing them (Session.cameraFrames). When the fit is done: GHOSTS
// ghosts of the result (Session.ghosts: object-to-world matrices drawn from its
// covariance, seeded; none until the result has one), an ambiguous fit's alternative
// poses (the result's `alternatives`) and, when the wasm has
// Session.suggestViews, the 3 best next views (from the upper half of the sphere with
// "next view from above"), each with its frame (framesOfCameras). When it is no longer
// done (Reset), both are cleared. A failure here is reported to the page's 3D view only.
const PICTURE_PX = 512; // longest side of a view's picture on its image plane
const GHOSTS = 12; // ghosts drawn
const GHOST_SEED = 1; // the same ghosts every time
let finished3d = false;
let aspect3d = 1; // the 3D view's width/height (main.js sends it)
let depth3d = null; // the scene's image-plane depth, for the suggestions' frusta

function scene3d() {
  finished3d = false;
  depth3d = null;
  try {
    const geometry = session.geometry();
    const cameras = session.cameras();
    const pictures = cameras.map((_, i) => session.viewPicture(i, PICTURE_PX));
    const frames = session.cameraFrames(aspect3d);
    depth3d = frames.depth;
    post({ type: 'view3d', scene: { geometry, cameras, pictures, frames } },
      [geometry.positions.buffer, geometry.indices.buffer, ...pictures.map((p) => p.rgba.buffer)]);
  } catch (e) {
    post({ type: 'view3d', error: e?.message ?? String(e) });
  }
}

function done3d(progress) {
  if (progress.done === finished3d) return;
  finished3d = progress.done;
  if (!progress.done) {
    post({ type: 'view3d', ghosts: null, alternatives: null, suggestions: null });
    post({ type: 'cameras', corrections: null, error: null });
    return;
  }
  const msg = { type: 'view3d', ghosts: null, alternatives: null, suggestions: null };
  try {
    // The result first, for "Download result" (the suggestions below can take seconds on a big mesh).
    let json = null;
    try {
      json = photo ? photo.resultJson(session) : session.resultJson();
    } finally {
      post({ type: 'finished', json }); // null: the page asks again, and shows the error
    }
    const result = JSON.parse(json);
    msg.ghosts = session.ghosts(GHOSTS, GHOST_SEED);
    // An ambiguous fit's alternatives (FitResult.alternatives), drawn as ghosts of their own colour.
    msg.alternatives = (result.alternatives ?? []).map((a) => a.matrix);
    post({ type: 'cameras', corrections: result.camera_corrections ?? null, test: result.camera_test ?? null, error: result.camera_correction_error ?? null });
    msg.suggestions = suggestions();
  } catch (e) {
    msg.error = e?.message ?? String(e);
  }
  post(msg);
}

// The 3 best next views from the chosen viewpoints, each with its frame for the 3D
// view (null when the wasm has none).
function suggestions() {
  if (typeof session.suggestViews !== 'function') return null;
  const list = session.suggestViews(3, suggestAbove ? 'above' : 'sphere');
  const frames = framesOfCameras(list.map((s) => s.camera), depth3d ?? session.cameraFrames().depth);
  return list.map((s, i) => ({ ...s, frame: frames[i] }));
}

// The suggestions again, after the viewpoints changed on a finished fit.
function suggest3d() {
  try {
    post({ type: 'view3d', suggestions: suggestions() });
  } catch (e) {
    post({ type: 'view3d', error: e?.message ?? String(e) });
  }
}

onmessage = async ({ data }) => {
  try {
    await ready;
    await handlers[data.type]?.(data);
  } catch (e) {
    fail(e);
  }
};

// ---- photographs without masks (a PhotoSession) ------------------------------------
// After the load: each view's photograph for drawing boxes on, and the boxes; the
// segmenter starts loading at once (its module and weights), while boxes are drawn.
// Start runs rounds: the segmentations photo.jobs() names (spread over the segmenter's
// Workers, a progress message after each), photo.answer() → the round's fit, a Session
// stepped and shown like any other, then photo.advance(): prompts again, or done. A
// point clicked on a view (or a box redrawn) once done asks for one more round.
const PICTURE_SIDE = 1024; // longest side of a photograph shown for drawing boxes
const MAX_SEGMENTERS = 4;
const segParam = new URL(self.location.href).searchParams.get('segmenters');
const simdParam = new URL(self.location.href).searchParams.get('simd'); // '128': the segmenter's simd128 build
const hashParam = new URL(self.location.href).searchParams.get('hash'); // 'module': each segmenter Worker hashes the weights

function loadedPhotos() {
  const views = photo.views();
  const pictures = views.map((v, i) => (v.has_mask ? null : photo.picture(i, PICTURE_SIDE)));
  post({ type: 'loaded', views, warnings: photo.warnings(), pool: 0, photo: true });
  post({ type: 'pictures', pictures, boxes: photo.boxes() }, pictures.filter(Boolean).map((p) => p.rgba.buffer));
  startSegmenters(views.filter((v) => !v.has_mask).length).catch(() => {}); // reported when needed
  warm();
}

// The first round's crops of the views with a box, encoded while the other boxes are
// drawn (each crop once): Start then finds them encoded. The crops are those of the
// boxes as they stand when the segmenter is ready (a box redrawn while it loads is not
// encoded twice). Failures wait for Start.
const warmed = new Set();
let warming = 0; // batches of warmed crops under way
function warm() {
  if (!photo || photo.started) return;
  const p = photo;
  startSegmenters(p.views().filter((v) => !v.has_mask).length)
    .then((pool) => {
      if (photo !== p || p.started) return null; // another scene, or Start asked for its own
      const key = (j) => `${j.view}:${j.side}:${j.box}`;
      const all = [...p.warmJobs()];
      const jobs = all.filter((j) => !warmed.has(key(j)));
      const n = all.length;
      const ready = () => {
        // Said once no crop is being warmed, and while Start has not taken the line over.
        if (photo !== p || p.started || warming > 0) return;
        post({
          type: 'segmenting', done: 1, total: 1, finished: true, encodings: pool.encodings, simd: pool.simd, hashed: pool.hashed,
          text: `segmenter ready${n > 0 ? `, ${n} view${n > 1 ? 's' : ''} encoded` : ''}: Start segments and fits`,
        });
      };
      if (jobs.length === 0) return ready();
      const keys = jobs.map(key); // made now: the jobs' buffers go to the segmenter
      for (const k of keys) warmed.add(k);
      post({ type: 'segmenting', text: `encoding the crops of ${jobs.length} box${jobs.length > 1 ? 'es' : ''}…`, done: 0, total: 0 });
      warming++;
      return pool.segment(jobs, undefined, true).then(() => {
        warming--;
        ready();
      }, () => {
        warming--;
        keys.forEach((k) => warmed.delete(k));
      });
    })
    .catch(() => {});
}

function postBoxes() {
  post({ type: 'boxes', boxes: photo.boxes() });
}

// The segmenter pool, started once per worker (it serves every later photograph scene).
function startSegmenters(photos) {
  if (!segmenters) {
    const cores = navigator.hardwareConcurrency || 1;
    const wanted = segParam === null ? cores : Number.parseInt(segParam, 10) || 1;
    const n = Math.max(1, Math.min(wanted, photos, MAX_SEGMENTERS));
    const started = Segmenters.start(n, (text) => post({ type: 'segmenting', text, done: 0, total: 0 }), simdParam, hashParam);
    segmenters = started;
    // A pool that failed to start, or broke later (a Worker ended), is started again next time.
    const forget = () => {
      if (segmenters === started) segmenters = null;
    };
    started.then((pool) => {
      pool.onBroken = forget;
    }, forget);
  }
  return segmenters;
}

// Ends the segmenter pool (the next segmentation starts a new one).
function stopSegmenters() {
  segmenters?.then((pool) => pool.terminate(), () => {});
  segmenters = null;
}

// Canvas pixel (x, y) of view `view`'s overlay → image pixel.
function toImage(view, x, y) {
  if (fullFrame) return [x, y];
  const w = session.windows()[view];
  return [w.x0 + ((x + 0.5) * w.width) / WINDOW_PX, w.y0 + ((y + 0.5) * w.height) / WINDOW_PX];
}

// Each of the session's views' clicked points in its overlay's pixels: [[x, y, on], …].
function pointMarks() {
  if (!session) return null;
  const windows = session.windows();
  const boxes = photo.boxes();
  return session.views().map((v, i) => (boxes.find((b) => b.view === v.name)?.points ?? []).map(([x, y, on]) => {
    if (fullFrame) return [x, y, on];
    const w = windows[i];
    return [((x - w.x0) * WINDOW_PX) / w.width - 0.5, ((y - w.y0) * WINDOW_PX) / w.height - 0.5, on];
  }));
}

// Once done, a point or a box asks for a round: run it (unless paused mid-way).
function resumeIfAsked() {
  if (photo.jobs().length === 0 || running) return;
  running = true;
  run();
}

// One round's segmentations: the answers, in order.
// Seconds spent in each phase since Start: the segmenter's start, each round's
// segmentations and fit (posted with the segmenter's progress).
let timings = [];
const mark = (what, t0) => timings.push([what, Number(((performance.now() - t0) / 1000).toFixed(2))]);

// `makeJobs()` gives the jobs (photo.jobs(): their buffers go to the Workers); a pool
// broken because one of its Workers ended (out of memory, a crash) is started again and
// the round's jobs made and sent again, once: a second end is the round's error.
async function segmentJobs(makeJobs) {
  try {
    return await segmentOnce(makeJobs());
  } catch (e) {
    if (!e?.ended) throw e;
    post({ type: 'segmenting', text: `${e.message}: starting the segmenter again`, done: 0, total: 0 });
    stopSegmenters();
    return segmentOnce(makeJobs());
  }
}

async function segmentOnce(jobs) {
  const tStart = performance.now();
  const pool = await startSegmenters(jobs.length);
  mark('segmenter ready', tStart);
  post({ type: 'segmenting', text: `segmenting: 0 of ${jobs.length} views`, done: 0, total: jobs.length });
  const t0 = performance.now();
  const answers = await pool.segment(jobs, (k, n) => post({
    type: 'segmenting', text: `segmenting: ${k} of ${n} views`, done: k, total: n,
  }));
  mark(`round ${photo.rounds + 1}: segmenting`, t0);
  post({
    timings,
    type: 'segmenting', done: jobs.length, total: jobs.length, finished: true,
    text: `round ${photo.rounds + 1}: ${jobs.length} view(s) segmented in ${((performance.now() - t0) / 1000).toFixed(1)} s`,
    encodings: pool.encodings,
    simd: pool.simd,
    hashed: pool.hashed,
  });
  return answers;
}

// The rounds, from where they stand, until done or paused.
async function runPhoto() {
  const me = ++runs;
  try {
    while (running && me === runs && photo) {
      if (!photo.started) {
        timings = [];
        await exclusive(() => {
          photo.start();
          postBoxes();
        });
      }
      if (session && roundOpen && !session.done) {
        // The round's fit, in slices, a frame after each.
        await exclusive(() => measured(() => frame(session.stepFor(sliceMs()))));
      } else if (session && roundOpen) {
        await exclusive(() => {
          timings.push([`round ${photo.rounds}: fit`, Number(session.seconds.toFixed(2))]);
          post({ type: 'segmenting', text: `round ${photo.rounds}: fitted in ${session.seconds.toFixed(1)} s`, done: 1, total: 1, timings });
          const t0 = performance.now();
          photo.advance(session);
          mark(`round ${photo.rounds}: next prompts`, t0);
          roundOpen = false;
          if (photo.done) running = false;
          frame();
        });
      } else {
        const jobs = photo.jobs();
        if (jobs.length === 0) {
          running = false;
          if (session) frame();
          break;
        }
        let fresh = jobs; // the jobs made above, then (after a segmenter's end) made again
        const answers = await segmentJobs(() => {
          const made = fresh ?? photo.jobs();
          fresh = null;
          return made;
        });
        if (me !== runs || !photo) return; // a new scene was loaded meanwhile
        await exclusive(() => {
          const first = !session;
          const t0 = performance.now();
          const next = photo.answer(answers);
          mark(`round ${photo.rounds}: masks taken`, t0);
          session?.free();
          session = next;
          roundOpen = true;
          // The round's views (a view whose mask came back empty sits it out).
          post({ type: 'round', views: session.views(), round: photo.rounds });
          if (first) scene3d();
          frame();
        });
      }
      await new Promise((ok) => setTimeout(ok, 0));
    }
  } catch (e) {
    fail(e);
  }
}

// Reset: the photographs again, the boxes drawn kept, no fit.
function resetPhotos() {
  const boxes = photo.boxes();
  const set = new FileSet();
  try {
    for (const f of files) set.add(f.path, f.bytes);
    const next = PhotoSession.fromFiles(set);
    boxes.forEach((b, i) => {
      if (b.given) next.setBox(i, Float64Array.from(b.given));
    });
    photo.free();
    photo = next;
  } finally {
    set.free();
  }
  session?.free();
  session = null;
  roundOpen = false;
  loadedPhotos();
}
