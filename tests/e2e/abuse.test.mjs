// The page under abuse (issue "Hostile and huge inputs", item 5): files dropped while a
// fit runs, Reset and Start clicked mid-step, a second scene asked for before the first
// finished loading, and Workers ended by the browser (the fit's, a pool's, a
// segmenter's: each holds a Web Lock the page watches, www/lifeline.js). Each ends in
// a state a user can go on from — the right scene shown, the buttons usable, a fit that
// finishes — with every error shown. Needs www/pkg/, the examples
// (scripts/build-examples.sh, ../shared beside the repository) and, for the segmenter's
// Worker, scripts/build-segmenter.sh.
//
//   node tests/e2e/abuse.test.mjs
import { readFileSync, readdirSync, statSync } from 'node:fs';
import { join } from 'node:path';
import assert from 'node:assert/strict';
import { byId, openPage, root, run, status, test, waitFor } from './harness.mjs';

const examples = join(root, 'www', 'examples');
const FIT_MS = 300_000; // limits for hangs, not benchmarks

// The views' names on the page.
const viewNames = (page) => page.evaluate(() => [...document.querySelectorAll('.view .name')].map((e) => e.textContent));
const sceneNames = (id) => JSON.parse(readFileSync(join(examples, id, 'scene.json'), 'utf8')).views.map((v) => v.name);
const buttons = (page) => page.evaluate(() => Object.fromEntries(
  ['start', 'pause', 'step', 'reset', 'download'].map((id) => [id, !document.querySelector(`[data-testid=${id}]`).disabled]),
));
const errorText = async (page) => ((await byId(page, 'error').isVisible()) ? byId(page, 'error').textContent() : null);

// A folder's files with bare names, as a file chooser gives them.
function folderFiles(dir) {
  const out = [];
  const walk = (d) => {
    for (const name of readdirSync(d)) {
      const p = join(d, name);
      if (statSync(p).isDirectory()) walk(p);
      else out.push({ name, mimeType: 'application/octet-stream', buffer: readFileSync(p) });
    }
  };
  walk(dir);
  return out;
}

async function chooseExample(page, id) {
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  await byId(page, 'example-choice').selectOption(`${id}/scene.json`);
  await byId(page, 'load-example').click();
}

// Until the page shows `names` as its views and Start is enabled.
const loaded = (page, names) => waitFor(page, (n) => {
  const shown = [...document.querySelectorAll('.view .name')].map((e) => e.textContent);
  return JSON.stringify(shown) === JSON.stringify(n) && !document.querySelector('[data-testid=start]').disabled
    && document.querySelector('[data-testid=status]').textContent.startsWith('ready');
}, names);

// Until the fit is under way (a frame of a running fit painted).
const fitting = (page) => waitFor(page, () => /search|refine/.test(document.querySelector('[data-testid=status]').textContent)
  && !document.querySelector('[data-testid=pause]').disabled);

// Start, then until done; the verdict.
async function fitToEnd(page) {
  await byId(page, 'start').click();
  await waitFor(page, () => document.querySelector('[data-testid=status]').textContent.startsWith('done'), null, FIT_MS);
  return byId(page, 'verdict').getAttribute('data-verdict');
}

// Stays so for `ms`: the views and the status's start do not change (no late message of
// an earlier scene or run repaints them).
async function stays(page, ms) {
  const before = [await viewNames(page), (await status(page)).split(' ')[0]];
  await page.waitForTimeout(ms);
  assert.deepEqual([await viewNames(page), (await status(page)).split(' ')[0]], before, 'the page changed on its own');
}

