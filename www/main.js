// The page: user interface only. The fit lives in worker.js; this file sends it the
// user's files and commands and paints the frames it sends back (one canvas per
// view, the loss curve, the pose, the status).
import { lifelineName, watchLifeline, withLifeline } from './lifeline.js';

const $ = (id) => document.getElementById(id);
const ui = {
  drop: $('drop'), input: $('file-input'), example: $('load-example'), choice: $('example-choice'),
  start: $('start'), pause: $('pause'), step: $('step'), reset: $('reset'), download: $('download'),
  status: $('status'), rate: $('rate'), error: $('error'), notice: $('notice'), views: $('views'), loss: $('loss'),
  verdict: $('verdict'), fullFrame: $('full-frame'), workers: $('workers'),
};
// `?pool=N`: a pool of N Workers computing the fit (0 or 1: the fit in one Worker);
// `?segmenters=N`: N segmenter Workers (1–4); without them the coordinator sizes both
// by the cores (worker.js).
const poolParam = new URLSearchParams(location.search).get('pool');
const segParam = new URLSearchParams(location.search).get('segmenters');
const simdParam = new URLSearchParams(location.search).get('simd');
// `?hash=module`: the segmenter's Workers hash its weights themselves, as where the page
// is not a secure context (no WebCrypto); by default the coordinator hashes them once.
const hashParam = new URLSearchParams(location.search).get('hash');

let worker = null;
let views = []; // [{ name, width, height, canvas, iou }]
// A scene of photographs without masks: boxes are drawn on the pictures until the first
// round's fit; then a click on a view adds (or removes) a point for the segmenter.
const photoState = { on: false, fitting: false, pictures: [], boxes: [], drag: null, marks: null };
let state = 'empty'; // empty | ready | running | paused | done
let latest = null; // the last frame not yet painted
let paints = []; // times of recent redraws while running, for the rate figure
let paintCount = 0;

// ---- worker -------------------------------------------------------------------
// The scene last asked for (files chosen or dropped, or an example), so that a Worker
// the browser ended can be replaced with the scene loaded again (once).
let lastLoad = null; // { files: [{path, file}] } | { example: path }, and `loaded`, `retried`
let loads = 0; // loads asked for: a slower earlier one (files still being read) is dropped
let life = null; // the fit Worker's lifeline (lifeline.js): { name, stop }
// The finished fit's result (JSON text), sent by the worker as the fit ends, so that
// "Download result" saves it at once, whatever the worker is busy with; null otherwise.
// `downloadWanted`: Download was clicked once done, before the result came.
let finishedJson = null;
let downloadWanted = false;

function startWorker() {
  const url = new URL('./worker.js', import.meta.url);
  if (poolParam !== null) url.searchParams.set('pool', poolParam);
  if (segParam !== null) url.searchParams.set('segmenters', segParam);
  if (simdParam !== null) url.searchParams.set('simd', simdParam);
  if (hashParam !== null) url.searchParams.set('hash', hashParam);
  const name = lifelineName('fit');
  worker = new Worker(withLifeline(url, name), { type: 'module' });
  // Its end, however it comes, is seen (lifeline.js).
  const me = (life = { name, stop: null });
  me.stop = watchLifeline(name, () => me === life && workerDied());
  worker.onmessage = ({ data }) => handlers[data.type]?.(data);
  // A worker started again (after a trap) still knows the 3D view's shape.
  if (scene3dState.view) send('aspect3d', { aspect: scene3dState.view.aspect() });
  worker.onerror = (e) => {
    e.preventDefault();
    showError(`the worker failed to start: ${e.message || 'could the wasm package (www/pkg/) be missing?'}`);
    if (state === 'running') state = 'paused';
    updateButtons();
  };
}

// Replaces the Worker on purpose (its instance is not to be trusted after a trap).
function restartWorker() {
  [finishedJson, downloadWanted] = [null, false];
  life?.stop();
  worker.terminate();
  buildViews([]);
  state = 'empty';
  startWorker();
}

