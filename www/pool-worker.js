// A member of the coordinator's pool (worker.js starts these): a module Web Worker
// holding one wasm Shard — the session's mesh and views, built once from the same
// files as the session — that answers the coordinator's requests. Requests and
// responses are opaque plain objects (Session.request / splitRequest / respond).
// Messages in: init {module: the coordinator's compiled WebAssembly.Module (optional:
// without it the glue fetches and compiles the wasm), files: [{path, bytes}], views:
// [indices it owns]}, work {id, request}.
// Messages out: ready {views}, done {id, response}, error {id?, message}.
import init, { FileSet, Shard } from './pkg/localisebot.js';
import { holdLifeline } from './lifeline.js';

// Its end is watched by the coordinator through a lock it holds (lifeline.js).
holdLifeline();

let ready = null; // wasm instantiated, at the first init
let shard = null;

function build(files, views) {
  const set = new FileSet();
  try {
    for (const f of files) set.add(f.path, f.bytes);
    set.setMasksOnly(true); // the images are only shown, by the coordinator
    shard?.free();
    shard = Shard.fromFiles(set, Uint32Array.from(views));
  } finally {
    set.free();
  }
  return shard.viewCount;
}

onmessage = async ({ data }) => {
  try {
    if (data.type === 'init') ready ??= init(data.module ? { module_or_path: data.module } : undefined);
    if (!ready) throw new Error('pool worker: work before init');
    await ready;
    if (data.type === 'init') {
      const views = build(data.files, data.views);
      postMessage({ type: 'ready', views });
    } else if (data.type === 'work') {
      if (!shard) throw new Error('pool worker: work before init');
      postMessage({ type: 'done', id: data.id, response: shard.work(data.request) });
    }
  } catch (e) {
    postMessage({ type: 'error', id: data.id, message: e?.message ?? String(e) });
  }
};
