// End-to-end test of the page's 3D view (www/view3d.js, three.js from www/vendor/):
// playwright-core drives Debian's Chromium (WebGL 2 through ANGLE on SwiftShader, the
// CPU renderer, even with --disable-gpu) against scripts/serve.mjs on a free port.
// Needs www/pkg/ (scripts/build-wasm.sh), www/examples/ (scripts/build-examples.sh)
// and www/vendor/ (scripts/build-vendor.sh).
//
//   node tests/e2e/view3d.test.mjs      # one line per test, then "N passed, N failed"
//
// The canvas is read back (preserveDrawingBuffer) and its pixels counted; the view's
// state is read through its API (document.getElementById('view3d').view3d.info()).
// What the view draws is computed in Rust (frames, ghosts, matrices): these tests check
// that the page draws it where it says.
import { chromium } from 'playwright-core';
import { spawn } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import assert from 'node:assert/strict';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
const artifacts = process.env.E2E_ARTIFACTS ?? join(root, 'target', 'e2e');
const CONVERGE_MS = 300_000;
mkdirSync(artifacts, { recursive: true });
for (const [file, how] of [
  ['www/pkg/localisebot_bg.wasm', 'scripts/build-wasm.sh'],
  ['www/examples/index.json', 'scripts/build-examples.sh'],
  ['www/vendor/three/three.module.js', 'scripts/build-vendor.sh'],
]) {
  if (!existsSync(join(root, file))) {
    console.error(`${file} is missing: run ${how} first`);
    process.exit(1);
  }
}
const toyDir = join(root, 'www', 'examples', 'toy');
const toyScene = JSON.parse(readFileSync(join(toyDir, 'scene.json'), 'utf8'));
const BACKGROUND = [0x1d, 0x21, 0x27]; // view3d.js BACKGROUND
const glueHasSuggest = readFileSync(join(root, 'www', 'pkg', 'localisebot.js'), 'utf8').includes('suggestViews(');

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
// The page test's flags: with --disable-gpu Chromium still gives WebGL 2 on SwiftShader.
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--disable-quic',
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
});

async function openPage({ init, route } = {}) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 }, acceptDownloads: true });
  if (init) await context.addInitScript(init);
  if (route) await context.route(route.pattern, route.handler);
  const page = await context.newPage();
  page.problems = [];
  page.on('pageerror', (e) => page.problems.push(`page error: ${e.message}`));
  page.on('console', (m) => m.type() === 'error' && page.problems.push(`console error: ${m.text()}`));
  await page.goto(server.url);
  return page;
}

const byId = (page, id) => page.getByTestId(id);
const info = (page) => page.evaluate(() => document.getElementById('view3d').view3d?.info() ?? null);
// Runs fn(view3d, arg) in the page.
const call = (page, fn, arg) => page.evaluate(([src, a]) => new Function('v', 'a', `return (${src})(v, a)`)(document.getElementById('view3d').view3d, a), [fn.toString(), arg]);

async function loadToy(page) {
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  await byId(page, 'load-example').click();
  await page.waitForFunction(
    () => !document.querySelector('[data-testid=start]').disabled || !document.querySelector('[data-testid=error]').hidden,
    null, { timeout: 60_000 });
  const error = byId(page, 'error');
  if (await error.isVisible()) throw new Error(`the page shows an error: ${await error.textContent()}`);
}

async function fit(page) {
  await byId(page, 'start').click();
  await page.waitForFunction(
    () => document.querySelector('[data-testid=status]').textContent.startsWith('done') ||
      !document.querySelector('[data-testid=error]').hidden,
    null, { timeout: CONVERGE_MS, polling: 20 });
  const error = byId(page, 'error');
  if (await error.isVisible()) throw new Error(`the page shows an error: ${await error.textContent()}`);
}

// Waits until the view has rendered at least twice more (a change is drawn on the next frame).
async function rendered(page) {
  const f = (await info(page)).frames;
  await call(page, (v) => v.requestRender());
  await page.waitForFunction((f0) => document.getElementById('view3d').view3d.info().frames >= f0 + 1, f);
  await page.evaluate(() => new Promise((ok) => requestAnimationFrame(() => requestAnimationFrame(ok))));
}

