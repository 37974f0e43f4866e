// What the page's end-to-end tests share: the static server (scripts/serve.mjs on a free
// port), Debian's Chromium through playwright-core, a page per test, element lookups,
// and the runner (one line per test, then "N passed, N failed"; E2E_ONLY=TEXT runs the
// tests whose name contains TEXT).
import { chromium } from 'playwright-core';
import { spawn } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

export const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
export const artifacts = process.env.E2E_ARTIFACTS ?? join(root, 'target', 'e2e');
mkdirSync(artifacts, { recursive: true });

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

export const server = await startServer();
export const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--disable-quic',
    '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
});

// A page at `query`, recording its errors in page.problems; `prepare(context)` runs
// before it loads (e.g. routes that answer some requests otherwise).
export async function openPage(query = '', prepare = async () => {}) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 900 }, acceptDownloads: true });
  await prepare(context);
  const page = await context.newPage();
  page.problems = [];
  page.on('pageerror', (e) => page.problems.push(`page error: ${e.message}`));
  page.on('console', (m) => m.type() === 'error' && page.problems.push(`console error: ${m.text()}`));
  await page.goto(server.url + query);
  return page;
}

export const byId = (page, id) => page.getByTestId(id);
export const status = (page) => byId(page, 'status').textContent();

// Waits until `fn` (run in the page) is true or the page shows an error; throws the error.
export async function waitFor(page, fn, arg = null, timeout = 60_000) {
  await page.waitForFunction(
    ([f, a]) => new Function(`return (${f})`)()(a) || !document.querySelector('[data-testid=error]').hidden,
    [fn.toString(), arg],
    { timeout, polling: 50 },
  );
  const error = byId(page, 'error');
  if (await error.isVisible()) throw new Error(`the page shows an error: ${await error.textContent()}`);
}

const tests = [];
export const test = (name, fn) => tests.push({ name, fn });

export async function run() {
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
}
