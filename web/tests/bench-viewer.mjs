// Times the browser viewer (web/viewer/dist/subvec-viewer.js) in headless Chromium with software
// WebGL (SwiftShader), as the issue asks: the first frame of a file at 512 x 512 after it is fetched
// (decode + renderer and GL setup + refine + draw + a pixel read, which waits for the GPU), in a
// freshly loaded page each run so that nothing is warm (and again in that page, compiled); and a
// re-render after a zoom step (setView, render, a pixel read). Medians of --runs runs (default 15), then the bundle's size.
//
//   node web/tests/bench-viewer.mjs FILE.svec [--runs N] [--size S]   (scripts/bench-viewer)
//
// Prints a Markdown table. Exit 0; 1 on an error (one line); 77 when Chromium or web/node_modules
// is missing.
import { readFileSync } from 'node:fs';
import { gzipSync } from 'node:zlib';
import { openViewer, bundle as defaultBundle, pageMessage, Skip } from './viewer-render.mjs';

const ZOOM_STEP = 1.25;  // one wheel notch of the element is about this much
const ZOOM_STEPS = 10;   // zoom steps timed per run

// Runs in the page: one cold first frame and ZOOM_STEPS zoom steps of the file at url.
async function bench([url, size, zoomStep, zoomSteps]) {
  const { decode, SubvecRenderer } = await import('/subvec-viewer.js');
  const bytes = new Uint8Array(await (await fetch(url)).arrayBuffer());
  const sync = (canvas) => {
    const gl = canvas.getContext('webgl2');  // the renderer's own context
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
  };
  // The image contained in the square canvas, centred, as <subvec-image> shows it.
  const fit = (w, h, z, cx = w / 2, cy = h / 2) => {
    const half = Math.max(w, h) / 2 / z;
    return { x0: cx - half, y0: cy - half, x1: cx + half, y1: cy + half };
  };
  // A first frame on a new canvas: renderer (context, shaders: the GPU process compiles them
  // while the page decodes), decode, refine, draw, sync; in <subvec-image>'s order.
  const firstFrame = () => {
    const t0 = performance.now();
    const canvas = document.createElement('canvas');
    canvas.width = canvas.height = size;
    document.body.append(canvas);
    const renderer = new SubvecRenderer(canvas);
    const t1 = performance.now();
    const image = decode(bytes, url.slice(url.lastIndexOf('/') + 1));
    const t2 = performance.now();
    renderer.setImage(image, 0);
    renderer.setView(fit(image.width, image.height, 1));
    renderer.render();
    const t3 = performance.now();
    sync(canvas);
    const t4 = performance.now();
    return { image, canvas, renderer, time: { total: t4 - t0, setup: t1 - t0, decode: t2 - t1, render: t3 - t2, sync: t4 - t3, ...renderer.stats } };
  };
  const { image, canvas, renderer, time: first } = firstFrame();
  // Zooming in about a point off the centre (where the image has detail), as a wheel does.
  const zooms = [];
  let z = 1;
  for (let i = 0; i < zoomSteps; i++) {
    z *= zoomStep;
    const s = performance.now();
    renderer.setView(fit(image.width, image.height, z, image.width * 0.45, image.height * 0.4));
    renderer.render();
    sync(canvas);
    zooms.push({ total: performance.now() - s, ...renderer.stats });
  }
  renderer.dispose();
  // The same again in this page: what is left of the first frame once the code is compiled.
  const again = firstFrame();
  again.renderer.dispose();
  return { first, again: again.time, zooms, vertices: image.levels[0].positions.length / 2 };
}

const median = (values) => {
  const v = [...values].sort((a, b) => a - b);
  return v.length % 2 ? v[(v.length - 1) / 2] : (v[v.length / 2 - 1] + v[v.length / 2]) / 2;
};
const ms = (v) => v.toFixed(1);

async function main(argv) {
  let runs = 15;
  let size = 512;
  const files = [];
  for (let i = 0; i < argv.length; i++) {
    if (argv[i] === '--runs') runs = Number(argv[++i]);
    else if (argv[i] === '--size') size = Number(argv[++i]);
    else files.push(argv[i]);
  }
  if (files.length !== 1 || !(runs >= 1 && Number.isInteger(runs)) || !(size >= 16 && size <= 4096)) {
    console.error('usage: bench-viewer FILE.svec [--runs N] [--size S]');
    return 2;
  }
  const [file] = files;
  let viewer;
  try {
    viewer = await openViewer({ module: process.env.SUBVEC_VIEWER_BUNDLE || defaultBundle });
  } catch (e) {
    console.error(`bench-viewer: ${e instanceof Skip ? 'skipped: ' : ''}${e.message.split('\n')[0]}`);
    return e instanceof Skip ? 77 : 1;
  }
  const results = [];
  try {
    const url = viewer.put(readFileSync(file), file);
    for (let i = 0; i < runs; i++) {
      await viewer.page.reload();  // a cold page: no JIT, no shader or context left from before
      await viewer.page.waitForFunction(() => window.ready);
      results.push(await viewer.page.evaluate(bench, [url, size, ZOOM_STEP, ZOOM_STEPS]));
    }
  } catch (e) {
    console.error(`bench-viewer: ${file}: ${pageMessage(e)}`);
    return 1;
  } finally {
    await viewer.close();
  }
  const firsts = results.map((r) => r.first);
  const agains = results.map((r) => r.again);
  const zooms = results.flatMap((r) => r.zooms);
  const js = readFileSync(process.env.SUBVEC_VIEWER_BUNDLE || defaultBundle);
  const row = (what, rs, extra) => `| ${what} | **${ms(median(rs.map((r) => r.total)))}** | ` +
    `${ms(Math.min(...rs.map((r) => r.total)))} – ${ms(Math.max(...rs.map((r) => r.total)))} | ${extra} |`;
  console.log(`${file}: ${results[0].vertices} vertices at level 0, canvas ${size} x ${size}, ` +
    `${runs} runs (Chromium, SwiftShader)`);
  console.log('');
  console.log('| what | median ms | range ms | of which (medians) |');
  console.log('|---|---|---|---|');
  console.log(row('first frame after the fetch', firsts,
    `decode ${ms(median(firsts.map((r) => r.decode)))}, refine ${ms(median(firsts.map((r) => r.refineMs)))}, ` +
    `draw ${ms(median(firsts.map((r) => r.drawMs)))}, context and shaders ${ms(median(firsts.map((r) => r.setup)))}, ` +
    `render() ${ms(median(firsts.map((r) => r.render)))}, GPU wait ${ms(median(firsts.map((r) => r.sync)))}; depth ${median(firsts.map((r) => r.depth))}, ` +
    `${median(firsts.map((r) => r.triangles))} triangles`));
  console.log(row('the same, a second file in that page', agains,
    `decode ${ms(median(agains.map((r) => r.decode)))}, refine ${ms(median(agains.map((r) => r.refineMs)))}`));
  console.log(row(`re-render after a ${ZOOM_STEP}x zoom step (${zooms.length})`, zooms,
    `refine ${ms(median(zooms.map((r) => r.refineMs)))}, draw ${ms(median(zooms.map((r) => r.drawMs)))}`));
  console.log(`| bundle (dist/subvec-viewer.js) | ${js.length} bytes minified | ` +
    `${gzipSync(js, { level: 9 }).length} bytes gzipped | |`);
  return 0;
}

process.exitCode = await main(process.argv.slice(2));
