// Rasterizes page 1 of a PDF with PDF.js (pdfjs-dist, Firefox's PDF renderer) in headless Chromium:
// PDF.js's own canvas renderer, as its viewer draws a page at zoom S with device scale factor 1.
//
//   node web/tests/pdfjs-render.mjs IN.pdf OUT.png [--scale S]      (scripts/pdfjs-render wraps it)
//
// The PNG is exactly PDF.js's canvas: page size x S pixels, floored as its viewer sizes the canvas,
// on the opaque white background it fills first. Exit 0: written; 1: the PDF could not be drawn
// (missing, not a PDF, timeout); 2: usage; 77: no Chromium or no web/node_modules, so a ctest can
// skip. Errors are one line on stderr. Also a module: openPdfjs() for tests that draw many PDFs.
import { createServer } from 'node:http';
import { readFileSync, writeFileSync, existsSync, renameSync } from 'node:fs';
import { join, dirname, resolve, extname } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { findChromium, launch } from './harness.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const pdfjsDir = join(here, '..', 'node_modules', 'pdfjs-dist');
const TIMEOUT_MS = 120000;

export class Skip extends Error {}

// Why PDF.js cannot run here, or null.
export function missing() {
  const playwright = join(here, '..', 'node_modules', 'playwright-core');
  if (!existsSync(join(pdfjsDir, 'build', 'pdf.mjs')) || !existsSync(playwright)) {
    return 'web/node_modules (pdfjs-dist, playwright-core) is missing (run: cd web && npm ci)';
  }
  if (!findChromium()) return 'no Chromium found (scripts/setup installs Debian\'s chromium; or set CHROMIUM)';
  return null;
}

// The page draws what /doc.pdf is at the moment, so one browser and server serve many PDFs.
const PAGE = `<!doctype html><meta charset="utf-8"><script type="module">
import * as pdfjs from '/pdfjs/build/pdf.mjs';
pdfjs.GlobalWorkerOptions.workerSrc = '/pdfjs/build/pdf.worker.mjs';
window.draw = async (scale) => {
  const task = pdfjs.getDocument('/doc.pdf');
  try {
    let doc;
    try {
      doc = await task.promise;
    } catch (e) {
      // PDF.js's exceptions do not cross into node with their message.
      throw new Error(\`\${e.name}: \${e.message}\`);
    }
    const page = await doc.getPage(1);
    const viewport = page.getViewport({ scale });
    // The viewer floors the canvas size (pdf_page_view.js with outputScale 1).
    const canvas = document.createElement('canvas');
    canvas.width = Math.floor(viewport.width);
    canvas.height = Math.floor(viewport.height);
    await page.render({ canvas, canvasContext: canvas.getContext('2d'), viewport }).promise;
    return canvas.toDataURL('image/png');
  } finally {
    await task.destroy();
  }
};
window.ready = true;
</script>`;

const TYPES = { '.mjs': 'text/javascript', '.wasm': 'application/wasm' };

// Static files only: the page, pdfjs-dist's files and the current PDF, on 127.0.0.1 (module scripts
// and the worker do not load from file://).
function startServer(state) {
  const server = createServer((req, res) => {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    let body = null;
    let type = 'application/octet-stream';
    if (path === '/') {
      body = PAGE;
      type = 'text/html';
    } else if (path === '/doc.pdf') {
      body = state.pdf;
      type = 'application/pdf';
    } else if (path.startsWith('/pdfjs/')) {
      const file = resolve(pdfjsDir, '.' + path.slice('/pdfjs'.length));
      if (file.startsWith(pdfjsDir + '/') && existsSync(file)) {
        body = readFileSync(file);
        type = TYPES[extname(file)] || type;
      }
    }
    if (body === null) {
      res.writeHead(404).end();
    } else {
      res.writeHead(200, { 'Content-Type': type, 'Cache-Control': 'no-store' }).end(body);
    }
  });
  return new Promise((ok) => server.listen(0, '127.0.0.1', () => ok(server)));
}