// The 3D canvas read back: its size, pixels away from the background, strongly orange
// pixels (the suggestion), a checksum, and optionally a mask of non-background pixels.
function glPixels(page, withMask = false) {
  return page.evaluate(([bg, withMask]) => {
    const c = document.querySelector('[data-testid=view3d-canvas]');
    const t = Object.assign(document.createElement('canvas'), { width: c.width, height: c.height });
    const ctx = t.getContext('2d');
    ctx.drawImage(c, 0, 0);
    const d = ctx.getImageData(0, 0, t.width, t.height).data;
    let ink = 0, orange = 0, sum = 0;
    const mask = withMask ? new Array(t.width * t.height) : null;
    for (let i = 0, p = 0; i < d.length; i += 4, p++) {
      const away = Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]);
      if (away > 30) ink++;
      if (mask) mask[p] = away > 30 ? 1 : 0;
      if (d[i] > 200 && d[i + 1] > 70 && d[i + 1] < 170 && d[i + 2] < 80) orange++;
      sum = (sum * 31 + d[i] + 7 * d[i + 1] + 13 * d[i + 2]) % 1000000007;
    }
    return { width: t.width, height: t.height, pixels: d.length / 4, ink, orange, sum, mask };
  }, [BACKGROUND, withMask]);
}

const maxDiff = (a, b) => Math.max(...a.flat().map((x, i) => Math.abs(x - b.flat()[i])));

// A camera on the far side of the object from view0, looking at it (OpenCV axes).
function oppositeCamera(scene, pose) {
  const w2c = scene.views[0].camera.world_to_camera;
  const R = w2c.slice(0, 3).map((r) => r.slice(0, 3));
  const t = w2c.slice(0, 3).map((r) => r[3]);
  const centre = [0, 1, 2].map((i) => -(R[0][i] * t[0] + R[1][i] * t[1] + R[2][i] * t[2]));
  const o = pose.translation;
  const eye = o.map((x, i) => 2 * x - centre[i]);
  const unit = (v) => v.map((x) => x / Math.hypot(...v));
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const z = unit(o.map((x, i) => x - eye[i]));
  const down = R[1]; // view0's y axis in the world
  const dz = down.reduce((s, x, i) => s + x * z[i], 0);
  const y = unit(down.map((x, i) => x - dz * z[i]));
  const x = cross(y, z);
  const rows = [x, y, z];
  const tt = rows.map((r) => -r.reduce((s, v, i) => s + v * eye[i], 0));
  const cam = scene.views[0].camera;
  return { name: 'opposite', width: cam.width, height: cam.height, fx: cam.fx, fy: cam.fy, cx: cam.cx, cy: cam.cy,
    world_to_camera: [[...x, tt[0]], [...y, tt[1]], [...z, tt[2]], [0, 0, 0, 1]] };
}

// ---- tests ---------------------------------------------------------------------------
const tests = [];
const test = (name, fn) => tests.push({ name, fn });

// One fitted page for the tests that need a finished fit (the fit takes seconds).
let fitted = null;
async function fittedPage() {
  if (fitted) return fitted;
  const page = await openPage();
  await loadToy(page);
  await page.waitForFunction(() => document.getElementById('view3d').view3d?.info().objectVisible);
  // Every pose the view is given, as the object's matrix it then draws.
  await call(page, (v) => {
    const setPose = v.setPose.bind(v);
    window.__matrices = [];
    v.setPose = (p) => {
      setPose(p);
      window.__matrices.push(v.info().objectMatrix);
    };
  });
  const t0 = Date.now();
  await fit(page);
  const wall = (Date.now() - t0) / 1000;
  const [download] = await Promise.all([page.waitForEvent('download'), byId(page, 'download').click()]);
  const saved = join(artifacts, 'view3d-result.json');
  await download.saveAs(saved);
  const result = JSON.parse(readFileSync(saved, 'utf8'));
  const matrices = await page.evaluate(() => window.__matrices);
  fitted = { page, result, matrices, wall };
  return fitted;
}

