// Drag latency of the browser editor, end to end: from the pointer event in headless Chromium
// (software WebGL) through the server's ARAP solve and limit evaluation to the redrawn pixels
// (the page reads one pixel back after drawing, which waits for the frame).
//
//   node web/tests/bench-drag.mjs BUILD/bin/subvec IMAGE.svec [--moves N] [--width W --height H]
//                                 [--quality fine|coarse]   (default: what the page picks)
//
// Grabs the longest feature at its middle vertex and drags it in N one-pixel steps, one at a
// time (each move waits for its frame, so latencies do not queue). Prints the latencies' median,
// 90th percentile and maximum, and the size of what was drawn; then the same for --clicks color
// clicks (default 15; the page's default region fill) at points spread over the image.
import { findChromium, launch, serve, stop, openEditor, client } from './harness.mjs';

const [binary, input, ...rest] = process.argv.slice(2);
const opt = (name, fallback) => {
  const i = rest.indexOf(name);
  return i >= 0 ? Number(rest[i + 1]) : fallback;
};
const moves = opt('--moves', 40);
const qi = rest.indexOf('--quality');
const quality = qi >= 0 ? rest[qi + 1] : '';
const viewport = { width: opt('--width', 1280), height: opt('--height', 800) };
const chromium = findChromium();
if (!binary || !input || !chromium) {
  console.error('usage: node web/tests/bench-drag.mjs SUBVEC IMAGE.svec (needs Debian\'s chromium)');
  process.exit(2);
}

const server = await serve(binary, [input]);
const browser = await launch(chromium);
try {
  const { page } = await openEditor(browser, server.url + (quality ? `?quality=${quality}` : ''), viewport);
  const info = await page.evaluate(async () => {
    const doc = await (await fetch('/api/document')).json();
    const control = await (await fetch('/api/control?level=0')).json();
    let best = control.features[0];
    for (const f of control.features) if (f.length > best.length) best = f;
    const v = best[Math.floor(best.length / 2)];
    return {
      vertices: doc.levels[0].vertices, triangles: doc.levels[0].triangles,
      at: [control.positions[2 * v], control.positions[2 * v + 1]], size: [doc.width, doc.height],
    };
  });
  await page.keyboard.press('d');
  await page.evaluate(() => window.subvec.measure(true));
  const [x0, y0] = await client(page, ...info.at);
  await page.mouse.move(x0, y0);
  await page.mouse.down();
  await page.waitForFunction(() => window.subvec.state.drag && window.subvec.state.drag.ok);
  const zoom = await page.evaluate(() => window.subvec.state.transform.zoom);
  // Past the click slop first (a press that moves less is a click), then time the moves.
  const x1 = x0 + 4;
  await page.mouse.move(x1, y0);
  await page.waitForFunction(() => window.subvec.latencies().length >= 1, null, { timeout: 30000 });
  await page.evaluate(() => window.subvec.measure(true));
  for (let i = 1; i <= moves; ++i) {
    // One image pixel per move, back and forth: the redraw costs the same at any displacement,
    // and a long drift would meet a fold the mesh refuses (issue 25).
    await page.mouse.move(x1 + (i % 2) * zoom, y0 + (Math.floor(i / 2) % 2) * zoom);
    await page.waitForFunction((n) => window.subvec.latencies().length >= n, i, { timeout: 30000 }).catch(async (e) => {
      throw new Error(`move ${i}: ${await page.evaluate(() => document.getElementById("status").textContent)}`);
    });
  }
  await page.mouse.up();
  const view = await page.evaluate(() => ({
    depth: window.subvec.state.view.depth, zoom: document.getElementById('zoom-out').textContent, canvas: [document.getElementById('canvas').width, document.getElementById('canvas').height],
  }));
  console.log(`image ${info.size[0]}x${info.size[1]}, ${info.vertices} control vertices, ${info.triangles} triangles; ` +
    `canvas ${view.canvas[0]}x${view.canvas[1]}, refinement depth ${view.depth} (${info.triangles * 4 ** view.depth} triangles drawn; ${view.zoom})`);
  // The median, p90 and maximum of `times`, and the medians of the page's phases of each.
  const report = async (what, times, first) => {
    const sorted = times.slice().sort((a, b) => a - b);
    const q = (p) => sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
    console.log(`${what}: median ${q(0.5).toFixed(1)} ms, p90 ${q(0.9).toFixed(1)} ms, max ${sorted[sorted.length - 1].toFixed(1)} ms`);
    const phases = await page.evaluate(() => window.subvec.phases());
    const median = (k) => phases.map((p) => p[k]).sort((a, b) => a - b)[Math.floor(phases.length / 2)];
    console.log(`  medians: ${first} to request ${median(0).toFixed(1)} ms, request ${median(1).toFixed(1)} ms, ` +
      `update ${median(2).toFixed(1)} ms, draw ${median(3).toFixed(1)} ms`);
    const frames = await page.evaluate(() => window.subvec.renderer().frames);
    const share = (sum) => (100 * sum / Math.max(1, frames.partial)).toFixed(0);
    console.log(`  frames so far: ${frames.partial} partial (on average ${share(frames.partialShare)} % of the canvas, ` +
      `${share(frames.triangleShare)} % of the triangles), ${frames.full} full`);
  };
  const latencies = await page.evaluate(() => window.subvec.latencies());
  await report(`drag redraw, ${latencies.length} moves`, latencies, 'event');

  // Color clicks with the page's defaults (a region fill), at points spread over the image, one at
  // a time: from the click to the recolored frame drawn.
  const clicks = opt('--clicks', 15);
  await page.keyboard.press('c');
  await page.evaluate(() => window.subvec.measure(true));
  for (let i = 1; i <= clicks; ++i) {
    const [x, y] = await client(page, info.size[0] * (0.15 + 0.7 * ((i * 0.618) % 1)), info.size[1] * (0.15 + 0.7 * ((i * 0.382) % 1)));
    await page.mouse.click(x, y);
    await page.waitForFunction((n) => window.subvec.clicks().length >= n, i, { timeout: 30000 });
    await page.waitForFunction(() => window.subvec.idle());
  }
  const taken = await page.evaluate(() => window.subvec.clicks());
  await report(`color click, ${taken.length} clicks`, taken, 'click');
} finally {
  await browser.close();
  await stop(server);
}