// The fit's Worker ended without a word (the browser stopped it: out of memory, a
// crash, the tab's Workers killed): a new one is started and the last scene loaded
// again, once; the reason stays on the page.
function workerDied() {
  const again = lastLoad?.loaded && !lastLoad.retried;
  const message = `The fit's Worker stopped without a word (the browser ended it: out of memory, or a crash). ${
    again ? 'A new one has the scene loaded again: press Start to fit it.' : 'A new one is ready: load the scene again.'}`;
  worker.terminate();
  [finishedJson, downloadWanted] = [null, false];
  buildViews([]);
  state = 'empty';
  photoState.on = false;
  latest = null;
  startWorker();
  updateButtons();
  showError(message);
  if (again) {
    lastLoad.retried = true;
    kept = message;
    load(lastLoad).catch((e) => showError(`${message} Loading it again failed: ${e.message}`));
  }
}
let kept = null; // an error to show again once the scene is loaded again

const handlers = {
  loaded(msg) {
    [finishedJson, downloadWanted] = [null, false];
    clearError();
    if (kept) showError(kept);
    kept = null;
    if (lastLoad) lastLoad.loaded = true;
    ui.notice.textContent = msg.warnings.join('\n');
    ui.notice.hidden = msg.warnings.length === 0;
    photoState.on = Boolean(msg.photo);
    photoState.fitting = false;
    photoState.marks = null;
    buildViews(msg.views);
    showWorkers(msg.pool);
    showSegmenting(null);
    state = 'ready';
    if (photoState.on) {
      ui.status.textContent = 'Drag a box around the object on each photograph (two are enough: the others are '
        + 'proposed, dashed), then Start.';
      ui.verdict.hidden = true;
    }
    updateButtons();
  },
  // A photograph session's pictures (for drawing boxes on) and its boxes.
  pictures(msg) {
    photoState.pictures = msg.pictures.map((p) => p && {
      ...p, image: new ImageData(new Uint8ClampedArray(p.rgba.buffer), p.width, p.height),
    });
    photoState.boxes = msg.boxes;
    paintPictures();
  },
  boxes(msg) {
    photoState.boxes = msg.boxes;
    if (!photoState.fitting) paintPictures();
  },
  // The segmenter's progress: loading, then each view of a round.
  segmenting(msg) {
    showSegmenting(msg);
  },
  // A round's fit starts: its views (a view whose mask came back empty sits it out).
  round(msg) {
    photoState.fitting = true;
    if (msg.views.map((v) => v.name).join('\n') !== views.map((v) => v.name).join('\n')) buildViews(msg.views);
  },
  view3d: (msg) => to3d(msg),
  cameras: (msg) => showCorrections(msg),
  frame(msg) {
    if (!msg.progress.done) [finishedJson, downloadWanted] = [null, false];
    photoState.marks = msg.marks;
    // The worker's state is the truth: a frame sent before a Start, Pause or Reset
    // arrived (one in flight when the button was clicked) is put right by the next; a
    // stopped fit is ready at its start, else paused, whatever frames came before.
    const atStart = msg.progress.iteration === 0 && msg.progress.searched === 0;
    if (msg.progress.done) state = 'done';
    else if (msg.running) state = 'running';
    else if (['running', 'paused', 'ready'].includes(state)) state = atStart ? 'ready' : 'paused';
    showWorkers(msg.pool);
    if (!latest) requestAnimationFrame(paint);
    latest = msg;
    updateButtons();
  },
  finished(msg) {
    finishedJson = msg.json;
    if (!downloadWanted) return;
    downloadWanted = false;
    if (msg.json) saveResult(msg.json);
    else send('result'); // it could not be made as the fit ended: asked for again, its error shown
  },
  result: (msg) => saveResult(msg.json),
  // A load that failed, or a fitting slice that threw: the worker has stopped; the
  // message is shown and the controls are usable again.
  error(msg) {
    showError(msg.message);
    if (state === 'running') state = 'paused';
    if (msg.fatal) restartWorker(); // a trap inside wasm: start afresh rather than trust the old instance
    updateButtons();
  },
};