test('scene: after loading, the 3D canvas is drawn; one frustum with its picture per view; the mesh as loaded', async () => {
  const page = await openPage();
  await loadToy(page);
  await page.waitForFunction(() => document.getElementById('view3d').view3d?.info().objectVisible);
  await rendered(page);
  const s = await info(page);
  assert.equal(s.webgl, true, `no WebGL: ${s.note}`);
  assert.equal(s.note, null);
  assert.equal(s.cameras, toyScene.views.length, 'one frustum per view');
  assert.equal(s.pictures, toyScene.views.length, 'every view has its picture on its image plane');
  assert.ok(s.triangles > 1000, `the toy's mesh: ${s.triangles} triangles`);
  const px = await glPixels(page);
  assert.ok(px.width > 100 && px.height > 100, `canvas ${px.width}×${px.height}`);
  await page.screenshot({ path: join(artifacts, "view3d-loaded.png"), clip: await byId(page, "view3d").boundingBox() });
  assert.ok(px.ink > 0.01 * px.pixels, `the 3D canvas is (nearly) blank: ${px.ink} of ${px.pixels} pixels drawn`);
  assert.equal(px.orange, 0, 'no suggestion yet');
  // Where the viewer starts and looks: Rust's (Session.cameraFrames), the views' axes meeting.
  const frames = await call(page, (v) => v.sceneFrames);
  assert.equal(frames.frames.length, toyScene.views.length);
  assert.ok(Array.isArray(frames.meet), 'the toy views\' axes meet');
  assert.deepEqual(s.viewer.target, frames.target);
  assert.ok(maxDiff(s.viewer.position, frames.home.position) < 1e-9, `${s.viewer.position} vs ${frames.home.position}`);
  const names = await byId(page, 'view3d-look').locator('option').allTextContents();
  assert.deepEqual(names, ['free orbit', ...toyScene.views.map((v) => v.name)]);
  await page.screenshot({ path: join(artifacts, 'view3d-loaded.png'), clip: await byId(page, 'view3d').boundingBox() });
  assert.deepEqual(page.problems, []);
  console.log(`  ${s.cameras} cameras, ${s.triangles} triangles, ${px.ink} of ${px.pixels} pixels drawn`);
  await page.context().close();
});

