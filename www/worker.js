// The fit's home: a module Web Worker that owns the wasm Session, so the page never
// waits for it. Messages in: load {files}, example, start, pause, step, reset,
// result. Messages out: loaded {views, warnings}, frame {progress, losses, overlays, running},
// result {json}, error {message, fatal}.
import init, { FileSet, Session, checkMesh } from './pkg/localisebot.js';
import { planScene } from './files.js';

const BUDGET_MS = 30; // work per frame: about 30 frames a second while fitting
const ready = init();
let session = null;
let running = false;

const post = (msg, transfer = []) => postMessage(msg, transfer);

// Sends the current state: progress, loss trace and every view's overlay.
function frame(progress = session.progress()) {
  const losses = session.losses();
  const overlays = [];
  for (let i = 0; i < session.viewCount; i++) {
    const px = session.overlay(i);
    overlays.push(px.buffer);
  }
  post({ type: 'frame', progress, losses, overlays, running }, [losses.buffer, ...overlays]);
}

function fileSet(files) {
  const set = new FileSet();
  for (const f of files) set.add(f.path, f.bytes);
  return set;
}

function load(files) {
  running = false;
  const plan = planScene(files);
  const set = fileSet(files);
  try {
    if (plan.meshOnly) {
      const { path, bytes } = plan.meshOnly;
      const triangles = checkMesh(path, bytes, set); // throws on a bad mesh
      throw new Error(
        `${path}: a valid mesh (${triangles} triangles), but there is no scene: ` +
          'add a scene.json (or one camera .json per view) and the masks',
      );
    }
    const next = Session.fromScene(plan.sceneFile, plan.sceneText, set);
    session?.free();
    session = next;
  } finally {
    set.free();
  }
  post({ type: 'loaded', views: session.views(), warnings: session.warnings(), source: plan.sceneFile });
  frame();
}

// The bundled example: www/example/scene.json and the files it names.
async function example() {
  const base = new URL('./example/', import.meta.url);
  const get = async (path) => {
    const res = await fetch(new URL(path, base));
    if (!res.ok) throw new Error(`example/${path}: HTTP ${res.status}`);
    return { path: `example/${path}`, bytes: new Uint8Array(await res.arrayBuffer()) };
  };
  const sceneFile = await get('scene.json');
  const scene = JSON.parse(new TextDecoder().decode(sceneFile.bytes));
  const paths = [scene.mesh, ...scene.views.flatMap((v) => (v.image ? [v.mask, v.image] : [v.mask]))];
  return [sceneFile, ...(await Promise.all(paths.map(get)))];
}

// Runs the fit in slices of BUDGET_MS, yielding between them so that pause and
// step messages get in.
function run() {
  if (!running || !session) return;
  const progress = session.stepFor(BUDGET_MS);
  if (progress.done) running = false;
  frame(progress);
  if (running) setTimeout(run, 0);
}

const handlers = {
  load: (msg) => load(msg.files),
  example: async () => load(await example()),
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
  result: () => session && post({ type: 'result', json: session.resultJson() }),
};

onmessage = async ({ data }) => {
  try {
    await ready;
    await handlers[data.type]?.(data);
  } catch (e) {
    running = false;
    // A WebAssembly.RuntimeError is a bug (a trap): the instance cannot be trusted.
    const fatal = e instanceof WebAssembly.RuntimeError;
    post({ type: 'error', message: e?.message ?? String(e), fatal });
  }
};
