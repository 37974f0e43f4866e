// Smoke test of the packed npm package: unpacks OUT_DIR/localisebot-*.tgz, checks its
// file list and package.json, loads it in Node (initSync) and fits the web page's toy
// example (www/examples/toy, made by scripts/build-examples.sh). Prints "N passed, N failed".
//
//   node pkg-config/smoke.mjs [OUT_DIR]     # default target/npm (see pkg-config/build.sh)
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import assert from 'node:assert/strict';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const out = process.argv[2] ?? join(root, 'target', 'npm');
const tgz = readdirSync(out).filter((f) => /^localisebot-.*\.tgz$/.test(f)).sort().at(-1);
if (!tgz) {
  console.error(`no localisebot-*.tgz in ${out}: run pkg-config/build.sh first`);
  process.exit(1);
}
const dir = mkdtempSync(join(tmpdir(), 'localisebot-pack-'));
execFileSync('tar', ['-xzf', join(out, tgz), '-C', dir]);
const pkgDir = join(dir, 'package');

let passed = 0;
let failed = 0;
async function test(name, fn) {
  try {
    await fn();
    passed++;
    console.log(`ok - ${name}`);
  } catch (e) {
    failed++;
    console.log(`FAIL - ${name}\n  ${e.stack ?? e}`);
  }
}

await test(`${tgz} holds the module, its types, the wasm and the README`, () => {
  const files = readdirSync(pkgDir).sort();
  assert.deepEqual(files, ['README.md', 'localisebot.d.ts', 'localisebot.js', 'localisebot_bg.wasm',
    'localisebot_bg.wasm.d.ts', 'package.json']);
  const pkg = JSON.parse(readFileSync(join(pkgDir, 'package.json'), 'utf8'));
  assert.equal(pkg.name, 'localisebot');
  assert.equal(pkg.types, './localisebot.d.ts');
  assert.equal(pkg.type, 'module');
  const cargoVersion = readFileSync(join(root, 'Cargo.toml'), 'utf8').match(/^version = "(.*)"/m)[1];
  assert.equal(pkg.version, cargoVersion);
  const dts = readFileSync(join(pkgDir, 'localisebot.d.ts'), 'utf8');
  for (const name of ['class Session', 'class SessionBuilder', 'class FileSet', 'interface Progress', 'interface FitResult',
    'function sceneFiles', 'static fromFiles'])
    assert.ok(dts.includes(name), `the TypeScript declarations lack ${name}`);
});

await test('the package loads in Node and fits a scene', async () => {
  const lib = await import(pathToFileURL(join(pkgDir, 'localisebot.js')).href);
  lib.initSync({ module: readFileSync(join(pkgDir, 'localisebot_bg.wasm')) });
  const scene = join(root, 'www', 'examples', 'toy');
  if (!existsSync(join(scene, 'scene.json'))) throw new Error(`${scene} is missing: run scripts/build-examples.sh first`);
  const text = readFileSync(join(scene, 'scene.json'), 'utf8');
  const files = new lib.FileSet();
  for (const f of lib.sceneFiles('scene.json', text)) files.add(f, readFileSync(join(scene, f)));
  assert.equal(files.length, 9, 'the mesh, 4 masks and 4 images');
  const session = lib.Session.fromScene('scene.json', text, files);
  let progress;
  while (!session.done) progress = session.stepFor(50);
  assert.equal(progress.phase, 'done');
  const result = session.result();
  assert.equal(result.views.length, 4);
  assert.ok(result.errors.rotation_deg < 5, `rotation error ${result.errors.rotation_deg}°`);
  assert.ok(result.mean_iou >= 0.95, `mean IoU ${result.mean_iou}`);
  assert.throws(() => lib.Session.fromScene('scene.json', '{"mesh": 1}', new lib.FileSet()), (e) =>
    e instanceof Error && e.message.startsWith('scene.json:'));
  assert.throws(() => lib.Session.fromFiles(new lib.FileSet()), (e) => e instanceof Error && e.message === 'no files were given');
  console.log(`  fitted in ${session.seconds.toFixed(2)} s, mean IoU ${result.mean_iou.toFixed(3)}`);
});

rmSync(dir, { recursive: true, force: true });
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
