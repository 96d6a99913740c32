// Shared by the end-to-end test and the benchmark: start `subvec serve`, find Chromium, open a page.
import { spawn, execFileSync } from 'node:child_process';
import { existsSync } from 'node:fs';

// Debian's chromium, or $CHROMIUM. null when there is none.
export function findChromium() {
  const candidates = [process.env.CHROMIUM, '/usr/bin/chromium', '/usr/bin/chromium-browser'];
  for (const c of candidates) if (c && existsSync(c)) return c;
  try {
    return execFileSync('sh', ['-c', 'command -v chromium'], { encoding: 'utf8' }).trim() || null;
  } catch {
    return null;
  }
}

// Headless Chromium with software WebGL (SwiftShader): no GPU, no sandbox (CI runs as root).
export async function launch(chromium) {
  const { chromium: pw } = await import('playwright-core');
  return pw.launch({
    executablePath: chromium,
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
      '--ignore-gpu-blocklist', '--disable-gpu-sandbox'],
  });
}

// Starts `subvec serve ARGS --port 0` and resolves with { url, process } once it printed its URL.
export function serve(binary, args, { timeout = 60000 } = {}) {
  return new Promise((resolve, reject) => {
    const child = spawn(binary, ['serve', ...args, '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let err = '';
    const timer = setTimeout(() => {
      child.kill('SIGTERM');
      reject(new Error(`subvec serve printed no URL within ${timeout} ms: ${out} ${err}`));
    }, timeout);
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/http:\/\/[^\s]+\//);
      if (m) {
        clearTimeout(timer);
        resolve({ url: m[0], process: child, stderr: () => err });
      }
    });
    child.stderr.on('data', (d) => { err += d; });
    child.on('exit', (code) => {
      clearTimeout(timer);
      reject(new Error(`subvec serve exited with ${code}: ${err.trim()}`));
    });
  });
}

export function stop(server) {
  return new Promise((resolve) => {
    if (server.process.exitCode !== null) return resolve(server.process.exitCode);
    server.process.removeAllListeners('exit');
    server.process.on('exit', (code) => resolve(code));
    server.process.kill('SIGTERM');
  });
}

// Waits until the page's editor is ready (document loaded, first view drawn).
export async function openEditor(browser, url, viewport = { width: 1000, height: 700 }) {
  const page = await browser.newPage({ viewport, deviceScaleFactor: 1, acceptDownloads: true });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(url);
  await page.waitForFunction(() => window.subvec && window.subvec.ready, null, { timeout: 120000 });
  return { page, errors };
}

export async function idle(page) {
  await page.waitForFunction(() => window.subvec.idle(), null, { timeout: 30000 });
  // one more frame so that the last delta is drawn
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
}

export const pixel = (page, x, y) => page.evaluate(([px, py]) => window.subvec.pixelAt(px, py), [x, y]);
export const client = (page, x, y) => page.evaluate(([px, py]) => window.subvec.clientPoint(px, py), [x, y]);

// The start of a browser test of `subvec serve` (SCRIPT BINARY): exits 77 with the reason when
// Chromium or web/node_modules is missing, 2 without a binary; returns Chromium's path.
export function requireBrowser(script, binary) {
  const chromium = findChromium();
  if (!chromium) {
    console.log('SKIPPED: no Chromium found (scripts/setup installs Debian\'s chromium; or set CHROMIUM)');
    process.exit(77);
  }
  if (!existsSync(new URL('../node_modules/playwright-core', import.meta.url))) {
    console.log('SKIPPED: web/node_modules is missing (run: cd web && npm ci)');
    process.exit(77);
  }
  if (!binary || !existsSync(binary)) {
    console.log(`usage: node web/tests/${script} PATH/TO/subvec (got '${binary}')`);
    process.exit(2);
  }
  return chromium;
}

// The checks of a browser test: check(name, ok, detail) prints "ok   name" or "FAIL name detail";
// finish() prints "N passed, M failed" and exits 0 when none failed, else 1.
let passed = 0;
let failed = 0;
export function check(name, ok, detail = '') {
  if (ok) passed++;
  else failed++;
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${name}${ok ? '' : ` ${detail}`}`);
}
export function finish() {
  console.log(`${passed} passed, ${failed} failed`);
  process.exit(failed === 0 ? 0 : 1);
}

// The largest channel difference of two RGB(A) pixels.
export const diff = (a, b) => Math.max(...[0, 1, 2].map((i) => Math.abs(a[i] - b[i])));