test('a second scene asked for before the first loaded: the last one asked for is shown, and fits', async () => {
  const page = await openPage();
  const toy = sceneNames('toy');
  // An example, then files at once: the example's fetch is dropped.
  await chooseExample(page, 'lmo-duck');
  await byId(page, 'file-input').setInputFiles(folderFiles(join(examples, 'toy')));
  await loaded(page, toy);
  await stays(page, 1500);
  // Files, then an example at once: the files (still being read) are dropped.
  await byId(page, 'file-input').setInputFiles(folderFiles(join(examples, 'lmo-duck')));
  await chooseExample(page, 'toy');
  await loaded(page, toy);
  await stays(page, 1500);
  // Two examples, one after the other, without waiting.
  await byId(page, 'example-choice').selectOption('lmo-duck/scene.json');
  await byId(page, 'load-example').click();
  await byId(page, 'example-choice').selectOption('toy/scene.json');
  await byId(page, 'load-example').click();
  await loaded(page, toy);
  await stays(page, 1500);
  assert.equal(await fitToEnd(page), 'ok');
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('files dropped while a fit runs: the fit stops, the new scene is shown ready, and fits', async () => {
  const page = await openPage();
  await chooseExample(page, 'toy');
  await loaded(page, sceneNames('toy'));
  await byId(page, 'start').click();
  await fitting(page);
  await byId(page, 'file-input').setInputFiles(folderFiles(join(examples, 'lmo-duck')));
  const duck = sceneNames('lmo-duck');
  await loaded(page, duck);
  await stays(page, 1500);
  assert.match(await status(page), /^ready/, 'the new scene waits for Start');
  assert.deepEqual(await buttons(page), { start: true, pause: false, step: true, reset: true, download: true });
  assert.equal(await fitToEnd(page), 'ok');
  assert.deepEqual(await viewNames(page), duck);
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('Reset, Start, Step and Pause clicked mid-step, fast: no stuck state, and the fit then ends as an undisturbed one', async () => {
  const page = await openPage();
  await chooseExample(page, 'toy');
  await loaded(page, sceneNames('toy'));
  const clean = await fitToEnd(page);
  const cleanStatus = await status(page);
  const iterations = (s) => Number(s.match(/in (\d+) iterations/)?.[1]);
  await byId(page, 'reset').click();
  await waitFor(page, () => document.querySelector('[data-testid=status]').textContent.startsWith('ready'));
  // Clicks as fast as the buttons allow, whatever state the fit is in.
  const order = ['start', 'reset', 'start', 'step', 'pause', 'start', 'reset', 'step', 'start', 'pause', 'step', 'start', 'reset'];
  for (let round = 0; round < 3; round++) {
    for (const id of order) {
      const b = byId(page, id);
      if (await b.isEnabled()) await b.click({ timeout: 2000 }).catch(() => {});
      await page.waitForTimeout(round * 40);
    }
  }
  // The last click was Reset: the fit is back at its start and stays there (once, a
  // stale frame left it 'paused' at 0/512: the page now follows the worker's last frame).
  await waitFor(page, () => document.querySelector('[data-testid=status]').textContent.startsWith('ready')).catch(async (e) => {
    throw new Error(`${e.message}; status: ${await status(page)}; buttons ${JSON.stringify(await buttons(page))}`);
  });
  await stays(page, 1500);
  assert.match(await status(page), /^ready — search: 0\//);
  assert.deepEqual(await buttons(page), { start: true, pause: false, step: true, reset: true, download: true });
  assert.equal(await errorText(page), null);
  // Then it fits as if nothing had happened: the same verdict and iterations.
  assert.equal(await fitToEnd(page), clean);
  assert.equal(iterations(await status(page)), iterations(cleanStatus), `${await status(page)} vs ${cleanStatus}`);
  // Pause and Start mid-fit, many times: it still ends the same.
  await byId(page, 'reset').click();
  await byId(page, 'start').click();
  for (let k = 0; k < 8; k++) {
    await byId(page, 'pause').click({ timeout: 5000 }).catch(() => {});
    await byId(page, 'start').click({ timeout: 5000 }).catch(() => {});
  }
  await waitFor(page, () => document.querySelector('[data-testid=status]').textContent.startsWith('done'), null, FIT_MS);
  assert.equal(iterations(await status(page)), iterations(cleanStatus));
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

// Ends a Worker from inside, as the browser would end it: no message, no error event.
async function endWorker(page, pathEnd) {
  const w = page.workers().find((x) => new URL(x.url()).pathname.endsWith(pathEnd));
  assert.ok(w, `no ${pathEnd} among ${page.workers().map((x) => x.url())}`);
  await w.evaluate(() => self.close()).catch(() => {}); // the evaluation may not answer
}

test('the fit\'s Worker ended by the browser mid-fit: the error is shown, a new Worker has the scene loaded again, and fits', async () => {
  const page = await openPage('?pool=0');
  await chooseExample(page, 'toy');
  await loaded(page, sceneNames('toy'));
  await byId(page, 'start').click();
  await fitting(page);
  await endWorker(page, '/worker.js');
  await page.waitForFunction(() => !document.querySelector('[data-testid=error]').hidden, null, { timeout: 30_000 });
  const message = await errorText(page);
  assert.match(message, /Worker stopped without a word.*scene loaded again/);
  await page.waitForFunction(() => !document.querySelector('[data-testid=start]').disabled, null, { timeout: 60_000 });
  assert.deepEqual(await viewNames(page), sceneNames('toy'));
  assert.equal(await errorText(page), message, 'the reason stays on the page');
  // The new Worker fits it.
  await byId(page, 'start').click();
  await page.waitForFunction(() => document.querySelector('[data-testid=status]').textContent.startsWith('done'), null, { timeout: FIT_MS });
  assert.equal(await byId(page, 'verdict').getAttribute('data-verdict'), 'ok');
  // A second death: the scene is not loaded again (once only), the page says so and is usable.
  await endWorker(page, '/worker.js');
  await page.waitForFunction(() => /load the scene again/.test(document.querySelector('[data-testid=error]').textContent), null, { timeout: 30_000 });
  assert.deepEqual(await buttons(page), { start: false, pause: false, step: false, reset: false, download: false });
  await chooseExample(page, 'toy');
  await loaded(page, sceneNames('toy'));
  assert.equal(await fitToEnd(page), 'ok');
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('a pool Worker ended by the browser mid-fit: the error names it, the fit goes on in one Worker and ends', async () => {
  const page = await openPage('?pool=2');
  await chooseExample(page, 'toy');
  await loaded(page, sceneNames('toy'));
  assert.equal(await byId(page, 'workers').getAttribute('data-pool'), '2');
  await byId(page, 'start').click();
  await fitting(page);
  // Paused mid-fit (so that the fit cannot end before the Worker does), one pool Worker
  // ended; Start: the step it would have answered must not wait for ever.
  await byId(page, 'pause').click();
  await waitFor(page, () => document.querySelector('[data-testid=status]').textContent.startsWith('paused'));
  await endWorker(page, '/pool-worker.js');
  await page.waitForTimeout(500);
  await byId(page, 'start').click();
  await page.waitForFunction(() => !document.querySelector('[data-testid=error]').hidden, null, { timeout: 30_000 });
  assert.match(await errorText(page), /pool worker \d stopped without a word.*the fit goes on in one worker/);
  assert.equal(await fitToEnd(page), 'ok');
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

test('segmenter Workers ended by the browser: idle or mid-round, a new one takes over; a second end in a round is its error, and Start goes on', async () => {
  const page = await openPage('?segmenters=1');
  // A segmenter Worker busy encoding runs no task of the test's (self.close() would wait
  // for the end of its batch): its owner, the fit's Worker, ends it as the browser would
  // — terminate(), its lifeline not told. The Worker constructor there is wrapped to
  // keep what it made.
  await page.waitForFunction(() => document.querySelector('[data-testid=example-choice]').options.length > 0);
  const fit = page.workers().find((w) => new URL(w.url()).pathname === '/worker.js');
  await fit.evaluate(() => {
    const Base = self.Worker;
    self.spawned = [];
    self.Worker = class extends Base {
      constructor(url, options) {
        super(url, options);
        self.spawned.push({ url: String(url), worker: this });
      }
    };
  });
  const segmenters = () => fit.evaluate(() => self.spawned.filter((s) => s.url.includes('seg-worker')).length);
  const started = async (k) => {
    const deadline = Date.now() + 120_000;
    while ((await segmenters()) <= k && Date.now() < deadline) await page.waitForTimeout(200);
  };
  const end = async (k) => {
    await started(k);
    assert.ok((await segmenters()) > k, `segmenter Worker ${k + 1} never started; the page: '${await page.locator('#seg-text').textContent()}', `
      + `error '${await errorText(page)}', status '${await status(page)}'; locks ${JSON.stringify(await fit.evaluate(() => navigator.locks.query()))}`);
    // Once it holds its lifeline (before, its end is a start that times out).
    await fit.evaluate(async (i) => {
      const { url, worker } = self.spawned.filter((s) => s.url.includes('seg-worker'))[i];
      const life = new URL(url).searchParams.get('life');
      while (!(await navigator.locks.query()).held.some((l) => l.name === life)) await new Promise((ok) => setTimeout(ok, 50));
      worker.terminate();
      // Gone once its lock is free (a Worker busy in wasm takes a moment to end).
      while ((await navigator.locks.query()).held.some((l) => l.name === life)) await new Promise((ok) => setTimeout(ok, 50));
    }, k);
  };
  await chooseExample(page, 'lmo-duck-photos');
  await waitFor(page, () => document.querySelectorAll('.view[data-shown]').length === 3);
  // The segmenter starts with the scene, while boxes are drawn: end it then.
  await end(0);
  await page.waitForTimeout(1000);
  // Start: a new one segments; end it mid-round: the round is sent to a third one…
  await byId(page, 'start').click();
  await page.waitForFunction(() => /segmenting: 0 of/.test(document.querySelector('#seg-text').textContent)
    || !document.querySelector('[data-testid=error]').hidden, null, { timeout: 180_000 });
  assert.equal(await errorText(page), null, 'the idle segmenter\'s end became an error');
  assert.equal(await segmenters(), 2, 'a new segmenter Worker was started for Start');
  await end(1);
  await started(2);
  assert.equal(await errorText(page), null, 'the first end in a round became an error');
  // …and ending that one too is the round's error.
  await end(2);
  await page.waitForFunction(() => !document.querySelector('[data-testid=error]').hidden, null, { timeout: 60_000 });
  const error = await errorText(page);
  assert.match(error, /segmenter worker \d stopped without a word/);
  await page.waitForFunction(() => !document.querySelector('[data-testid=start]').disabled, null, { timeout: 30_000 });
  // Start again: a fourth, and the rounds go on to the end.
  await byId(page, 'start').click();
  await page.waitForFunction(() => document.querySelector('[data-testid=status]').textContent.startsWith('done'), null, { timeout: FIT_MS });
  assert.equal(await segmenters(), 4);
  console.log(`  the error shown: '${error}'; then: ${await status(page)}`);
  assert.notEqual(await byId(page, 'verdict').getAttribute('data-verdict'), 'failed');
  assert.deepEqual(page.problems, []);
  await page.context().close();
});

await run();
