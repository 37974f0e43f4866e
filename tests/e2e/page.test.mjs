// End-to-end test of the web page (www/): playwright-core drives Debian's Chromium
// against scripts/serve.mjs on a free port. Needs www/pkg/ (scripts/build-wasm.sh) and
// www/examples/ with the command line (scripts/build-examples.sh; CLI_PROFILE as there), which also
// makes the test's other scenes (the toy as .gltf + .bin and as .ply) in target/e2e/.
//
//   node tests/e2e/page.test.mjs        # prints one line per test, then "N passed, N failed"
//
// Artifacts (screenshot of the converged page, the downloaded result) go to
// target/e2e/ (or $E2E_ARTIFACTS). Timings are printed, never asserted.
import { chromium } from 'playwright-core';
import { execFileSync, spawn } from 'node:child_process';
import { deflateSync } from 'node:zlib';
import { existsSync, mkdirSync, readFileSync, readdirSync, statSync } from 'node:fs';
import { dirname, join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';
import assert from 'node:assert/strict';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const artifacts = process.env.E2E_ARTIFACTS ?? join(root, 'target', 'e2e');
const CONVERGE_MS = 300_000; // generous: a limit for hangs, not a benchmark
mkdirSync(artifacts, { recursive: true });
if (!existsSync(join(root, 'www', 'pkg', 'localisebot_bg.wasm'))) {
  console.error('www/pkg/ is missing: run scripts/build-wasm.sh first');
  process.exit(1);
}
const examplesDir = join(root, 'www', 'examples');
// The command line build-examples.sh used: release, or the dev build with CLI_PROFILE=dev (test.sh).
const profile = process.env.CLI_PROFILE ?? 'release';
const cli = join(process.env.CARGO_TARGET_DIR ?? join(root, 'target'), profile === 'dev' ? 'debug' : profile, 'localisebot');
if (!existsSync(join(examplesDir, 'index.json')) || !existsSync(cli)) {
  console.error(`www/examples/ or ${cli} is missing: run scripts/build-examples.sh first`);
  process.exit(1);
}
const toyDir = join(examplesDir, 'toy');
const examples = JSON.parse(readFileSync(join(examplesDir, 'index.json'), 'utf8')).examples;

// A scene folder written by the command line (`localisebot synth ARGS --out DIR`).
function synthScene(name, args) {
  const out = join(artifacts, 'scenes', name);
  execFileSync(cli, ['synth', ...args, '--out', out], { stdio: ['ignore', 'ignore', 'inherit'] });
  return out;
}
const gltfScene = synthScene('toy-gltf', ['--shape', 'toy', '--mesh-format', 'gltf', '--views', '3', '--seed', '5',
  '--width', '240', '--height', '200']);
const plyScene = synthScene('toy-ply', ['--shape', 'toy', '--mesh-format', 'ply', '--views', '3', '--seed', '9']);

// An 8-bit grey PNG (zlib from Node), for masks made here.
function pngGray(width, height, pixel) {
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc = (buf) => {
    let c = 0xffffffff;
    for (const b of buf) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const chunk = (type, data) => {
    const body = Buffer.concat([Buffer.from(type, 'ascii'), data]);
    const out = Buffer.alloc(12 + data.length);
    out.writeUInt32BE(data.length, 0);
    body.copy(out, 4);
    out.writeUInt32BE(crc(body), 8 + data.length);
    return out;
  };
  const raw = Buffer.alloc((width + 1) * height);
  for (let y = 0; y < height; y++) for (let x = 0; x < width; x++) raw[y * (width + 1) + 1 + x] = pixel(x, y);
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0);
  ihdr.writeUInt32BE(height, 4);
  ihdr.set([8, 0, 0, 0, 0], 8);
  return Buffer.concat([Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]), chunk('IHDR', ihdr),
    chunk('IDAT', deflateSync(raw)), chunk('IEND', Buffer.alloc(0))]);
}

// An impossible scene: the glTF toy scene with every mask replaced by a thin ring (no
// solid object's silhouette covers a ring without its hole).
function ringFiles() {
  const scene = JSON.parse(readFileSync(join(gltfScene, 'scene.json'), 'utf8'));
  return folderFiles(gltfScene).map((f) => {
    const v = scene.views.find((v) => v.mask === f.rel.split('\\').join('/'));
    if (!v) return f;
    const { width: w, height: h } = v.camera;
    return { ...f, buffer: pngGray(w, h, (x, y) => (Math.abs(Math.hypot(x - w / 2, y - h / 2) - 40) < 3 ? 255 : 0)) };
  });
}