test('mouse: dragging orbits about the target (same distance), the wheel zooms', async () => {
  const page = await openPage();
  await loadToy(page);
  await page.waitForFunction(() => document.getElementById('view3d').view3d?.info().objectVisible);
  const dist = (v) => Math.hypot(...v.position.map((x, i) => x - v.target[i]));
  const a = (await info(page)).viewer;
  const box = await byId(page, 'view3d-canvas').boundingBox();
  const [cx, cy] = [box.x + box.width / 2, box.y + box.height / 2];
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx + 40, cy + 10, { steps: 5 });
  await page.mouse.move(cx + 80, cy + 20, { steps: 5 });
  await page.mouse.up();
  const b = (await info(page)).viewer;
  assert.ok(maxDiff(a.position, b.position) > 1e-3 * dist(a), `the camera did not move: ${a.position} → ${b.position}`);
  assert.ok(Math.abs(dist(b) - dist(a)) < 1e-6 * dist(a), `orbit changed the distance: ${dist(a)} → ${dist(b)}`);
  assert.deepEqual(b.target, a.target);
  const before = await glPixels(page);
  await page.mouse.wheel(0, -400);
  await page.waitForFunction((d0) => {
    const v = document.getElementById('view3d').view3d.info().viewer;
    return Math.hypot(...v.position.map((x, i) => x - v.target[i])) < 0.95 * d0;
  }, dist(b));
  await rendered(page);
  const after = await glPixels(page);
  assert.ok(after.ink > before.ink, `zooming in covers more pixels: ${before.ink} → ${after.ink}`);
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('fit: the object follows the fit live, and ends at the result pose (matrix within 1e-6)', async () => {
  const { page, result, matrices, wall } = await fittedPage();
  assert.ok(matrices.length >= 5, `only ${matrices.length} pose updates while fitting`);
  const distinct = matrices.filter((m, i) => i === 0 || maxDiff(m, matrices[i - 1]) > 1e-9).length;
  assert.ok(distinct >= 3, `the drawn pose changed only ${distinct} times`);
  const first = matrices[0];
  const last = (await info(page)).objectMatrix;
  const expected = result.matrix.flat();
  assert.ok(maxDiff(first, expected) > 1e-3, 'the early pose differs from the final one');
  assert.ok(maxDiff(last, expected) < 1e-6, `drawn ${last} vs result ${expected}`);
  // The pose form: object-to-world = [R·diag(s) | t].
  const { rotation: R, scale: s, translation: t } = result.pose;
  const fromPose = [0, 1, 2].flatMap((i) => [R[i][0] * s[0], R[i][1] * s[1], R[i][2] * s[2], t[i]]).concat([0, 0, 0, 1]);
  assert.ok(maxDiff(last, fromPose) < 1e-6, 'T·R·S of the result pose');
  console.log(`  ${matrices.length} pose updates (${distinct} distinct) in ${wall.toFixed(1)} s of fitting`);
});

test('look through a view: the object drawn at the fitted pose covers that view\'s mask (IoU >= 0.9)', async () => {
  const { page } = await fittedPage();
  const ious = [];
  for (let k = 0; k < toyScene.views.length; k++) {
    await call(page, (v, k) => {
      v.setVisible({ cameras: false, ghosts: false, suggestion: false });
      v.lookThrough(k);
    }, k);
    await rendered(page);
    const px = await glPixels(page, true);
    const mask = await page.evaluate(async (path) => {
      const bmp = await createImageBitmap(await (await fetch(path)).blob());
      const c = Object.assign(document.createElement('canvas'), { width: bmp.width, height: bmp.height });
      const ctx = c.getContext('2d');
      ctx.drawImage(bmp, 0, 0);
      const d = ctx.getImageData(0, 0, c.width, c.height).data;
      return { w: c.width, h: c.height, on: Array.from({ length: c.width * c.height }, (_, i) => (d[4 * i] >= 128 ? 1 : 0)) };
    }, `examples/toy/${toyScene.views[k].mask}`);
    // Canvas pixel centre → image pixel: the image fitted into the canvas at scale kf, centred.
    const kf = Math.min(px.width / mask.w, px.height / mask.h);
    const [ox, oy] = [(px.width - kf * mask.w) / 2, (px.height - kf * mask.h) / 2];
    let inter = 0, union = 0, outside = 0;
    for (let Y = 0; Y < px.height; Y++) {
      for (let X = 0; X < px.width; X++) {
        const u = Math.round((X + 0.5 - ox) / kf - 0.5);
        const v = Math.round((Y + 0.5 - oy) / kf - 0.5);
        const drawn = px.mask[Y * px.width + X];
        if (u < 0 || v < 0 || u >= mask.w || v >= mask.h) {
          outside += drawn;
          continue;
        }
        const m = mask.on[v * mask.w + u];
        inter += drawn & m;
        union += drawn | m;
      }
    }
    const iou = inter / union;
    ious.push(iou);
    assert.ok(iou >= 0.9, `view ${k}: IoU ${iou.toFixed(3)} between the drawn object and the mask`);
    assert.equal(outside, 0, `view ${k}: drawn outside the image`);
    assert.equal((await info(page)).through, k);
  }
  await page.screenshot({ path: join(artifacts, 'view3d-through.png'), clip: await byId(page, 'view3d').boundingBox() });
  await call(page, (v) => {
    v.setVisible({ cameras: true, ghosts: true, suggestion: true });
    v.home();
  });
  assert.equal((await info(page)).through, null);
  console.log(`  IoU drawn object vs mask, per view: ${ious.map((x) => x.toFixed(3)).join(' ')}`);
});

// The ghosts are poses drawn in Rust (Session.ghosts) from the finished fit's
// covariance; the singular and indefinite covariances are the Rust unit tests' cases
// (src/uncertainty/mod.rs). Here: the page draws the worker's ghosts where Rust put
// them, they stay put, and any matrices given are drawn as given.
test('uncertainty: the finished fit\'s ghosts from Rust, spread as its standard deviations, seeded; given matrices drawn as given', async () => {
  const { page, result } = await fittedPage();
  assert.ok(Array.isArray(result.covariance), `the toy's fit measures its uncertainty: ${result.uncertainty_error}`);
  await rendered(page);
  const s0 = await info(page);
  assert.equal(s0.ghosts, 12, 'Session.ghosts(12, 1), posted by the worker');
  const M = s0.objectMatrix;
  const col = (m, j) => [m[j], m[4 + j], m[8 + j]];
  // About the result's pose, within 6σ of its translation and scale; not all on it.
  const sdT = Math.hypot(...result.std_dev.translation);
  const shifts = s0.ghostMatrices.map((g) => Math.hypot(g[3] - M[3], g[7] - M[7], g[11] - M[11]));
  assert.ok(Math.max(...shifts) < 6 * sdT, `a ghost moved ${Math.max(...shifts)} (σ ${sdT})`);
  assert.ok(shifts.some((d) => d > 0), 'the ghosts spread');
  const sdS = Math.max(...result.std_dev.scale_pct) / 100;
  const logScale = s0.ghostMatrices.flatMap((g) => [0, 1, 2].map((j) => Math.log(Math.hypot(...col(g, j)) / Math.hypot(...col(M, j)))));
  assert.ok(Math.max(...logScale.map(Math.abs)) < 6 * sdS + 1e-9, `log scales ${logScale} (σ ${sdS})`);
  assert.ok(s0.ghostMatrices.every((g) => g.length === 16 && g.every(Number.isFinite)));
  // Seeded: the same ghosts frame after frame.
  await rendered(page);
  await rendered(page);
  assert.deepEqual((await info(page)).ghostMatrices, s0.ghostMatrices, 'the ghosts stay put between frames');

  // Drawing: none, then given matrices (the object's, moved sideways) exactly as given.
  await call(page, (v) => v.setGhosts(null));
  await rendered(page);
  assert.equal((await info(page)).ghosts, 0);
  const clean = await glPixels(page);
  const step = 0.1 * Math.hypot(...col(M, 0));
  const moved = [[step, 0, 0], [-step, 0, 0], [0, step, 0], [0, -step, 0]]
    .map((d) => M.map((x, k) => (k === 3 ? x + d[0] : k === 7 ? x + d[1] : k === 11 ? x + d[2] : x)));
  await call(page, (v, m) => v.setGhosts(m), moved);
  await rendered(page);
  const s = await info(page);
  assert.equal(s.ghosts, 4);
  assert.ok(maxDiff(s.ghostMatrices, moved) < 1e-12, 'drawn at the matrices given');
  const withGhosts = await glPixels(page);
  assert.notEqual(withGhosts.sum, clean.sum, 'the ghosts change the picture');
  assert.ok(withGhosts.ink >= clean.ink, 'ghosts only add');
  // 4×4 rows are taken too; an entry that is not 16 finite numbers is left out.
  const rows = [0, 1, 2, 3].map((i) => moved[0].slice(4 * i, 4 * i + 4));
  await call(page, (v, m) => v.setGhosts(m), [rows, [1, NaN], moved[1].map((x, k) => (k === 5 ? NaN : x))]);
  const g = await info(page);
  assert.equal(g.ghosts, 1);
  assert.ok(maxDiff(g.ghostMatrices[0], moved[0]) < 1e-12);
  await call(page, (v, m) => v.setGhosts(m), s0.ghostMatrices); // the worker's again
  assert.equal((await info(page)).ghosts, 12);
  // An ambiguous fit's alternatives (the result's `alternatives[].matrix`, 4×4 rows): the toy
  // fit has none, so the worker posted none; given ones are drawn in their own colour, apart
  // from the ghosts, and cleared with null.
  assert.equal(s0.alternatives, 0, 'the toy fit is not ambiguous');
  await call(page, (v) => v.setGhosts(null));
  await rendered(page);
  const noGhosts = await glPixels(page);
  await call(page, (v, m) => v.setAlternatives(m), [rows]);
  await rendered(page);
  const a = await info(page);
  assert.equal(a.alternatives, 1);
  assert.equal(a.ghosts, 0, 'the alternatives are not ghosts');
  assert.ok(maxDiff(a.alternativeMatrices[0], moved[0]) < 1e-12, 'drawn at the matrix given');
  assert.notEqual((await glPixels(page)).sum, noGhosts.sum, 'the alternative changes the picture');
  await call(page, (v) => v.setAlternatives(null));
  assert.equal((await info(page)).alternatives, 0);
  await call(page, (v, m) => v.setGhosts(m), s0.ghostMatrices);
  assert.deepEqual(page.problems, []);
});

test('next view from above: the switch re-ranks the finished fit\'s next views on the upper half of the sphere, and back', async () => {
  assert.ok(glueHasSuggest, 'this wasm has Session.suggestViews');
  const { page } = await fittedPage();
  const suggestion = () => call(page, (v) => v.suggestion);
  // The views' mean image-up (−y of each camera, in the world) and the object's centre
  // (its model box's centre at the drawn pose): the lattice's axis and centre.
  const up = [0, 1, 2].map((j) => -toyScene.views.reduce((s, v) => s + v.camera.world_to_camera[1][j], 0));
  const centre = await call(page, (v) => {
    const g = v.object.geometry;
    g.computeBoundingBox();
    return g.boundingBox.getCenter(new v.THREE.Vector3()).applyMatrix4(v.object.matrixWorld).toArray();
  });
  const heights = (list) => list.map(({ world_to_camera: m }) => [0, 1, 2]
    .map((i) => -(m[0][i] * m[0][3] + m[1][i] * m[1][3] + m[2][i] * m[2][3]))
    .reduce((s, x, i) => s + (x - centre[i]) * up[i], 0));
  const sphere = await suggestion();
  assert.equal(sphere?.length, 3, 'the worker posted 3 suggestions');
  const changed = (before) => page.waitForFunction((b) => JSON.stringify(document.getElementById('view3d').view3d.suggestion) !== b,
    JSON.stringify(before), { timeout: 30_000 });
  await byId(page, 'suggest-above').check();
  await changed(sphere);
  const above = await suggestion();
  assert.equal(above.length, 3);
  assert.ok(heights(above).every((h) => h > 0), `heights along the views' up: ${heights(above)}`);
  assert.ok((await info(page)).suggestion, 'the best is drawn');
  await byId(page, 'suggest-above').uncheck();
  await changed(above);
  assert.deepEqual(await suggestion(), sphere, 'the sphere\'s suggestions again');
  assert.deepEqual(page.problems, []);
});

test('suggestion: the next view is a highlighted frustum with its camera JSON; Reset clears it and the ghosts', async () => {
  const { page, result } = await fittedPage();
  const s0 = await info(page);
  if (glueHasSuggest) {
    assert.ok(s0.suggestions >= 1 && s0.suggestion, 'the worker posted Session.suggestViews(3)');
  } else {
    assert.equal(s0.suggestions, 0, 'no suggestViews in this wasm: nothing suggested yet');
    assert.ok(await byId(page, 'suggestion').isHidden());
  }
  await call(page, (v) => v.setSuggestion(null));
  await rendered(page);
  const before = await glPixels(page);
  const cam = oppositeCamera(toyScene, result.pose);
  const second = oppositeCamera({ views: [toyScene.views[1]] }, result.pose);
  // Their frames from Rust (framesOfCameras, as the worker makes the suggestions'), by
  // the page's wasm package loaded here, with the scene's image-plane depth.
  const depth = await call(page, (v) => v.sceneFrames.depth);
  const frames = await page.evaluate(async ([cams, depth]) => {
    const m = await import(new URL('pkg/localisebot.js', location.href).href);
    await m.default({ module_or_path: new URL('pkg/localisebot_bg.wasm', location.href) });
    return m.framesOfCameras(cams, depth);
  }, [[cam, second], depth]);
  assert.equal(frames.length, 2);
  await call(page, (v, list) => v.setSuggestion(list), [{ camera: cam, frame: frames[0] }, { camera: second, frame: frames[1], score: 0.5 }]);
  await rendered(page);
  const s = await info(page);
  assert.ok(s.suggestion, 'the best suggestion is drawn');
  assert.equal(s.suggestions, 2);
  const after = await glPixels(page);
  assert.notEqual(after.sum, before.sum, 'the suggestion changes the picture');
  assert.ok(after.orange > before.orange + 30, `orange pixels ${before.orange} → ${after.orange}`);
  assert.ok(await byId(page, 'suggestion').isVisible());
  const shown = JSON.parse(await byId(page, 'suggestion-json').textContent());
  assert.deepEqual(shown, cam, 'the readout is the best camera, in scene-file form');
  await page.screenshot({ path: join(artifacts, 'view3d-suggestion.png'), clip: await byId(page, 'view3d').boundingBox() });

  // Reset: the fit is no longer done, so the worker clears the ghosts and the suggestion.
  assert.equal((await info(page)).ghosts, 12);
  await byId(page, 'reset').click();
  await page.waitForFunction(() => {
    const i = document.getElementById('view3d').view3d.info();
    return i.ghosts === 0 && !i.suggestion;
  });
  assert.ok(await byId(page, 'suggestion').isHidden());
  assert.deepEqual(page.problems, []);
  await page.context().close();
  fitted = null;
});

test('robust: without WebGL the 3D view is a note and the page fits as before', async () => {
  const page = await openPage({
    init: () => {
      const getContext = HTMLCanvasElement.prototype.getContext;
      HTMLCanvasElement.prototype.getContext = function (type, ...rest) {
        return /webgl/i.test(type) ? null : getContext.call(this, type, ...rest);
      };
    },
  });
  const note = byId(page, 'view3d-note');
  await note.waitFor({ state: 'visible' });
  assert.match(await note.textContent(), /WebGL/);
  await loadToy(page);
  await page.waitForFunction((n) => document.getElementById('view3d').view3d?.info()?.cameras === n, toyScene.views.length, { timeout: 10_000 });
  const s = await info(page);
  assert.equal(s.webgl, false);
  assert.equal(s.cameras, toyScene.views.length, 'the scene is still taken');
  await fit(page);
  assert.match(await byId(page, 'status').textContent(), /^done — verdict ok/);
  await call(page, (v) => v.setSuggestion([{ name: 'x', width: 8, height: 8, fx: 8, fy: 8, cx: 4, cy: 4, world_to_camera: [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 1]] }]));
  assert.ok(await byId(page, 'suggestion').isVisible(), 'the readout works without WebGL');
  assert.equal(await page.locator('[data-testid=view3d-canvas]').count(), 0);
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('robust: without three.js (www/vendor/ not served) the 3D view is a note and the page works', async () => {
  const page = await openPage({ route: { pattern: '**/vendor/three/**', handler: (r) => r.fulfill({ status: 404, body: 'not here' }) } });
  const note = byId(page, 'view3d-note');
  await note.waitFor({ state: 'visible' });
  assert.match(await note.textContent(), /three\.js did not load/);
  await loadToy(page);
  await byId(page, 'step').click();
  await page.waitForFunction(() => /search: [1-9]/.test(document.querySelector('[data-testid=status]').textContent));
  assert.ok(await byId(page, 'error').isHidden());
  // The browser reports the 404s themselves; nothing else may go wrong.
  assert.deepEqual(page.problems.filter((p) => !/Failed to load resource/.test(p)), []);
  await page.context().close();
});

// ---- run ---------------------------------------------------------------------------------
let passed = 0;
let failed = 0;
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