const send = (type, extra = {}, transfer = []) => worker.postMessage({ type, ...extra }, transfer);

// Saves the result (JSON text) as localisebot-result.json.
function saveResult(json) {
  const url = URL.createObjectURL(new Blob([json], { type: 'application/json' }));
  const a = Object.assign(document.createElement('a'), { href: url, download: 'localisebot-result.json' });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10_000);
}

// ---- files --------------------------------------------------------------------
// Loads a scene: { files: [{path, file}] } (read here, then handed to the Worker) or
// { example: path }. The latest asked for wins: files still being read when another
// load is asked for are dropped.
async function load(what) {
  const me = ++loads;
  lastLoad = what;
  if (what.example !== undefined) {
    send('example', { path: what.example });
    return;
  }
  ui.status.textContent = `reading ${what.files.length} file(s)…`;
  const files = await Promise.all(
    what.files.map(async ({ path, file }) => ({ path, bytes: new Uint8Array(await file.arrayBuffer()) })),
  );
  if (me !== loads) return;
  send('load', { files }, files.map((f) => f.bytes.buffer));
}

async function sendFiles(list) {
  clearError();
  if (list.length === 0) return;
  await load({ files: list });
}

// Every file under a dropped entry, with its folder-relative path.
async function walk(entry, out) {
  if (entry.isFile) {
    const file = await new Promise((ok, fail) => entry.file(ok, fail));
    out.push({ path: entry.fullPath.replace(/^\//, ''), file });
  } else if (entry.isDirectory) {
    const reader = entry.createReader();
    for (;;) {
      const batch = await new Promise((ok, fail) => reader.readEntries(ok, fail));
      if (batch.length === 0) break;
      for (const e of batch) await walk(e, out);
    }
  }
}

async function dropped(dt) {
  const entries = [...dt.items].map((i) => i.webkitGetAsEntry?.()).filter(Boolean);
  if (entries.length === 0) return [...dt.files].map((file) => ({ path: file.name, file }));
  const out = [];
  for (const e of entries) await walk(e, out);
  return out;
}

ui.input.addEventListener('change', () => {
  const list = [...ui.input.files].map((file) => ({ path: file.webkitRelativePath || file.name, file }));
  ui.input.value = '';
  sendFiles(list).catch((e) => showError(e.message));
});
// Files dropped anywhere on the page are taken (rather than opened by the browser).
window.addEventListener('dragover', (e) => {
  e.preventDefault();
  ui.drop.classList.add('over');
});
window.addEventListener('dragleave', (e) => e.relatedTarget === null && ui.drop.classList.remove('over'));
window.addEventListener('drop', (e) => {
  e.preventDefault();
  ui.drop.classList.remove('over');
  dropped(e.dataTransfer).then(sendFiles).catch((err) => showError(err.message));
});

// ---- controls -----------------------------------------------------------------
// The examples scripts/build-examples.sh made: examples/index.json lists them.
async function listExamples() {
  const res = await fetch(new URL('./examples/index.json', import.meta.url));
  if (!res.ok) throw new Error(`examples/index.json: HTTP ${res.status}`);
  const { examples } = await res.json();
  ui.choice.replaceChildren(
    ...examples.map(({ id, title, path }) => Object.assign(new Option(title, path), { id: `example-${id}` })),
  );
  const toy = examples.findIndex((e) => e.id === 'toy');
  ui.choice.selectedIndex = Math.max(toy, 0);
  ui.example.disabled = ui.choice.disabled = examples.length === 0;
}
listExamples().catch((e) => {
  ui.status.textContent = `No examples (${e.message}): run scripts/build-examples.sh, or drop your files.`;
});

ui.example.addEventListener('click', () => {
  clearError();
  ui.status.textContent = `loading the example ${ui.choice.selectedOptions[0]?.text ?? ''}…`;
  load({ example: ui.choice.value });
});
ui.start.addEventListener('click', () => {
  clearError();
  state = 'running';
  paints = [];
  updateButtons();
  send('start');
});
ui.pause.addEventListener('click', () => send('pause'));
ui.step.addEventListener('click', () => send('step'));
ui.reset.addEventListener('click', () => {
  state = 'ready';
  send('reset');
});
// A finished fit's result is here already, or on its way (the worker sends it as the fit
// ends); before the end, the worker makes it at the current pose.
ui.download.addEventListener('click', () => {
  if (finishedJson) saveResult(finishedJson);
  else if (state === 'done') downloadWanted = true;
  else send('result');
});
// Each view shows its object window by default; the toggle shows the whole image.
ui.fullFrame.addEventListener('change', () => send('view', { full: ui.fullFrame.checked }));
$('refine-cameras').addEventListener('change', (e) => send('cameras', { on: e.target.checked }));
// The next view's candidates: the whole sphere, or its upper half (a camera over a table).
$('suggest-above').addEventListener('change', (e) => send('viewpoints', { above: e.target.checked }));

// The camera corrections of a fit done with "refine cameras" (or why there are none),
// and whether they were applied (only when they explain enough of the loss).
function showCorrections({ corrections, test, error }) {
  const el = $('camera-corrections');
  el.hidden = !corrections && !error;
  el.dataset.applied = test ? String(test.applied) : '';
  const verdict = test
    ? ` (they remove ${(100 * test.loss_reduction).toFixed(1)} % of the loss: ${
        test.applied ? 'applied' : `not applied, below ${(100 * test.min_reduction).toFixed(0)} %`
      })`
    : '';
  el.textContent = error
    ? `Cameras not corrected: ${error}`
    : (corrections ?? [])
        .map((c) => `${c.view}: ${c.angle_deg.toFixed(2)}°, ${c.shift_pct.toFixed(2)} % of its distance`)
        .join(' · ')
        .replace(/^/, corrections?.length ? 'Camera corrections — ' : '') + verdict;
}

function updateButtons() {
  const loaded = state !== 'empty';
  ui.start.disabled = !(state === 'ready' || state === 'paused');
  ui.pause.disabled = state !== 'running';
  const boxing = photoState.on && !photoState.fitting; // boxes still to draw: nothing to step or download
  ui.step.disabled = boxing || !(state === 'ready' || state === 'paused');
  ui.reset.disabled = !loaded;
  ui.download.disabled = !loaded || boxing;
}

// How many Workers compute the fit: a pool of n (the coordinator besides), or one.
function showWorkers(n) {
  ui.workers.dataset.pool = n;
  ui.workers.textContent = n ? `pool of ${n} workers` : '1 worker';
}

function showError(message) {
  ui.error.textContent = message;
  ui.error.hidden = false;
}
function clearError() {
  ui.error.hidden = true;
  ui.error.textContent = '';
}

// ---- painting -----------------------------------------------------------------
function buildViews(list) {
  ui.views.replaceChildren();
  views = list.map((v) => {
    const fig = $('view-template').content.firstElementChild.cloneNode(true);
    const canvas = fig.querySelector('canvas');
    canvas.width = v.width;
    canvas.height = v.height;
    fig.querySelector('.name').textContent = v.name;
    ui.views.append(fig);
    const view = { ...v, fig, canvas, ctx: canvas.getContext('2d'), iou: fig.querySelector('.iou') };
    canvas.addEventListener('pointerdown', (e) => pointerDown(view, e));
    canvas.addEventListener('pointermove', (e) => pointerMove(view, e));
    canvas.addEventListener('pointerup', (e) => pointerUp(view, e));
    canvas.addEventListener('contextmenu', (e) => photoState.on && e.preventDefault());
    return view;
  });
}

// ---- photographs: boxes and points ---------------------------------------------------
// A canvas point of a pointer event, in canvas pixels (edges: pixel i spans [i, i + 1]).
function canvasPoint(v, e) {
  const r = v.canvas.getBoundingClientRect();
  return [((e.clientX - r.left) * v.canvas.width) / r.width, ((e.clientY - r.top) * v.canvas.height) / r.height];
}

function pointerDown(v, e) {
  if (!photoState.on) return;
  const i = views.indexOf(v);
  if (!photoState.fitting && photoState.pictures[i]) {
    v.canvas.setPointerCapture(e.pointerId);
    photoState.drag = { view: i, from: canvasPoint(v, e), to: canvasPoint(v, e) };
  } else if (photoState.fitting && (state === 'done' || state === 'paused')) {
    // A point for the segmenter: on the object, or (shift, right button) off it.
    const [x, y] = canvasPoint(v, e);
    clearError();
    state = 'running';
    updateButtons();
    send('point', { name: v.name, x: x - 0.5, y: y - 0.5, object: !(e.shiftKey || e.button === 2) });
  }
}

function pointerMove(v, e) {
  const d = photoState.drag;
  if (!d || views[d.view] !== v) return;
  d.to = canvasPoint(v, e);
  paintPictures();
}

function pointerUp(v, e) {
  const d = photoState.drag;
  if (!d || views[d.view] !== v) return;
  photoState.drag = null;
  d.to = canvasPoint(v, e);
  const s = photoState.pictures[d.view].scale;
  const [x0, x1] = [d.from[0], d.to[0]].sort((a, b) => a - b);
  const [y0, y1] = [d.from[1], d.to[1]].sort((a, b) => a - b);
  if (x1 - x0 < 3 || y1 - y0 < 3) {
    paintPictures(); // a click, not a drag
    return;
  }
  clearError();
  send('setBox', { view: d.view, box: [x0 / s, y0 / s, x1 / s, y1 / s] });
}

// The pictures with their boxes: drawn or given (green), proposed (orange, dashed), and
// the one being dragged.
function paintPictures() {
  views.forEach((v, i) => {
    const p = photoState.pictures[i];
    if (!p) return;
    if (v.canvas.width !== p.width || v.canvas.height !== p.height) Object.assign(v.canvas, { width: p.width, height: p.height });
    v.ctx.putImageData(p.image, 0, 0);
    const b = photoState.boxes[i];
    const rect = (box, colour, dashed) => {
      v.ctx.save();
      v.ctx.strokeStyle = colour;
      v.ctx.lineWidth = 2;
      if (dashed) v.ctx.setLineDash([6, 4]);
      v.ctx.strokeRect(box[0] * p.scale, box[1] * p.scale, (box[2] - box[0]) * p.scale, (box[3] - box[1]) * p.scale);
      v.ctx.restore();
    };
    if (b?.given) rect(b.given, '#2ecc40', false);
    else if (b?.proposed) rect(b.proposed, '#ff7a00', true);
    const d = photoState.drag;
    if (d && d.view === i) {
      rect([d.from[0] / p.scale, d.from[1] / p.scale, d.to[0] / p.scale, d.to[1] / p.scale], '#ffffff', true);
    }
    v.fig.dataset.box = b?.given ? 'given' : b?.proposed ? 'proposed' : 'none';
    v.fig.dataset.shown = JSON.stringify({ box: b?.given ?? b?.proposed ?? null, scale: p.scale });
    v.iou.textContent = b?.given ? 'box drawn' : b?.proposed ? 'box proposed' : 'no box yet';
  });
}

// A point clicked for the segmenter: a green dot on the object, a red cross off it.
function drawMark(ctx, x, y, on) {
  ctx.save();
  ctx.lineWidth = 2;
  ctx.strokeStyle = '#000';
  ctx.fillStyle = on ? '#2ecc40' : '#ff4136';
  ctx.beginPath();
  if (on) {
    ctx.arc(x, y, 4, 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
  } else {
    ctx.strokeStyle = '#ff4136';
    ctx.moveTo(x - 4, y - 4);
    ctx.lineTo(x + 4, y + 4);
    ctx.moveTo(x + 4, y - 4);
    ctx.lineTo(x - 4, y + 4);
    ctx.stroke();
  }
  ctx.restore();
}

// The segmenter's progress bar and line (hidden with null).
function showSegmenting(msg) {
  const bar = $('seg-progress');
  const text = $('seg-text');
  bar.hidden = text.hidden = !msg;
  if (!msg) return;
  text.textContent = msg.text;
  if (msg.total > 0) {
    bar.max = msg.total;
    bar.value = msg.done;
  } else {
    bar.removeAttribute('value'); // indeterminate while loading
  }
  bar.dataset.finished = msg.finished ? 'true' : 'false';
  // Every run of the encoders so far ({count, ms}), for the tests to print.
  if (msg.encodings) text.dataset.encodings = JSON.stringify(msg.encodings);
  // The segmenter's build in use: 'relaxed' (relaxed SIMD) or '128'.
  if (msg.simd) text.dataset.simd = msg.simd;
  // Who hashed the weights: 'webcrypto' (the coordinator) or 'module' (each Worker).
  if (msg.hashed) text.dataset.hashed = msg.hashed;
  // Where the time of a photograph fit went (the worker's phases), for the tests to print.
  if (msg.timings) document.body.dataset.timings = JSON.stringify(msg.timings);
}

function paint() {
  const msg = latest;
  latest = null;
  if (!msg || msg.overlays.length !== views.length) return;
  const p = msg.progress;
  views.forEach((v, i) => {
    // An object window (msg.size square) or the whole image (the view's size).
    const [w, h] = msg.size ? [msg.size, msg.size] : [v.width, v.height];
    if (v.canvas.width !== w || v.canvas.height !== h) Object.assign(v.canvas, { width: w, height: h });
    v.ctx.putImageData(new ImageData(new Uint8ClampedArray(msg.overlays[i]), w, h), 0, 0);
    v.iou.textContent = p.iou[i].toFixed(3);
    for (const [x, y, on] of msg.marks?.[i] ?? []) drawMark(v.ctx, x + 0.5, y + 0.5, on);
  });
  showVerdict(p);
  drawLoss(msg.losses);
  showPose(p.pose);
  to3d({ pose: p.matrix });
  ui.status.textContent = statusText(p);
  paintCount++;
  ui.status.dataset.paints = paintCount;
  const now = performance.now();
  if (state === 'running' || p.done) {
    paints.push(now);
    while (paints.length > 2 && now - paints[0] > 1000) paints.shift();
  }
  if (paints.length > 1) {
    const span = (paints.at(-1) - paints[0]) / 1000;
    ui.rate.textContent = `${((paints.length - 1) / span).toFixed(0)} redraws/s`;
  }
}

function statusText(p) {
  const secs = `${p.seconds.toFixed(2)} s`;
  const round = p.round ? `round ${p.round}: ` : '';
  if (p.done && p.round) {
    return `done — verdict ${p.verdict} after ${p.round} round(s) of segmenting and fitting; click a view to add `
      + 'a point on the object (shift-click: off it; click a point again to remove it) and refit';
  }
  if (p.done) {
    // A failed fit is never "converged": the verdict comes first.
    const why = { converged: 'converged', completed: 'schedule completed', stalled: 'stalled, best pose kept' }[p.termination] ?? p.termination;
    return `done — verdict ${p.verdict} (${why}) in ${p.iteration} iterations, ${secs}`;
  }
  const prefix = state === 'paused' ? 'paused — ' : state === 'ready' && p.iteration === 0 && p.searched === 0 ? 'ready — ' : '';
  if (p.phase === 'search') return `${prefix}${round}search: ${p.searched}/${p.search_total} orientations, ${secs}`;
  const loss = Number.isFinite(p.loss) ? `, loss ${p.loss.toFixed(4)}` : '';
  if (p.phase === 'done') return `${prefix}${round}fitted (verdict ${p.verdict}), ${secs}: segmenting again…`;
  return `${prefix}${round}refine: stage ${p.stage + 1}/${p.stages}, candidate ${p.candidate + 1}, iteration ${p.iteration}${loss}, ${secs}`;
}

// The verdict, plainly: ok / poor / ambiguous / failed, with its reasons and the views it doubts.
function showVerdict(p) {
  const el = ui.verdict;
  if (!p.done || !p.verdict) {
    el.hidden = true;
    return;
  }
  el.hidden = false;
  el.className = `verdict ${p.verdict}`;
  el.dataset.verdict = p.verdict;
  const label = {
    ok: 'ok — every view agrees with the pose',
    poor: 'poor — some views disagree',
    ambiguous: 'ambiguous — another pose explains the masks nearly as well (magenta in the 3D view); add a view from a suggested camera',
    failed: 'failed — the pose does not explain the masks',
  }[p.verdict];
  const doubted = p.doubted_views.length ? ` Doubted: ${p.doubted_views.join(', ')}.` : '';
  el.textContent = `Verdict: ${label}.${doubted}${p.verdict_reasons.length ? ' ' + p.verdict_reasons.join('; ') + '.' : ''}`;
  views.forEach((v, i) => v.fig.classList.toggle('doubted', p.doubted_views.includes(v.name)));
}

const fmt = (xs, d = 3) => xs.map((x) => x.toFixed(d)).join('  ');
function showPose(pose) {
  $('pose-t').textContent = fmt(pose.translation, 4);
  $('pose-s').textContent = fmt(pose.scale, 4);
  $('pose-e').textContent = fmt(pose.euler_xyz_deg, 1);
  $('pose-q').textContent = fmt(pose.quaternion, 4);
}

// The loss of every refinement iteration, log scale.
function drawLoss(losses) {
  const c = ui.loss;
  const ctx = c.getContext('2d');
  ctx.clearRect(0, 0, c.width, c.height);
  const ys = [...losses].filter((y) => y > 0 && Number.isFinite(y)).map(Math.log10);
  if (ys.length < 2) return;
  const lo = Math.min(...ys);
  const hi = Math.max(...ys);
  const pad = 18;
  const x = (i) => pad + (i / (ys.length - 1)) * (c.width - 2 * pad);
  const y = (v) => c.height - pad - ((v - lo) / (hi - lo || 1)) * (c.height - 2 * pad);
  ctx.strokeStyle = '#1f6feb';
  ctx.lineWidth = 1.5;
  ctx.beginPath();
  ys.forEach((v, i) => (i ? ctx.lineTo(x(i), y(v)) : ctx.moveTo(x(i), y(v))));
  ctx.stroke();
  ctx.fillStyle = '#555';
  ctx.font = '11px system-ui, sans-serif';
  ctx.fillText(`${10 ** hi < 0.01 ? (10 ** hi).toExponential(1) : (10 ** hi).toFixed(3)}`, 2, pad - 6);
  ctx.fillText(`${(10 ** ys.at(-1)).toFixed(4)} (${ys.length} iterations)`, 2, c.height - 4);
}

// ---- 3D view (www/view3d.js, three.js) ------------------------------------------
// Loaded on its own: without it (or without WebGL) the page works, and says so there.
// Messages for it wait until it is there; the last of each kind is what counts.
const scene3dState = { view: null, waiting: {} };
function to3d(msg) {
  if (msg.error) console.warn(`3D view: ${msg.error}`);
  if (scene3dState.view) scene3dState.view.apply(msg);
  else Object.assign(msg.scene ? (scene3dState.waiting = {}) : scene3dState.waiting, msg);
}
import('./view3d.js')
  .then(({ mountView3d }) => mountView3d($('view3d')))
  .then((view) => {
    scene3dState.view = view;
    view.apply(scene3dState.waiting);
    send('aspect3d', { aspect: view.aspect() }); // where its viewer starts (the next scene's)
  })
  .catch((e) => {
    $('view3d').textContent = `3D view unavailable: ${e.message}`;
  });

startWorker();
updateButtons();