// ---- server and browser ----------------------------------------------------------
function startServer() {
  const proc = spawn(process.execPath, [join(root, 'scripts', 'serve.mjs'), '--port', '0'], {
    stdio: ['ignore', 'pipe', 'inherit'],
  });
  return new Promise((ok, fail) => {
    let out = '';
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/at (http:\/\/\S+)/);
      if (m) ok({ proc, url: m[1] });
    });
    proc.on('exit', (code) => fail(new Error(`server exited (${code}): ${out}`)));
  });
}

const server = await startServer();
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--disable-quic',
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
});

// The page, with `query` (e.g. '?pool=3': a pool of 3 Workers; '?pool=0': one Worker).
async function openPage(query = '') {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 }, acceptDownloads: true });
  const page = await context.newPage();
  page.problems = [];
  page.on('pageerror', (e) => page.problems.push(`page error: ${e.message}`));
  page.on('console', (m) => m.type() === 'error' && page.problems.push(`console error: ${m.text()}`));
  // Fetches of the wasm by the page and its Workers (a pool's Workers get the module compiled).
  page.wasmFetches = 0;
  context.on('request', (r) => r.url().endsWith('/localisebot_bg.wasm') && page.wasmFetches++);
  await page.goto(server.url + query);
  return page;
}

// How many pool Workers the page says compute the fit (0: the coordinator alone).
const workers = async (page) => Number(await byId(page, 'workers').getAttribute('data-pool'));

// The result the page downloads, parsed.
async function downloadResult(page, name) {
  const [download] = await Promise.all([page.waitForEvent('download'), byId(page, 'download').click()]);
  const saved = join(artifacts, name);
  await download.saveAs(saved);
  return JSON.parse(readFileSync(saved, 'utf8'));
}

const byId = (page, id) => page.getByTestId(id);
const status = (page) => byId(page, 'status').textContent();

// Waits for the start button to be usable (a scene is loaded), or fails with the page's error.
async function waitLoaded(page) {
  await page.waitForFunction(
    () => !document.querySelector('[data-testid=start]').disabled || !document.querySelector('[data-testid=error]').hidden,
    null,
    { timeout: 60_000 },
  );
  const error = byId(page, 'error');
  if (await error.isVisible()) throw new Error(`the page shows an error: ${await error.textContent()}`);
}

// Clicks Start and waits for the fit to end ("done — verdict …"); returns the timings seen from outside.
async function fitToConvergence(page) {
  await page.evaluate(() => {
    window.__frames = 0;
    const tick = () => {
      window.__frames++;
      requestAnimationFrame(tick);
    };
    requestAnimationFrame(tick);
  });
  const paints0 = Number((await byId(page, 'status').getAttribute('data-paints')) ?? 0);
  const t0 = Date.now();
  await byId(page, 'start').click();
  await page.waitForFunction(
    () => document.querySelector('[data-testid=status]').textContent.startsWith('done') ||
      !document.querySelector('[data-testid=error]').hidden,
    null,
    { timeout: CONVERGE_MS, polling: 20 },
  );
  const wall = (Date.now() - t0) / 1000;
  const error = byId(page, 'error');
  if (await error.isVisible()) throw new Error(`the page shows an error: ${await error.textContent()}`);
  const paints = Number(await byId(page, 'status').getAttribute('data-paints')) - paints0;
  const frames = await page.evaluate(() => window.__frames);
  const text = await status(page);
  return { wall, paintsPerSecond: paints / wall, framesPerSecond: frames / wall, status: text };
}

async function ious(page) {
  return (await byId(page, 'view-iou').allTextContents()).map((t) => {
    assert.match(t, /^\d\.\d{3}$/, `view-iou text '${t}' is not an IoU with 3 decimals`);
    return Number(t);
  });
}

// Per 2D canvas (the views' and the loss curve's; the 3D view's is WebGL, see
// view3d.test.mjs): how many pixels differ from its first pixel, and how many are in
// the overlay's contour colours.
function canvasStats(page) {
  return page.evaluate(() =>
    [...document.querySelectorAll('.view canvas, #loss')].map((c) => {
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let varied = 0, magenta = 0, green = 0, ink = 0;
      for (let i = 0; i < d.length; i += 4) {
        if (d[i] !== d[0] || d[i + 1] !== d[1] || d[i + 2] !== d[2] || d[i + 3] !== d[3]) varied++;
        if (d[i] === 255 && d[i + 1] === 0 && d[i + 2] === 255) magenta++;
        if (d[i] === 0 && d[i + 1] === 255 && d[i + 2] === 0) green++;
        if (d[i + 3] > 0) ink++;
      }
      return { id: c.id, pixels: d.length / 4, varied, magenta, green, ink };
    }),
  );
}

