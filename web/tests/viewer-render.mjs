// Draws a .svec / .svec.json file with the browser viewer (web/viewer/dist/subvec-viewer.js, the
// committed bundle) in headless Chromium, software WebGL, and writes the canvas as a PNG.
//
//   node web/tests/viewer-render.mjs IN.svec OUT.png [--width W] [--window X0,Y0,X1,Y1] [--level L]
//                                                        (scripts/viewer-render wraps it)
//
// The canvas is sized as `subvec render` sizes its output: W (default: the window's width, which is
// the image's without --window) by round(W * window height / window width); outside the image it is
// transparent. Everything is served as static files from 127.0.0.1 (no subvec process). Exit 0:
// written; 1: the file could not be drawn; 2: usage; 77: no Chromium or no web/node_modules, so a
// ctest can skip. Errors are one line on stderr. Also a module: openViewer() draws many files with
// one browser.
import { createServer } from 'node:http';
import { readFileSync, writeFileSync, existsSync, renameSync, statSync } from 'node:fs';
import { join, dirname, basename, resolve, extname } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { findChromium, launch } from './harness.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const viewerDir = join(here, '..', 'viewer');
export const bundle = join(viewerDir, 'dist', 'subvec-viewer.js');
const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.json': 'application/json' };
const TIMEOUT_MS = 120000;

export class Skip extends Error {}

// Why the viewer cannot run here, or null.
export function missing() {
  if (!existsSync(join(here, '..', 'node_modules', 'playwright-core'))) {
    return 'web/node_modules (playwright-core) is missing (run: cd web && npm ci)';
  }
  if (!findChromium()) return 'no Chromium found (scripts/setup installs Debian\'s chromium; or set CHROMIUM)';
  return null;
}

// The page draws /input/NAME, a file that node put there: one browser serves many files.
// SvecError and friends are re-thrown as plain Errors so that their message reaches node.
const PAGE = `<!doctype html><meta charset="utf-8"><script type="module">
import { decode, SubvecRenderer } from '/subvec-viewer.js';
window.draw = async (url, options) => {
  let renderer;
  try {
    const response = await fetch(url);
    // decode() names the file in its messages as node was given it
    const image = decode(new Uint8Array(await response.arrayBuffer()), options.name);
    const w = options.window ?? { x0: 0, y0: 0, x1: image.width, y1: image.height };
    const ww = w.x1 - w.x0, wh = w.y1 - w.y0;
    // As render_size (src/render/renderer.cpp) rounds the output size.
    const width = Math.max(1, Math.round(options.width ?? ww));
    const height = Math.max(1, Math.round(width * wh / ww));
    const canvas = document.createElement('canvas');
    canvas.width = width;
    canvas.height = height;
    renderer = new SubvecRenderer(canvas);
    renderer.setImage(image, options.level ?? 0);
    renderer.setView(options.window ?? null);
    renderer.render();
    // Read in the same task as the drawing: the drawing buffer is still there.
    return { png: canvas.toDataURL('image/png'), stats: { ...renderer.stats }, width, height };
  } catch (e) {
    throw new Error(e && e.message ? e.message : String(e));
  } finally {
    renderer?.dispose();
  }
};
window.ready = true;
</script>`;

// Static files only: the page, the bundle, the inputs node put there and web/viewer's files (the
// demo), on 127.0.0.1 (module scripts do not load from file://).
function startServer(state) {
  const server = createServer((req, res) => {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    let body = null;
    let type = 'application/octet-stream';
    const headers = {};
    if (path === '/') {
      body = PAGE;
      type = 'text/html';
    } else if (path === '/csp') {
      // A page whose Content-Security-Policy does not allow WebAssembly (viewer-element.mjs).
      body = '<!doctype html><meta charset="utf-8"><title>csp</title>';
      type = 'text/html';
      headers['Content-Security-Policy'] = "script-src 'self'";
    } else if (path === '/subvec-viewer.js' && existsSync(state.bundle)) {
      body = readFileSync(state.bundle);
      type = 'text/javascript';
    } else if (path.startsWith('/input/') && state.files.has(path.slice(7))) {
      body = state.files.get(path.slice(7));
    } else if (path.startsWith('/viewer/')) {
      // web/viewer as it is (the demo page's test)
      const file = resolve(viewerDir, '.' + path.slice('/viewer'.length));
      if (file.startsWith(viewerDir + '/') && existsSync(file) && statSync(file).isFile()) {
        body = readFileSync(file);
        type = TYPES[extname(file)] || type;
      }
    }
    if (body === null) res.writeHead(404).end();
    else res.writeHead(200, { 'Content-Type': type, 'Cache-Control': 'no-store', ...headers }).end(body);
  });
  return new Promise((ok) => server.listen(0, '127.0.0.1', () => ok(server)));
}

function withTimeout(promise, what) {
  let timer;
  const timeout = new Promise((_, reject) => {
    timer = setTimeout(() => reject(new Error(`${what} took more than ${TIMEOUT_MS / 1000} s`)), TIMEOUT_MS);
  });
  return Promise.race([promise, timeout]).finally(() => clearTimeout(timer));
}