function withTimeout(promise, what) {
  let timer;
  const timeout = new Promise((_, reject) => {
    const error = new Error(`${what} took more than ${TIMEOUT_MS / 1000} s`);
    timer = setTimeout(() => reject(error), TIMEOUT_MS);
  });
  return Promise.race([promise, timeout]).finally(() => clearTimeout(timer));
}

// Starts Chromium and the server once; render(pdfBytes, scale) resolves with PNG bytes, close()
// ends both. Throws Skip when PDF.js cannot run here.
export async function openPdfjs() {
  const why = missing();
  if (why) throw new Skip(why);
  const state = { pdf: Buffer.alloc(0) };
  const server = await startServer(state);
  let browser;
  try {
    browser = await launch(findChromium());
    const page = await browser.newPage({ deviceScaleFactor: 1 });
    const errors = [];
    page.on('pageerror', (e) => errors.push(String(e)));
    await page.goto(`http://127.0.0.1:${server.address().port}/`, { timeout: TIMEOUT_MS });
    await page.waitForFunction(() => window.ready, null, { timeout: TIMEOUT_MS }).catch(() => {
      throw new Error(`PDF.js did not load in the page: ${errors.join('; ') || 'timeout'}`);
    });
    const render = async (pdf, scale = 1) => {
      state.pdf = pdf;
      const url = await withTimeout(page.evaluate((s) => window.draw(s), scale), 'PDF.js rendering');
      return Buffer.from(url.slice(url.indexOf(',') + 1), 'base64');
    };
    const close = async () => {
      await browser.close();
      server.close();
    };
    return { render, close };
  } catch (e) {
    if (browser) await browser.close();
    server.close();
    throw e;
  }
}

async function main(argv) {
  const args = [];
  let scale = 1;
  for (let i = 0; i < argv.length; i++) {
    if (argv[i] === '--scale') scale = Number(argv[++i]);
    else if (argv[i] === '-h' || argv[i] === '--help') args.length = 99;
    else args.push(argv[i]);
  }
  if (args.length !== 2 || !(scale > 0 && scale <= 64)) {
    console.error('usage: pdfjs-render IN.pdf OUT.png [--scale S]   (default 1: one point, one pixel)');
    return 2;
  }
  const [input, output] = args;
  let pdf;
  try {
    pdf = readFileSync(input);
  } catch (e) {
    console.error(`pdfjs-render: cannot read ${input}: ${e.code || e.message}`);
    return 1;
  }
  let pdfjs;
  try {
    pdfjs = await openPdfjs();
  } catch (e) {
    console.error(`pdfjs-render: ${e instanceof Skip ? 'skipped: ' : ''}${e.message.split('\n')[0]}`);
    return e instanceof Skip ? 77 : 1;
  }
  let png;
  try {
    png = await pdfjs.render(pdf, scale);
  } catch (e) {
    const why = e.message.split('\n')[0].replace(/^page\.evaluate: (Error: )?/, '');
    console.error(`pdfjs-render: ${input}: ${why}`);
    return 1;
  } finally {
    await pdfjs.close();
  }
  try {
    // Written whole or not at all, as subvec writes its outputs.
    writeFileSync(output + '.tmp', png);
    renameSync(output + '.tmp', output);
  } catch (e) {
    console.error(`pdfjs-render: cannot write ${output}: ${e.code || e.message}`);
    return 1;
  }
  return 0;
}

if (import.meta.url === pathToFileURL(process.argv[1]).href) {
  // A hung browser must not keep the process alive past the timeout.
  const watchdog = setTimeout(() => {
    console.error(`pdfjs-render: no result within ${(TIMEOUT_MS + 30000) / 1000} s`);
    process.exit(1);
  }, TIMEOUT_MS + 30000);
  watchdog.unref();
  process.exitCode = await main(process.argv.slice(2));
}