// Files for setInputFiles from a folder: bare names (as a file chooser gives them).
function folderFiles(dir) {
  const out = [];
  const walk = (d) => {
    for (const name of readdirSync(d)) {
      const p = join(d, name);
      if (statSync(p).isDirectory()) walk(p);
      else out.push({ name, mimeType: 'application/octet-stream', buffer: readFileSync(p), rel: relative(dir, p) });
    }
  };
  walk(dir);
  return out;
}
const upload = (page, files) => byId(page, 'file-input').setInputFiles(files.map(({ name, mimeType, buffer }) => ({ name, mimeType, buffer })));

// ---- tests ---------------------------------------------------------------------------
const tests = [];
const test = (name, fn) => tests.push({ name, fn });

// Files dropped on the page with a synthetic drop event (bare names, as dt.files).
async function drop(page, files) {
  const dt = await page.evaluateHandle((list) => {
    const dt = new DataTransfer();
    for (const f of list) dt.items.add(new File([Uint8Array.from(atob(f.b64), (c) => c.charCodeAt(0))], f.name));
    return dt;
  }, files.map((f) => ({ name: f.name, b64: f.buffer.toString('base64') })));
  await page.dispatchEvent('#drop', 'drop', { dataTransfer: dt });
}

test('examples: the chooser lists examples/index.json, the toy first; Load, Start, verdict ok, IoU >= 0.95, result downloads; same pose and iterations as the CLI', async () => {
  const page = await openPage();
  const choice = byId(page, 'example-choice');
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  const options = await choice.locator('option').evaluateAll((os) => os.map((o) => ({ path: o.value, title: o.text })));
  assert.deepEqual(options, examples.map(({ path, title }) => ({ path, title })));
  assert.equal(await choice.inputValue(), 'toy/scene.json', 'the toy is the default');
  // The Duck is built from ../shared when it is there, and only then.
  const sharedDuck = existsSync(join(root, '..', 'shared', 'data', 'gltf', 'Duck', 'glTF-Binary', 'Duck.glb'));
  assert.equal(examples.some((e) => e.id === 'duck'), sharedDuck, 'examples/index.json lists the duck iff ../shared has it');
  await byId(page, 'load-example').click();
  await waitLoaded(page);
  assert.equal(await byId(page, 'view-iou').count(), 4);
  const t = await fitToConvergence(page);
  const values = await ious(page);
  assert.equal(values.length, 4);
  for (const v of values) assert.ok(v >= 0.95, `view IoU ${v} < 0.95 (all: ${values})`);
  const verdict = byId(page, 'verdict');
  assert.ok(await verdict.isVisible(), 'the verdict is shown');
  assert.equal(await verdict.getAttribute('data-verdict'), 'ok', await verdict.textContent());
  assert.match(t.status, /^done — verdict ok/);
  // Each view shows its object window (256 px square) by default; the toggle shows the whole image.
  const sizes = () => page.evaluate(() => [...document.querySelectorAll('.view canvas')].map((c) => [c.width, c.height]));
  for (const [w, h] of await sizes()) assert.ok(w === 256 && h === 256, `window canvas ${w}×${h}`);
  const scene = JSON.parse(readFileSync(join(toyDir, 'scene.json'), 'utf8'));
  await byId(page, 'full-frame').check();
  await page.waitForFunction((w) => [...document.querySelectorAll('.view canvas')].every((c) => c.width === w), scene.views[0].camera.width);
  await byId(page, 'full-frame').uncheck();
  await page.waitForFunction(() => [...document.querySelectorAll('.view canvas')].every((c) => c.width === 256));
  const shot = join(artifacts, 'converged.png');
  await page.screenshot({ path: shot, fullPage: true });
  assert.ok(statSync(shot).size > 20_000, 'the screenshot is suspiciously small');
  const stats = await canvasStats(page);
  const viewCanvases = stats.filter((s) => s.id !== 'loss');
  assert.equal(viewCanvases.length, 4);
  for (const s of viewCanvases) {
    assert.ok(s.varied > s.pixels * 0.05, `a view canvas is (nearly) uniform: ${JSON.stringify(s)}`);
    assert.ok(s.magenta > 50, `no rendered contour drawn: ${JSON.stringify(s)}`);
  }
  const loss = stats.find((s) => s.id === 'loss');
  assert.ok(loss.ink > 100, `the loss curve is blank: ${JSON.stringify(loss)}`);
  const pose = await page.locator('#pose-q').textContent();
  assert.equal(pose.trim().split(/\s+/).length, 4, `quaternion not shown: '${pose}'`);

  const [download] = await Promise.all([page.waitForEvent('download'), byId(page, 'download').click()]);
  const saved = join(artifacts, 'result.json');
  await download.saveAs(saved);
  const result = JSON.parse(readFileSync(saved, 'utf8'));
  assert.equal(result.views.length, 4);
  assert.ok(result.mean_iou >= 0.95, `result mean IoU ${result.mean_iou}`);
  assert.equal(result.pose.quaternion.length, 4);
  assert.equal(result.matrix.length, 4);
  assert.ok(result.errors && result.errors.rotation_deg < 5, `rotation error ${result.errors?.rotation_deg}°`);
  assert.equal(result.verdict, 'ok');
  // One default for every front end: the command line fits the same example to the same
  // pose in the same number of iterations.
  const nativePath = join(artifacts, 'toy-native.json');
  execFileSync(cli, ['fit', join(toyDir, 'scene.json'), '--out', nativePath], { stdio: ['ignore', 'ignore', 'inherit'] });
  const native = JSON.parse(readFileSync(nativePath, 'utf8'));
  assert.equal(result.iterations, native.iterations, 'the page and the CLI do the same number of iterations');
  for (const k of ['translation', 'scale', 'quaternion']) {
    result.pose[k].forEach((v, i) => assert.ok(Math.abs(v - native.pose[k][i]) < 1e-6, `pose.${k}: page ${result.pose[k]} vs CLI ${native.pose[k]}`));
  }
  assert.ok(Math.abs(result.errors.rotation_deg - native.errors.rotation_deg) < 1e-3, 'the same error figures');
  assert.deepEqual(page.problems, []);
  console.log(`  status: ${t.status}`);
  console.log(`  benchmark: converged from no initial pose in ${t.wall.toFixed(2)} s wall (target < 3 s)`);
  console.log(`  benchmark: ${t.paintsPerSecond.toFixed(1)} canvas repaints/s while fitting (target >= 10), ` +
    `${t.framesPerSecond.toFixed(1)} animation frames/s on the page`);
  console.log(`  screenshot: ${relative(root, shot)}, result: ${relative(root, saved)}`);
  await page.context().close();
});

