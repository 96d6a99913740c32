// Checks that web/dist (committed, embedded into `subvec serve`) is what web/src builds to:
// type-checks the sources, builds them into a temporary folder and compares every file.
// Exit 0: identical; 1: stale (run `npm run build` in web/ and commit dist/); 77: skipped.
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
const files = (dir) => readdirSync(dir).flatMap((name) => {
  const p = join(dir, name);
  return statSync(p).isDirectory() ? files(p) : [p];
});
execFileSync(join(bin, 'tsc'), ['--noEmit', '-p', web], { stdio: 'inherit', cwd: web });
const out = mkdtempSync(join(tmpdir(), 'subvec-dist-'));
let failed = 0;
try {
  execFileSync(join(bin, 'vite'), ['build', '--logLevel', 'warn', '--outDir', out, '--emptyOutDir'],
    { stdio: 'inherit', cwd: web });
  const built = files(out).map((p) => relative(out, p)).sort();
  const committed = files(join(web, 'dist')).map((p) => relative(join(web, 'dist'), p)).sort();
  if (JSON.stringify(built) !== JSON.stringify(committed)) {
    console.log(`FAIL file lists differ: built ${built.join(', ')}; committed ${committed.join(', ')}`);
    failed++;
  }
  for (const f of built) {
    const a = readFileSync(join(out, f));
    const b = existsSync(join(web, 'dist', f)) ? readFileSync(join(web, 'dist', f)) : null;
    if (!b || !a.equals(b)) {
      console.log(`FAIL web/dist/${f} is stale: run 'npm run build' in web/ and commit web/dist`);
      failed++;
    }
  }
} finally {
  rmSync(out, { recursive: true, force: true });
}
console.log(`${failed === 0 ? 1 : 0} passed, ${failed === 0 ? 0 : 1} failed`);
process.exit(failed === 0 ? 0 : 1);
