// The browser viewer (web/viewer/dist/subvec-viewer.js) against `subvec render`, in headless
// Chromium with software WebGL: for each examples/*.svec.json and the demo's photograph
// (web/viewer/demo/rocket.svec), both draw the image at 1x and 4x its width and a 16x zoomed window
// (1/16 of the width, centred on the most salient feature, drawn at the image's width), and the MAE
// between them (`subvec compare`, 0-255 scale) must stay within the limits below. The same for
// files with objects made at test time (`subvec edit` with tests/bad-input/files/ops-objects.json:
// examples/01-disk's disk made an object, moved, rotated and scaled; and one that reaches past the
// image, drawn also in a window larger than the image; a hidden one; one with a vertex on the image's
// corner; strokes on an object, and on the lower of two objects), plus a window on an object's
// boundary. Then the <subvec-image> element's behaviour and the demo page
// (viewer-element.mjs), and the bundle's import in node.
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
export const MAX_MAE = { '1x': 1.0, '4x': 1.0, '16x window': 1.5, '16x object window': 1.5, '1.5x wider window': 1.0 };

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

const rounded = (w) => ({ x0: +w.x0.toFixed(4), y0: +w.y0.toFixed(4), x1: +w.x1.toFixed(4), y1: +w.y1.toFixed(4) });
const windowCase = (name, svec, win) => [name, ['--width', String(svec.width), '--window', windowArg(win)], { width: svec.width, window: win }];

// The three cases of one file: [name, `subvec render` arguments, viewer options]. A file with
// objects adds a 16x window on the rightmost vertex of its first object (on its boundary), and
// `outside` a window of 1.5 times the image about its centre.
export function cases(svec, outside = false) {
  const out = [
    ['1x', ['--width', String(svec.width)], { width: svec.width }],
    ['4x', ['--width', String(4 * svec.width)], { width: 4 * svec.width }],
    windowCase('16x window', svec, rounded(zoomWindow(svec))),
  ];
  const object = svec.objects?.[0];
  if (object) {
    const [cx, cy] = object.mesh.vertices.reduce((a, b) => (b[0] > a[0] ? b : a));
    const ww = svec.width / 16, wh = svec.height / 16;
    out.push(windowCase('16x object window', svec, rounded({ x0: cx - ww / 2, y0: cy - wh / 2, x1: cx + ww / 2, y1: cy + wh / 2 })));
  }
  if (outside) {
    const { width: w, height: h } = svec;
    out.push(windowCase('1.5x wider window', svec, rounded({ x0: -w / 4, y0: -h / 4, x1: 1.25 * w, y1: 1.25 * h })));
  }
  return out;
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
    // Files with objects, made with the CLI: the disk an object (moved, rotated, scaled), as .svec
    // (version 3), lossless and as JSON; and an object reaching past the image's right and bottom.
    const objects = [];
    try {
      const disk = join(root, 'examples', '01-disk.svec.json'), ops = join(root, 'tests', 'bad-input', 'files', 'ops-objects.json');
      const made = (name, ...args) => (execFileSync(binary, args.map((a) => (a === '@' ? join(dir, name) : a))), join(dir, name));
      objects.push(made('disk-object.svec', 'edit', disk, '-o', '@', '--ops', ops));
      objects.push(made('disk-object-lossless.svec', 'convert', objects[0], '-o', '@', '--lossless'));
      objects.push(made('disk-object-json.svec.json', 'convert', objects[0], '-o', '@'));
      writeFileSync(join(dir, 'ops-outside.json'), JSON.stringify([{ op: 'make-object', at: [48, 48], name: 'outside' },
        { op: 'move-object', object: 0, translate: [40, 20], rotate: 30, scale: 1.2 }]));
      objects.push(made('disk-object-outside.svec', 'edit', disk, '-o', '@', '--ops', join(dir, 'ops-outside.json')));
      writeFileSync(join(dir, 'ops-hidden.json'), JSON.stringify([{ op: 'make-object', at: [48, 48], name: 'hidden' },
        { op: 'move-object', object: 0, translate: [20, 0] }, { op: 'hide-object', object: 0 }]));
      objects.push(made('disk-object-hidden.svec', 'edit', disk, '-o', '@', '--ops', join(dir, 'ops-hidden.json')));
      // An object with vertices on the image's corner and sides: no vertex of an object is an
      // image corner, its boundary is one smooth crease curve.
      const corner = JSON.parse(readFileSync(disk, 'utf8'));
      corner.version = 2;
      corner.objects = [{ name: 'corner', mesh: { vertices: [[0, 0], [60, 0], [0, 60], [20, 20]], colors: [[20, 160, 40], [20, 160, 40], [200, 220, 40], [250, 250, 250]],
        triangles: [[0, 1, 3], [1, 2, 3], [2, 0, 3]] } }];
      writeFileSync(join(dir, 'corner-object.svec.json'), JSON.stringify(corner));
      objects.push(join(dir, 'corner-object.svec.json'));
      // Strokes on objects (`stylize --object`): the disk object's, as .svec and JSON; and the
      // lower of two overlapping objects stylized, so that the upper one covers its strokes.
      objects.push(made('disk-object-styled.svec', 'stylize', objects[0], '-o', '@', '--object', '0'));
      objects.push(made('disk-object-styled-json.svec.json', 'convert', join(dir, 'disk-object-styled.svec'), '-o', '@'));
      writeFileSync(join(dir, 'ops-two.json'), JSON.stringify([{ op: 'make-object', at: [48, 48], name: 'lower' },
        { op: 'move-object', object: 0, translate: [-12, 6], scale: 0.6 }, { op: 'make-object', at: [48, 48], name: 'upper' }]));
      const two = made('two-objects.svec', 'edit', disk, '-o', '@', '--ops', join(dir, 'ops-two.json'));
      objects.push(made('two-objects-styled.svec', 'stylize', two, '-o', '@', '--object', '0'));
    } catch (e) {
      failed++;
      console.log(`FAIL making the files with objects: ${why(e)}`);
    }
    for (const file of [...files, ...objects]) {
      const name = basename(file).replace(/\..*$/, '');
      let svec;
      try {
        svec = readJson(binary, file, dir);
      } catch (e) {
        failed++;
        console.log(`FAIL ${name}: ${why(e)}`);
        continue;
      }
      for (const c of cases(svec, file.endsWith('outside.svec'))) {
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
      const ok = exported === 'SubvecImageElement SubvecRenderer SvecError decode load' && rocket.width === 384 && !rocket.objects.length;
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