test('examples: every other listed example loads with the views its scene.json names', async () => {
  const page = await openPage();
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  const others = examples.filter((e) => e.id !== 'toy');
  if (others.length === 0) console.log('  only the toy was built (no ../shared beside the repository): nothing more to load');
  for (const e of others) {
    const scene = JSON.parse(readFileSync(join(examplesDir, e.path), 'utf8'));
    await byId(page, 'example-choice').selectOption(e.path);
    await byId(page, 'load-example').click();
    await page.waitForFunction((names) => [...document.querySelectorAll('.view .name')].map((n) => n.textContent).join() === names,
      scene.views.map((v) => v.name).join(), { timeout: 60_000 });
    await waitLoaded(page);
    if (scene.views.some((v) => !v.mask)) {
      // Photographs without masks: a step means loading the segmenter and segmenting
      // first; tests/e2e/photos.test.mjs drives that path. Here: loaded, boxes shown.
      await page.waitForFunction((n) => document.querySelectorAll('.view[data-shown]').length === n, scene.views.length);
      console.log(`  ${e.id}: ${scene.views.length} views from photographs loaded, their boxes shown`);
      continue;
    }
    await byId(page, 'step').click();
    await page.waitForFunction(() => /search: [1-9]/.test(document.querySelector('[data-testid=status]').textContent));
    console.log(`  ${e.id}: ${scene.views.length} views loaded and stepped`);
  }
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('real photographs: the Linemod-Occluded example fits to verdict ok, its object windows shown over the photographs', async () => {
  const sharedLmo = existsSync(join(root, '..', 'shared', 'data', 'real', 'lmo', 'test', '000002', 'scene_gt.json'));
  const lmo = examples.find((e) => e.id === 'lmo-duck');
  assert.equal(Boolean(lmo), sharedLmo, 'examples/index.json lists the real scene iff ../shared has it');
  if (!lmo) {
    console.log('  ../shared/data/real/lmo is not beside the repository: no real example was built');
    return;
  }
  const page = await openPage();
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  await byId(page, 'example-choice').selectOption(lmo.path);
  await byId(page, 'load-example').click();
  await page.waitForFunction(() => document.querySelectorAll('.view').length === 3, null, { timeout: 60_000 });
  await waitLoaded(page);
  const t = await fitToConvergence(page);
  assert.match(t.status, /^done — verdict ok/, t.status);
  for (const v of await ious(page)) assert.ok(v >= 0.9, `view IoU ${v} < 0.9`);
  // The object fills the window: the photograph's window with both contours on it.
  const stats = (await canvasStats(page)).filter((s) => s.id !== 'loss');
  for (const s of stats) {
    assert.equal(s.pixels, 256 * 256);
    assert.ok(s.magenta > 200 && s.varied > s.pixels * 0.5, `window overlay: ${JSON.stringify(s)}`);
  }
  const shot = join(artifacts, 'real.png');
  await page.screenshot({ path: shot, fullPage: true });
  assert.deepEqual(page.problems, []);
  console.log(`  status: ${t.status} (${t.wall.toFixed(2)} s wall); screenshot: ${relative(root, shot)}`);
  await page.context().close();
});

test('file input: a .gltf + .bin scene (flat file names) converges', async () => {
  const page = await openPage();
  await upload(page, folderFiles(gltfScene));
  await waitLoaded(page);
  assert.equal(await byId(page, 'view-iou').count(), 3);
  const t = await fitToConvergence(page);
  for (const v of await ious(page)) assert.ok(v >= 0.95, `view IoU ${v} < 0.95`);
  assert.deepEqual(page.problems, []);
  console.log(`  status: ${t.status} (${t.wall.toFixed(2)} s wall)`);
  await page.context().close();
});

test('file input: per-view camera JSON, masks and images of the same names; Step, Pause, Reset', async () => {
  const page = await openPage();
  const scene = JSON.parse(readFileSync(join(toyDir, 'scene.json'), 'utf8'));
  const files = [{ name: scene.mesh, mimeType: 'model/gltf-binary', buffer: readFileSync(join(toyDir, scene.mesh)) }];
  for (const v of scene.views) {
    files.push({ name: `${v.name}.json`, mimeType: 'application/json', buffer: Buffer.from(JSON.stringify(v.camera)) });
    // A mask and an image both called NAME.png: told apart by their content.
    files.push({ name: `${v.name}.png`, mimeType: 'image/png', buffer: readFileSync(join(toyDir, v.image)) });
    files.push({ name: `${v.name}.png`, mimeType: 'image/png', buffer: readFileSync(join(toyDir, v.mask)) });
  }
  await upload(page, files);
  await waitLoaded(page);
  assert.deepEqual(await page.locator('.view .name').allTextContents(), scene.views.map((v) => v.name));
  await byId(page, 'step').click();
  await page.waitForFunction(() => /search: [1-9]/.test(document.querySelector('[data-testid=status]').textContent));
  await byId(page, 'start').click();
  await page.waitForTimeout(300);
  await byId(page, 'pause').click();
  await page.waitForFunction(() => document.querySelector('[data-testid=status]').textContent.startsWith('paused'));
  await byId(page, 'reset').click();
  await page.waitForFunction(() => document.querySelector('[data-testid=status]').textContent.startsWith('ready'));
  const stats = await canvasStats(page);
  for (const s of stats.filter((s) => s.id !== 'loss')) {
    assert.ok(s.varied > s.pixels * 0.05, 'the image is shown, not only the mask');
    assert.ok(s.green > 50, 'the mask outline is drawn');
  }
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('drop: files dropped on the page, masks but no images, load with a notice', async () => {
  const page = await openPage();
  await drop(page, folderFiles(toyDir).filter((f) => !f.rel.startsWith('images')));
  await waitLoaded(page);
  assert.equal(await byId(page, 'view-iou').count(), 4);
  const notice = page.locator('#notice');
  assert.ok(await notice.isVisible());
  assert.match(await notice.textContent(), /view 'view0': image 'images\/view0\.png' not given/);
  assert.ok(await byId(page, 'error').isHidden());
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('drop: a .ply mesh with its scene and masks loads and steps', async () => {
  const page = await openPage();
  const files = folderFiles(plyScene);
  assert.ok(files.some((f) => f.name === 'toy.ply'), 'the scene has a .ply mesh');
  await drop(page, files);
  await waitLoaded(page);
  assert.equal(await byId(page, 'view-iou').count(), 3);
  await byId(page, 'step').click();
  await page.waitForFunction(() => /search: [1-9]/.test(document.querySelector('[data-testid=status]').textContent));
  assert.ok(await byId(page, 'error').isHidden());
  assert.equal(await byId(page, 'file-input').getAttribute('accept').then((a) => a.split(',').includes('.ply')), true);
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('errors: a malformed .glb, alone or named by a scene, shows a specific error', async () => {
  const page = await openPage();
  const broken = { name: 'broken.glb', mimeType: 'model/gltf-binary', buffer: Buffer.from('glTF\x02\x00\x00\x00\x10\x00\x00\x00garbage!') };
  await upload(page, [broken]);
  const error = byId(page, 'error');
  await error.waitFor({ state: 'visible' });
  assert.match(await error.textContent(), /broken\.glb/);

  const files = folderFiles(toyDir).filter((f) => !f.name.endsWith('.glb'));
  const scene = JSON.parse(readFileSync(join(toyDir, 'scene.json'), 'utf8'));
  await upload(page, [...files, { ...broken, name: scene.mesh }]);
  await page.waitForFunction((name) => document.querySelector('[data-testid=error]').textContent.includes(name), scene.mesh);
  assert.match(await error.textContent(), /mesh/);
  assert.ok(await error.isVisible());
  assert.ok(await byId(page, 'start').isDisabled(), 'nothing to start after a failed load');

  // A mask of the wrong size names the view and the file.
  const small = folderFiles(gltfScene).find((f) => f.rel.startsWith('masks'));
  await upload(page, [...files.filter((f) => f.rel !== join('masks', 'view1.png')), { ...small, name: 'view1.png' }, folderFiles(toyDir).find((f) => f.name.endsWith('.glb'))]);
  await page.waitForFunction(() => document.querySelector('[data-testid=error]').textContent.includes('view1'));
  assert.match(await error.textContent(), /view 'view1': mask .* is 240×200 but the camera is 256×256/);

  // A good scene afterwards clears the error.
  await byId(page, 'load-example').click();
  await waitLoaded(page);
  assert.ok(await error.isHidden());
  await page.context().close();
});

test('verdict: an impossible scene (ring masks) ends with verdict failed, shown on the page, never "converged"', async () => {
  const page = await openPage();
  await upload(page, ringFiles());
  await waitLoaded(page);
  const t = await fitToConvergence(page);
  assert.match(t.status, /^done — verdict failed/, t.status);
  assert.ok(!t.status.includes('converged'), t.status);
  const verdict = byId(page, 'verdict');
  assert.equal(await verdict.getAttribute('data-verdict'), 'failed');
  assert.match(await verdict.textContent(), /failed/);
  assert.deepEqual(page.problems, []);
  console.log(`  status: ${t.status}`);
  await page.context().close();
});

test('refine cameras: the switch makes the fit correct every view\'s camera; the corrections are shown and in the result', async () => {
  const page = await openPage();
  await byId(page, 'refine-cameras').check();
  await byId(page, 'load-example').click();
  await waitLoaded(page);
  const t = await fitToConvergence(page);
  assert.match(t.status, /^done — verdict ok/, t.status);
  const shown = byId(page, 'camera-corrections');
  await page.waitForFunction(() => !document.querySelector('[data-testid=camera-corrections]').hidden, null, { timeout: 10_000 });
  const text = await shown.textContent();
  assert.match(text, /^Camera corrections — /, text);
  assert.equal(text.split(' · ').length, 4, text);
  const [download] = await Promise.all([page.waitForEvent('download'), byId(page, 'download').click()]);
  const result = JSON.parse(readFileSync(await download.path(), 'utf8'));
  assert.equal(result.camera_corrections.length, 4);
  // The example's cameras are exact: the corrections explain little of the loss and the
  // page says whether they were applied, as the result does.
  const test = result.camera_test;
  assert.ok(test.loss_reduction >= 0 && test.loss_reduction < 1, JSON.stringify(test));
  assert.equal(test.applied, test.loss_reduction >= test.min_reduction);
  assert.equal(await shown.getAttribute('data-applied'), String(test.applied));
  assert.match(text, test.applied ? /: applied\)$/ : /: not applied, below 15 %\)$/, text);
  for (const c of result.camera_corrections) {
    // The toy's cameras are exact: the corrections stay well inside the 1° / 1 % prior.
    assert.ok(c.angle_deg < 1 && c.shift_pct < 1, JSON.stringify(c));
    assert.equal(c.world_to_camera.length, 4);
  }
  assert.equal(result.covariance.length, 9);
  assert.ok(result.std_dev.add_95 > 0);
  assert.deepEqual(page.problems, []);
  console.log(`  ${text}`);
  await page.context().close();
});

test('errors: an error thrown inside a fitting slice is shown, and Start works again', async () => {
  const page = await openPage('?pool=0'); // one Worker: the Session steps with stepFor
  // The real glue, with Session.stepFor wrapped to throw on its 4th call (once): the
  // worker's own catch path must report it.
  let served = 0;
  await page.context().route('**/pkg/localisebot.js', async (route) => {
    const response = await route.fetch();
    served++;
    const body = (await response.text()) + `
const __stepFor = Session.prototype.stepFor;
let __calls = 0;
Session.prototype.stepFor = function (...args) {
  if (++__calls === 4) throw new Error('injected failure in fitting slice ' + __calls);
  return __stepFor.apply(this, args);
};
`;
    await route.fulfill({ response, body });
  });
  await page.reload();
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  await byId(page, 'load-example').click();
  await waitLoaded(page);
  assert.ok(served >= 1, 'the glue was served through the route');
  await byId(page, 'start').click();
  const error = byId(page, 'error');
  await error.waitFor({ state: 'visible', timeout: 60_000 });
  assert.equal(await error.textContent(), 'injected failure in fitting slice 4');
  await page.waitForFunction(() => !document.querySelector('[data-testid=start]').disabled);
  assert.ok(await byId(page, 'pause').isDisabled(), 'no longer running');
  assert.ok(await byId(page, 'step').isEnabled() && await byId(page, 'reset').isEnabled());
  // The worker is alive and the fit goes on from where it stopped.
  const t = await fitToConvergence(page);
  for (const v of await ious(page)) assert.ok(v >= 0.95, `view IoU ${v} < 0.95`);
  assert.ok(await error.isHidden());
  assert.deepEqual(page.problems, []);
  console.log(`  after the error: ${t.status}`);
  await page.context().close();
});

// The toy example fitted in one Worker (stepFor), for the pool tests to compare with.
let single = null;

test('pool: 2 and 3 Workers give the single Worker\'s fit bit for bit (pose, iterations, loss trace), also after Reset; timings printed', async () => {
  const fits = [];
  for (const n of [0, 2, 3]) {
    const page = await openPage(`?pool=${n}`);
    await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
    await byId(page, 'load-example').click();
    await waitLoaded(page);
    assert.equal(await workers(page), n, `?pool=${n}: the page reports its workers`);
    assert.equal(await byId(page, 'workers').textContent(), n ? `pool of ${n} workers` : '1 worker');
    const who = n === 0 ? 'one worker' : `pool of ${n} workers`;
    // Twice: in fresh Workers (their wasm still being tiered up), then after Reset (which
    // keeps the pool: the shards serve the fit from the start again).
    for (const run of ['fresh', 'after Reset']) {
      if (run !== 'fresh') {
        await byId(page, 'reset').click();
        await page.waitForFunction(() => document.querySelector('[data-testid=status]').textContent.startsWith('ready'));
      }
      const t = await fitToConvergence(page);
      assert.match(t.status, /^done — verdict ok/, t.status);
      assert.equal(await workers(page), n, 'the pool stayed up');
      const result = await downloadResult(page, `result-pool${n}${run === 'fresh' ? '' : '-reset'}.json`);
      fits.push({ n, label: `${who}, ${run}`, t, result });
    }
    assert.deepEqual(page.problems, []);
    assert.equal(page.wasmFetches, 1, 'the wasm is fetched once: the pool Workers get the compiled module');
    await page.context().close();
  }
  single = fits[0].result;
  for (const { label, result } of fits.slice(1)) {
    assert.deepEqual(result.pose, single.pose, `${label}: the same pose, bit for bit`);
    assert.deepEqual(result.matrix, single.matrix, `${label}: the same matrix`);
    assert.equal(result.iterations, single.iterations, `${label}: the same iterations`);
    assert.deepEqual(result.loss_history, single.loss_history, `${label}: the same loss trace`);
    assert.deepEqual(result.views, single.views, `${label}: the same per-view figures`);
  }
  for (const { label, t, result } of fits) {
    console.log(`  benchmark: ${label.padEnd(32)}: converged in ${t.wall.toFixed(2)} s wall, ` +
      `${result.seconds.toFixed(2)} s fitting, ${result.iterations} iterations, ${t.paintsPerSecond.toFixed(1)} repaints/s`);
  }
});

// The real glue with Shard.prototype.work wrapped to throw (in every pool Worker, on its
// calls number `at`).
async function routeGlue(page, at) {
  await page.context().route('**/pkg/localisebot.js', async (route) => {
    const response = await route.fetch();
    const body = (await response.text()) + `
const __work = Shard.prototype.work;
let __calls = 0;
Shard.prototype.work = function (...args) {
  if (++__calls === ${at}) throw new Error('injected failure in a shard');
  return __work.apply(this, args);
};
`;
    await route.fulfill({ response, body });
  });
}

test('pool errors: a shard that throws mid-fit shows the error, stops the pool; Start finishes the same fit in one worker', async () => {
  const page = await openPage('?pool=2');
  await routeGlue(page, 40);
  await page.reload();
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  await byId(page, 'load-example').click();
  await waitLoaded(page);
  assert.equal(await workers(page), 2);
  await byId(page, 'start').click();
  const error = byId(page, 'error');
  await error.waitFor({ state: 'visible', timeout: 60_000 });
  const message = await error.textContent();
  assert.match(message, /injected failure in a shard/);
  assert.match(message, /the worker pool was stopped: the fit goes on in one worker/);
  await page.waitForFunction(() => !document.querySelector('[data-testid=start]').disabled);
  assert.ok(await byId(page, 'pause').isDisabled(), 'no longer running');
  const t = await fitToConvergence(page);
  assert.equal(await workers(page), 0, 'the fit went on without the pool');
  assert.match(t.status, /^done — verdict ok/, t.status);
  const result = await downloadResult(page, 'result-pool-error.json');
  if (single) {
    // The failed step was never taken: the fit is the one a single worker makes.
    assert.deepEqual(result.pose, single.pose);
    assert.equal(result.iterations, single.iterations);
  }
  assert.deepEqual(page.problems, []);
  console.log(`  after the pool error: ${t.status}`);
  await page.context().close();
});

// The real glue, made to fail in pool Workers only (self.location is the Worker's
// script): `where` 'load' throws when pool-worker.js imports it (the Worker fails to
// start: its error event), 'shard' when it builds its Shard (an error message back).
// Playwright does not intercept a nested Worker's own script, so its import is the hook.
async function breakPoolWorkers(page, where) {
  await page.context().route('**/pkg/localisebot.js', async (route) => {
    const response = await route.fetch();
    const inPool = "/pool-worker\\.js$/.test(self.location.pathname)";
    const body = where === 'load'
      ? `if (${inPool}) throw new Error('no pool here');\n${await response.text()}`
      : `${await response.text()}
if (${inPool}) Shard.fromFiles = () => { throw new Error('no shard here'); };
`;
    await route.fulfill({ response, body });
  });
}

test('pool errors: a pool that cannot start (a Worker fails to load, or its Shard to build) leaves the fit to one worker, with a notice', async () => {
  for (const [where, why] of [['load', /pool worker \d failed to start: .*no pool here/], ['shard', /no shard here/]]) {
    const page = await openPage('?pool=3');
    await breakPoolWorkers(page, where);
    await page.reload();
    await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
    await byId(page, 'load-example').click();
    await waitLoaded(page);
    assert.equal(await workers(page), 0, where);
    assert.equal(await byId(page, 'workers').textContent(), '1 worker');
    const notice = page.locator('#notice');
    assert.ok(await notice.isVisible(), where);
    const text = await notice.textContent();
    assert.match(text, /no worker pool \(.*\): the fit runs in one worker/);
    assert.match(text, why);
    assert.ok(await byId(page, 'error').isHidden(), where);
    await byId(page, 'step').click();
    await page.waitForFunction(() => /search: [1-9]/.test(document.querySelector('[data-testid=status]').textContent));
    const t = await fitToConvergence(page);
    assert.match(t.status, /^done — verdict ok/, t.status);
    console.log(`  ${where}: notice: ${text}`);
    await page.context().close();
  }
});

// ---- run ---------------------------------------------------------------------------------
let passed = 0;
let failed = 0;
// E2E_ONLY=TEXT runs only the tests whose name contains TEXT (when debugging one).
const only = process.env.E2E_ONLY;
const chosen = only ? tests.filter((t) => t.name.includes(only)) : tests;
if (only) console.log(`E2E_ONLY=${only}: ${chosen.length} of ${tests.length} tests`);
for (const { name, fn } of chosen) {
  const t0 = Date.now();
  try {
    await fn();
    passed++;
    console.log(`ok - ${name} (${((Date.now() - t0) / 1000).toFixed(1)} s)`);
  } catch (e) {
    failed++;
    console.log(`FAIL - ${name}\n  ${e.stack ?? e}`);
  }
}
await browser.close();
server.proc.kill();
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
