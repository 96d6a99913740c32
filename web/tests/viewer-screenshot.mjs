// The screenshot in docs/viewer.md: the demo page (web/viewer/demo) served by a plain static file
// server (python3 -m http.server), as a visitor sees it first.
//
//   node web/tests/viewer-screenshot.mjs docs/figures/viewer-demo.png
import { spawn } from 'node:child_process';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { findChromium, launch } from './harness.mjs';

const out = process.argv[2];
if (!out) {
  console.error('usage: node web/tests/viewer-screenshot.mjs OUT.png');
  process.exit(2);
}
const root = join(dirname(fileURLToPath(import.meta.url)), '..', 'viewer');
// Port 0: the system picks one, and the server prints it.
const server = spawn('python3', ['-u', '-m', 'http.server', '0', '--bind', '127.0.0.1', '--directory', root],
  { stdio: ['ignore', 'pipe', 'ignore'] });
const port = await new Promise((ok, fail) => {
  let text = '';
  server.stdout.on('data', (d) => {
    text += d;
    const m = text.match(/port (\d+)/);
    if (m) ok(m[1]);
  });
  server.on('exit', (code) => fail(new Error(`python3 -m http.server exited with ${code}`)));
});
const browser = await launch(findChromium());
try {
  const page = await browser.newPage({ viewport: { width: 1000, height: 730 }, deviceScaleFactor: 1 });
  await page.goto(`http://127.0.0.1:${port}/demo/index.html`);
  await page.waitForFunction(() => /drawn at depth/.test(document.getElementById('status').textContent));
  await page.waitForTimeout(300);
  await page.screenshot({ path: out });
} finally {
  await browser.close();
  server.kill();
}
