// Checks that the committed builds are what their sources build to: web/dist (the editor page,
// embedded into `subvec serve`) from web/src, web/viewer/src/wasm-binary.ts (the viewer's
// WebAssembly) from web/viewer/wasm, and web/viewer/dist (the browser viewer's bundle and type
// declarations) from web/viewer/src. Type-checks the sources, builds them into temporary folders
// and compares every file.
// Exit 0: identical; 1: stale (run `npm run build` / `npm run build:viewer` in web/ and commit the
// dist folders); 77: skipped.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readdirSync, readFileSync, rmSync, statSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';

const web = join(dirname(fileURLToPath(import.meta.url)), '..');
const bin = join(web, 'node_modules', '.bin');
if (!existsSync(join(bin, 'vite')) || !existsSync(join(bin, 'tsc'))) {
  console.log('SKIPPED: web/node_modules is missing (run: cd web && npm ci)');
  process.exit(77);
}
const files = (dir) => !existsSync(dir) ? [] : readdirSync(dir).flatMap((name) => {
  const p = join(dir, name);
  return statSync(p).isDirectory() ? files(p) : [p];
});
const run = (tool, args) => execFileSync(join(bin, tool), args, { stdio: 'inherit', cwd: web });

// Builds into a temporary folder with build(out) and compares it with the committed folder.
// `keep` picks the committed files that the build makes (all by default).
function check(committed, command, build, keep = () => true) {
  const out = mkdtempSync(join(tmpdir(), 'subvec-dist-'));
  let stale = 0;
  try {
    build(out);
    const built = files(out).map((p) => relative(out, p)).sort();
    const have = files(committed).map((p) => relative(committed, p)).filter(keep).sort();
    if (JSON.stringify(built) !== JSON.stringify(have)) {
      console.log(`FAIL file lists differ: built ${built.join(', ')}; committed ${have.join(', ')}`);
      stale++;
    }
    for (const f of built) {
      const a = readFileSync(join(out, f));
      const b = existsSync(join(committed, f)) ? readFileSync(join(committed, f)) : null;
      if (!b || !a.equals(b)) {
        console.log(`FAIL ${relative(join(web, '..'), join(committed, f))} is stale: run '${command}' in web/ and commit it`);
        stale++;
      }
    }
  } finally {
    rmSync(out, { recursive: true, force: true });
  }
  console.log(`${stale ? 'FAIL' : 'ok  '} ${relative(join(web, '..'), committed)} is what its sources build to`);
  return stale === 0;
}

let passed = 0;
let failed = 0;
const checks = [
  () => check(join(web, 'dist'), 'npm run build', (out) => {
    run('tsc', ['--noEmit', '-p', web]);
    run('vite', ['build', '--logLevel', 'warn', '--outDir', out, '--emptyOutDir']);
  }),
  () => check(join(web, 'viewer', 'src'), 'npm run build:viewer', (out) => {
    execFileSync(join(web, 'viewer', 'wasm', 'build'), [join(out, 'wasm-binary.ts')], { stdio: 'inherit' });
  }, (name) => name === 'wasm-binary.ts'),
  () => check(join(web, 'viewer', 'dist'), 'npm run build:viewer', (out) => {
    run('tsc', ['-p', 'viewer']);
    run('vite', ['build', 'viewer', '--logLevel', 'warn', '--outDir', out, '--emptyOutDir']);
    run('tsc', ['-p', 'viewer/tsconfig.types.json', '--outDir', join(out, 'types')]);
  }),
];
for (const c of checks) {
  let ok = false;
  try {
    ok = c();
  } catch (e) {
    console.log(`FAIL ${String(e.message).split('\n')[0]}`);  // a type error or a failed build
  }
  ok ? passed++ : failed++;
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 ? 0 : 1);