// The message of an error thrown in the page, without playwright's prefix and stack.
export const pageMessage = (e) =>
  String(e.message).split('\n')[0].replace(/^page\.evaluate: (Error: )?/, '');

// Starts Chromium and the server once. render(bytes, name, { width, window, level }) resolves with
// { png (Buffer), stats, width, height }; put(bytes, name) serves a file for the page's own use
// (page, errors: its uncaught exceptions; origin: the server's, which also serves web/viewer/ as
// /viewer/); close() ends both. Throws Skip when the viewer cannot run.
// `module` may name another build of the viewer.
export async function openViewer({ module = bundle } = {}) {
  const why = missing();
  if (why) throw new Skip(why);
  if (!existsSync(module)) throw new Error(`${module} is missing (run: cd web && npm run build:viewer)`);
  const state = { bundle: module, files: new Map() };
  const server = await startServer(state);
  let browser;
  try {
    browser = await launch(findChromium());
    const page = await browser.newPage({ deviceScaleFactor: 1 });
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    await page.goto(`http://127.0.0.1:${server.address().port}/`, { timeout: TIMEOUT_MS });
    await page.waitForFunction(() => window.ready, null, { timeout: TIMEOUT_MS }).catch(() => {
      throw new Error(`the viewer did not load in the page: ${errors.join('; ') || 'timeout'}`);
    });
    // Serves bytes as the current input; its URL on the page.
    const put = (bytes, name) => {
      state.files.set(basename(name), bytes);
      return '/input/' + encodeURIComponent(basename(name));
    };
    const render = async (bytes, name, options = {}) => {
      const url = put(bytes, name);
      const r = await withTimeout(page.evaluate(([u, o]) => window.draw(u, o), [url, { name, ...options }]),
        'the viewer');
      return { ...r, png: Buffer.from(r.png.slice(r.png.indexOf(',') + 1), 'base64') };
    };
    const close = async () => {
      await browser.close();
      server.close();
    };
    return { render, put, close, page, errors, origin: `http://127.0.0.1:${server.address().port}` };
  } catch (e) {
    if (browser) await browser.close();
    server.close();
    throw e;
  }
}

// "X0,Y0,X1,Y1" as { x0, y0, x1, y1 }, or null when it is not four finite numbers with x0 < x1,
// y0 < y1.
export function parseWindow(text) {
  const v = String(text).split(',').map(Number);
  if (v.length !== 4 || !v.every(Number.isFinite) || !(v[0] < v[2] && v[1] < v[3])) return null;
  return { x0: v[0], y0: v[1], x1: v[2], y1: v[3] };
}

const USAGE = 'usage: viewer-render IN.svec OUT.png [--width W] [--window X0,Y0,X1,Y1] [--level L]';

async function main(argv) {
  const args = [];
  const options = {};
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--width' || a === '--level') {
      const n = Number(argv[++i]);
      const ok = Number.isInteger(n) && (a === '--width' ? n >= 1 && n <= 16384 : n >= 0);
      if (!ok) {
        console.error(`viewer-render: ${a} wants ${a === '--width' ? 'an integer 1 to 16384' : 'an integer >= 0'}, not '${argv[i] ?? ''}'`);
        return 2;
      }
      options[a.slice(2)] = n;
    } else if (a === '--window') {
      options.window = parseWindow(argv[++i]);
      if (!options.window) {
        console.error(`viewer-render: --window wants X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1, not '${argv[i] ?? ''}'`);
        return 2;
      }
    } else if (a === '-h' || a === '--help' || a.startsWith('-')) {
      console.error(USAGE);
      return 2;
    } else {
      args.push(a);
    }
  }
  if (args.length !== 2) {
    console.error(USAGE);
    return 2;
  }
  const [input, output] = args;
  let bytes;
  try {
    bytes = readFileSync(input);
  } catch (e) {
    console.error(`viewer-render: cannot read ${input}: ${e.code || e.message}`);
    return 1;
  }
  let viewer;
  try {
    viewer = await openViewer();
  } catch (e) {
    console.error(`viewer-render: ${e instanceof Skip ? 'skipped: ' : ''}${e.message.split('\n')[0]}`);
    return e instanceof Skip ? 77 : 1;
  }
  let png;
  try {
    png = (await viewer.render(bytes, input, options)).png;
  } catch (e) {
    const message = pageMessage(e);
    console.error(`viewer-render: ${message.startsWith(input + ': ') ? '' : input + ': '}${message}`);
    return 1;
  } finally {
    await viewer.close();
  }
  try {
    // Written whole or not at all, as subvec writes its outputs.
    writeFileSync(output + '.tmp', png);
    renameSync(output + '.tmp', output);
  } catch (e) {
    console.error(`viewer-render: cannot write ${output}: ${e.code || e.message}`);
    return 1;
  }
  return 0;
}

if (import.meta.url === pathToFileURL(process.argv[1]).href) {
  // A hung browser must not keep the process alive past the timeout.
  const watchdog = setTimeout(() => {
    console.error(`viewer-render: no result within ${(TIMEOUT_MS + 30000) / 1000} s`);
    process.exit(1);
  }, TIMEOUT_MS + 30000);
  watchdog.unref();
  process.exitCode = await main(process.argv.slice(2));
}
