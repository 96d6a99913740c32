// PDF export in PDF.js (Firefox's PDF renderer) in headless Chromium: for each examples/*.svec.json,
// `subvec render` to PNG and to PDF, PDF.js draws the PDF at 1x (pdfjs-render.mjs), and the MAE
// between the two (`subvec compare`, 0-255 scale) must stay within MAX_MAE.
//
//   node web/tests/pdfjs-export.mjs BUILD/bin/subvec
//
// Exit status 0: all passed; 1: a check failed; 77: skipped (no Chromium or no node_modules), with
// the reason on stdout. The last line is "N passed, M failed".
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readdirSync, readFileSync, writeFileSync, existsSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { openPdfjs, Skip } from './pdfjs-render.mjs';

// The project's target for PDF.js. Measured 2026-12-06 (pdfjs-dist 5.6.205, Chromium 156): 0.78,
// 0.64, 1.16 (pdftocairo 0.58, 0.28, 0.62). The difference is PDF.js's own: its mesh rasterizer
// truncates colors (-0.3 to -0.9 levels on average), leaves the mesh's edges at tears aliased, and
// wraps the mesh's last column into its first (the page's left column is 9 to 31 levels off here).
const MAX_MAE = 1.5;

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');
const binary = process.argv[2];
if (!binary || !existsSync(binary)) {
  console.log(`usage: node web/tests/pdfjs-export.mjs PATH/TO/subvec (got '${binary}')`);
  process.exit(2);
}

let pdfjs;
try {
  pdfjs = await openPdfjs();
} catch (e) {
  if (!(e instanceof Skip)) throw e;
  console.log(`SKIPPED: ${e.message}`);
  process.exit(77);
}

let passed = 0;
let failed = 0;
const dir = mkdtempSync(join(tmpdir(), 'subvec-pdfjs-'));
try {
  const examples = readdirSync(join(root, 'examples')).filter((f) => f.endsWith('.svec.json')).sort();
  for (const file of examples) {
    const name = file.replace(/\.svec\.json$/, '');
    const input = join(root, 'examples', file);
    const [png, pdf, drawn] = ['.png', '.pdf', '-pdfjs.png'].map((s) => join(dir, name + s));
    try {
      execFileSync(binary, ['render', input, '-o', png]);
      execFileSync(binary, ['render', input, '-o', pdf]);
      writeFileSync(drawn, await pdfjs.render(readFileSync(pdf)));
      const compare = execFileSync(binary, ['compare', png, drawn, '--json'], { encoding: 'utf8' });
      const mae = JSON.parse(compare).mae_mean;
      const ok = mae <= MAX_MAE;
      ok ? passed++ : failed++;
      console.log(`${ok ? 'ok  ' : 'FAIL'} ${name}: PDF.js MAE ${mae.toFixed(2)} (at most ${MAX_MAE}),`,
        `PDF ${readFileSync(pdf).length} bytes`);
    } catch (e) {
      failed++;
      console.log(`FAIL ${name}: ${String(e.stderr || e.message).trim().split('\n')[0]}`);
    }
  }
} finally {
  await pdfjs.close();
  rmSync(dir, { recursive: true, force: true });
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed || !passed ? 1 : 0);
