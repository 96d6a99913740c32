// The browser viewer (web/viewer/dist/subvec-viewer.js) against `subvec render`, in headless
// Chromium with software WebGL: for each examples/*.svec.json and the demo's photograph
// (web/viewer/demo/rocket.svec), both draw the image at 1x and 4x its width and a 16x zoomed window
// (1/16 of the width, centred on the most salient feature, drawn at the image's width), and the MAE
// between them (`subvec compare`, 0-255 scale) must stay within the limits below. Then the
// <subvec-image> element's behaviour and the demo page (viewer-element.mjs), and the bundle's import
// in node.
//
//   node web/tests/viewer-compare.mjs BUILD/bin/subvec
//
// Exit status 0: all passed; 1: a check failed; 77: skipped (no Chromium or no node_modules), with
// the reason on stdout. The last line is "N passed, M failed".
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, readdirSync, writeFileSync, existsSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname, basename } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { openViewer, pageMessage, Skip, bundle } from './viewer-render.mjs';
import { checkElement } from './viewer-element.mjs';

// The targets (docs/viewer.md).
export const MAX_MAE = { '1x': 1.0, '4x': 1.0, '16x window': 1.5 };

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');

// The size and level 0 of a .svec / .svec.json file, read through `subvec convert` (JSON).
export function readJson(binary, file, dir) {
  if (file.endsWith('.json')) return JSON.parse(readFileSync(file, 'utf8'));
  const json = join(dir, basename(file) + '.json');
  execFileSync(binary, ['convert', file, '-o', json]);
  return JSON.parse(readFileSync(json, 'utf8'));
}

// A window 1/16 of the image's width, of the image's aspect, inside the image and centred on the
// middle vertex of level 0's most salient feature (a tear: the detail worth zooming into), or on the
// image's centre when there is none.
export function zoomWindow(svec) {
  const { width, height } = svec;
  const level = svec.levels[0];
  let [cx, cy] = [width / 2, height / 2];
  const features = [...(level.features ?? [])].sort((a, b) => (b.saliency ?? 0) - (a.saliency ?? 0));
  if (features.length) {
    const chain = features[0].vertices;
    [cx, cy] = level.vertices[chain[Math.floor(chain.length / 2)]];
  }
  const ww = width / 16, wh = height / 16;
  const x0 = Math.min(Math.max(cx - ww / 2, 0), width - ww);
  const y0 = Math.min(Math.max(cy - wh / 2, 0), height - wh);
  return { x0, y0, x1: x0 + ww, y1: y0 + wh };
}

export const windowArg = (w) => [w.x0, w.y0, w.x1, w.y1].map((v) => +v.toFixed(4)).join(',');

// The three cases of one file: [name, `subvec render` arguments, viewer options].
export function cases(svec) {
  const w = zoomWindow(svec);
  const win = { x0: +w.x0.toFixed(4), y0: +w.y0.toFixed(4), x1: +w.x1.toFixed(4), y1: +w.y1.toFixed(4) };
  return [
    ['1x', ['--width', String(svec.width)], { width: svec.width }],
    ['4x', ['--width', String(4 * svec.width)], { width: 4 * svec.width }],
    ['16x window', ['--width', String(svec.width), '--window', windowArg(win)], { width: svec.width, window: win }],
  ];
}

// MAE of the viewer's drawing of one case against `subvec render`'s, 0-255 scale.
export async function measure(viewer, binary, file, [name, renderArgs, options], dir) {
  const stem = basename(file).replace(/\..*$/, '') + '-' + name.replace(/\W+/g, '');
  const reference = join(dir, stem + '-subvec.png');
  const drawn = join(dir, stem + '-viewer.png');
  execFileSync(binary, ['render', file, '-o', reference, ...renderArgs]);
  writeFileSync(drawn, (await viewer.render(readFileSync(file), file, options)).png);
  const compare = execFileSync(binary, ['compare', reference, drawn, '--json'], { encoding: 'utf8' });
  return JSON.parse(compare).mae_mean;
}

// One line for an exception of `subvec`, the page or playwright.
export const why = (e) => String(e.stderr || pageMessage(e)).trim().split('\n')[0];

async function main() {
  const binary = process.argv[2];
  if (!binary || !existsSync(binary)) {
    console.log(`usage: node web/tests/viewer-compare.mjs PATH/TO/subvec (got '${binary}')`);
    return 2;
  }
  let viewer;
  try {
    viewer = await openViewer();
  } catch (e) {
    if (!(e instanceof Skip)) throw e;
    console.log(`SKIPPED: ${e.message}`);
    return 77;
  }
  let passed = 0;
  let failed = 0;
  const dir = mkdtempSync(join(tmpdir(), 'subvec-viewer-'));
  try {
    const files = readdirSync(join(root, 'examples')).filter((f) => f.endsWith('.svec.json')).sort()
      .map((f) => join(root, 'examples', f));
    files.push(join(root, 'web', 'viewer', 'demo', 'rocket.svec'));
    for (const file of files) {
      const name = basename(file).replace(/\..*$/, '');
      let svec;
      try {
        svec = readJson(binary, file, dir);
      } catch (e) {
        failed++;
        console.log(`FAIL ${name}: ${why(e)}`);
        continue;
      }
      for (const c of cases(svec)) {
        try {
          const mae = await measure(viewer, binary, file, c, dir);
          const ok = mae <= MAX_MAE[c[0]];
          ok ? passed++ : failed++;
          console.log(`${ok ? 'ok  ' : 'FAIL'} ${name} ${c[0]}${c[2].window ? ' ' + windowArg(c[2].window) : ''}:`,
            `MAE ${mae.toFixed(3)} (at most ${MAX_MAE[c[0]]})`);
        } catch (e) {
          failed++;
          console.log(`FAIL ${name} ${c[0]}: ${why(e)}`);
        }
      }
    }
    // The module imports where there is no DOM (the element is registered only where there is).
    try {
      const module = await import(pathToFileURL(bundle).href);
      const exported = Object.keys(module).sort().join(' ');
      const rocket = module.decode(readFileSync(files[files.length - 1]));
      const ok = exported === 'SubvecImageElement SubvecRenderer SvecError decode load' && rocket.width === 384;
      ok ? passed++ : failed++;
      console.log(`${ok ? 'ok  ' : 'FAIL'} the bundle imports in node and decodes there (exports ${exported})`);
    } catch (e) {
      failed++;
      console.log(`FAIL the bundle in node: ${why(e)}`);
    }
    const element = await checkElement(viewer, binary, dir);
    passed += element.passed;
    failed += element.failed;
  } finally {
    await viewer.close();
    rmSync(dir, { recursive: true, force: true });
  }
  console.log(`${passed} passed, ${failed} failed`);
  return failed || !passed ? 1 : 0;
}

// Also a module: scripts/measure-viewer uses cases() and measure().
if (import.meta.url === pathToFileURL(process.argv[1]).href) process.exitCode = await main();
