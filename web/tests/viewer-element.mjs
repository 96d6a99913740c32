// <subvec-image> in headless Chromium (run by viewer-compare.mjs, in its page and browser): layout
// like an <img>, the same pixels as the module API, contain-fit and centring, setView, a lost WebGL
// context restored, wheel zoom with `interactive` only, and errors as events (bad file, missing
// file, bad level, bad window, a page that forbids WebAssembly) with nothing thrown to the page;
// then the demo page.
import { execFileSync } from 'node:child_process';
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

const rocket = fileURLToPath(new URL('../viewer/demo/rocket.svec', import.meta.url));

// Page helpers: add an element and wait for its first frame or its error; wait for the next
// event of a kind. Each frame's canvas is captured in the render event (same task as drawing).
function install() {
  const until = (el, types) => new Promise((ok, fail) => {
    const timer = setTimeout(() => fail(new Error(`no ${types.join(' or ')} event within 20 s`)), 20000);
    for (const type of types) {
      el.addEventListener(type, (e) => {
        clearTimeout(timer);
        ok({ type, detail: e.detail });
      }, { once: true });
    }
  });
  const state = (el) => {
    const r = el.getBoundingClientRect();
    const canvas = el.shadowRoot.querySelector('canvas');
    return { width: r.width, height: r.height, canvas: [canvas.width, canvas.height],
      error: el.error, view: el.view, png: el.lastPng ?? null };
  };
  window.until = until;
  window.state = state;
  window.add = async (attrs, style = '') => {
    const el = document.createElement('subvec-image');
    el.addEventListener('render', () => {
      el.lastPng = el.shadowRoot.querySelector('canvas').toDataURL('image/png');
    });
    el.style.cssText = style;
    const done = until(el, ['render', 'error']);
    const load = until(el, ['load', 'error']);
    for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, v);
    document.body.append(el);
    window.el = el;
    const first = await load;
    const end = first.type === 'error' ? first : await done;
    return { load: first, end: end.type, ...state(el) };
  };
  // Changes the element with f (a function's source) and waits for the event.
  window.change = async (f, types = ['render', 'error']) => {
    const next = until(window.el, types);
    (0, eval)(f)(window.el);
    const e = await next;
    return { type: e.type, detail: e.detail, ...state(window.el) };
  };
  // The alpha of the last frame at canvas pixels.
  window.alphas = async (points) => {
    const img = new Image();
    img.src = window.el.lastPng;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    return points.map(([x, y]) => g.getImageData(x, y, 1, 1).data[3]);
  };
  document.body.style.margin = '0';
}

const png = (dataUrl) => Buffer.from(dataUrl.slice(dataUrl.indexOf(',') + 1), 'base64');

export async function checkElement(viewer, binary, dir) {
  const { page, errors } = viewer;
  let passed = 0;
  let failed = 0;
  const check = (ok, what) => {
    ok ? passed++ : failed++;
    console.log(`${ok ? 'ok  ' : 'FAIL'} element: ${what}`);
  };
  // MAE of a frame of the element against the module API's drawing of the same view.
  const mae = async (frame, options, stem) => {
    const a = join(dir, stem + '-element.png');
    const b = join(dir, stem + '-module.png');
    writeFileSync(a, png(frame));
    writeFileSync(b, (await viewer.render(readFileSync(rocket), 'rocket.svec', options)).png);
    return JSON.parse(execFileSync(binary, ['compare', a, b, '--json'], { encoding: 'utf8' })).mae_mean;
  };
  const run = async (what, body) => {
    try {
      await body();
    } catch (e) {
      check(false, `${what}: ${String(e.message).split('\n')[0]}`);
    }
  };
  const good = viewer.put(readFileSync(rocket), 'rocket.svec');
  const bad = viewer.put(Buffer.from('this is not a vector image'), 'bad.svec');
  await page.evaluate(install);

  await run('natural size', async () => {
    const s = await page.evaluate((src) => window.add({ src }), good);
    check(s.load.type === 'load' && s.load.detail.width === 384 && s.load.detail.levels === 3,
      `load event with the size and levels (${JSON.stringify(s.load.detail)})`);
    check(s.width === 384 && s.height === 256 && s.canvas.join() === '384,256',
      `no CSS size: the image's own, 384 x 256 (got ${s.width} x ${s.height}, canvas ${s.canvas})`);
    const m = await mae(s.png, {}, 'natural');
    check(m <= 0.01, `the same pixels as SubvecRenderer at 1x (MAE ${m.toFixed(3)})`);
  });
  await run('css width', async () => {
    const s = await page.evaluate(() => window.change('(el) => { el.style.width = "192px"; }'));
    check(s.width === 192 && s.height === 128 && s.canvas.join() === '192,128',
      `CSS width 192px: height 128 from the aspect (got ${s.width} x ${s.height}, canvas ${s.canvas})`);
    const t = await page.evaluate(() => window.change('(el) => { el.style.width = ""; el.style.height = "64px"; }'));
    check(t.width === 96 && t.height === 64, `CSS height 64px: width 96 (got ${t.width} x ${t.height})`);
  });
  await run('contain', async () => {
    await page.evaluate(() => window.change('(el) => { el.style.width = "300px"; el.style.height = "100px"; }'));
    // The image fills 150 x 100 in the middle; the sides are transparent.
    const a = await page.evaluate(() => window.alphas([[20, 50], [80, 50], [150, 50], [220, 50], [280, 50]]));
    check(a.join() === '0,255,255,255,0', `300 x 100: the image fitted and centred (alpha ${a})`);
  });
  await run('setView', async () => {
    const w = { x0: 100, y0: 60, x1: 196, y1: 124 };
    const s = await page.evaluate((v) =>
      window.change(`(el) => { el.style.width = el.style.height = ""; el.setView(${JSON.stringify(v)}); }`), w);
    const m = await mae(s.png, { width: 384, window: w }, 'view');
    check(JSON.stringify(s.view) === JSON.stringify(w) && m <= 0.01,
      `setView draws that window as SubvecRenderer does (view ${JSON.stringify(s.view)}, MAE ${m.toFixed(3)})`);
    const r = await page.evaluate(() => window.change('(el) => el.setView({ x0: 5, y0: 0, x1: 5, y1: 9 })', ['error']));
    check(r.type === 'error' && r.detail.message && JSON.stringify(r.view) === JSON.stringify(w),
      `an empty window: error event '${r.detail.message}', the view kept`);
  });
  await run('context loss', async () => {
    // A lost WebGL context, restored: the element draws again by itself, the same pixels.
    const s = await page.evaluate(() => window.change(`(el) => {
      const lose = el.shadowRoot.querySelector('canvas').getContext('webgl2').getExtension('WEBGL_lose_context');
      lose.loseContext();
      setTimeout(() => lose.restoreContext(), 50);
    }`));
    const m = await mae(s.png, { width: 384, window: { x0: 100, y0: 60, x1: 196, y1: 124 } }, 'restored');
    check(s.type === 'render' && m <= 0.01, `a lost context restored: drawn again (MAE ${m.toFixed(3)})`);
  });
  await run('wheel', async () => {
    await page.evaluate(() => window.change('(el) => el.setView(null)'));
    const r = await page.evaluate(() => window.el.getBoundingClientRect().toJSON());
    await page.mouse.move(r.x + r.width / 2, r.y + r.height / 2);
    await page.mouse.wheel(0, -500);
    await page.waitForTimeout(300);
    const before = await page.evaluate(() => window.state(window.el).view);
    check(before === null, `no zoom without 'interactive' (view ${JSON.stringify(before)})`);
    await page.evaluate(() => { window.el.interactive = true; });
    const next = page.evaluate(() => window.until(window.el, ['viewchange']));
    await page.mouse.wheel(0, -500);
    const e = await next;
    const v = e.detail;
    const centred = v && Math.abs((v.x0 + v.x1) / 2 - 192) < 1e-6 && Math.abs((v.y0 + v.y1) / 2 - 128) < 1e-6;
    check(v && v.x1 - v.x0 < 384 * 0.9 && centred,
      `interactive: the wheel zooms in about the pointer (view ${JSON.stringify(v)})`);
  });
  await run('errors', async () => {
    const lvl = await page.evaluate(() => window.change('(el) => { el.level = 99; }', ['error']));
    check(lvl.type === 'error' && /level/i.test(lvl.detail.message) && lvl.error === lvl.detail.message,
      `level 99 of 3: error event and property '${lvl.error}'`);
    const back = await page.evaluate(() => window.change('(el) => { el.level = 1; }'));
    check(back.type === 'render' && back.error === null, `level 1: drawn again, error cleared (${back.error})`);
    for (const [src, what] of [[bad, 'a file that is no .svec'], ['/input/missing.svec', 'a missing file']]) {
      const s = await page.evaluate((u) => window.add({ src: u }), src);
      check(s.load.type === 'error' && s.load.detail.message && s.error === s.load.detail.message &&
        !s.load.detail.message.includes('\n'), `${what}: error event '${s.load.detail.message}'`);
    }
    const s = await page.evaluate((u) => window.change(`(el) => { el.src = '${u}'; }`, ['load']), good);
    check(s.type === 'load' && s.error === null, `a good src after a bad one loads (error ${s.error})`);
  });
  check(errors.length === 0, `nothing thrown to the page${errors.length ? ': ' + errors.join('; ') : ''}`);
  await run('no WebAssembly', () => checkNoWasm(viewer, check));
  await run('demo', () => checkDemo(viewer, check));
  return { passed, failed };
}

// A page whose Content-Security-Policy lacks 'wasm-unsafe-eval': the element reports an error
// event that names WebAssembly, and nothing is thrown to the page.
async function checkNoWasm(viewer, check) {
  const page = await viewer.page.context().browser().newPage({ deviceScaleFactor: 1 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  try {
    await page.goto(`${viewer.origin}/csp`);
    const detail = await page.evaluate(async () => {
      await import('/subvec-viewer.js');
      const el = document.createElement('subvec-image');
      const event = new Promise((ok) => {
        for (const type of ['load', 'error']) el.addEventListener(type, (e) => ok({ type, message: e.detail?.message ?? '' }));
      });
      el.src = '/viewer/demo/rocket.svec';
      document.body.append(el);
      return event;
    });
    check(detail.type === 'error' && /rocket\.svec: WebAssembly is not available here: /.test(detail.message) && !detail.message.includes('\n'),
      `a page that forbids WebAssembly: error event '${detail.message}'`);
    check(errors.length === 0, `no WebAssembly: nothing thrown to the page${errors.length ? ': ' + errors.join('; ') : ''}`);
  } finally {
    await page.close();
  }
}

// The demo page (web/viewer/demo) as a static server serves it: the photograph shown, the zoom
// buttons, a dropped bad file's error in the page, a dropped good file shown.
async function checkDemo(viewer, check) {
  const page = await viewer.page.context().browser().newPage({ deviceScaleFactor: 1 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  try {
    await page.goto(`${viewer.origin}/viewer/demo/index.html`);
    const status = () => page.textContent('#status');
    await page.waitForFunction(() => /drawn at depth/.test(document.getElementById('status').textContent),
      null, { timeout: 20000 });
    const levels = await page.$$eval('#level option', (o) => o.length);
    check(/rocket\.svec: 384 × 256 pixels, 3 levels/.test(await status()) && levels === 3,
      `demo: the photograph shown ('${await status()}', ${levels} levels to choose)`);
    await page.click('#zoom-in');
    await page.click('#zoom-in');
    const view = await page.evaluate(() => document.getElementById('image').view);
    check(view && Math.abs(view.x1 - view.x0 - 192) < 1e-9 && await page.textContent('#zoom-value') === '2.0×',
      `demo: two zoom-in clicks zoom 2x (view ${JSON.stringify(view)})`);
    const drop = (name, text) => page.evaluate(([n, t]) => {
      const data = new DataTransfer();
      data.items.add(new File([t], n));
      document.getElementById('stage').dispatchEvent(
        new DragEvent('drop', { dataTransfer: data, bubbles: true, cancelable: true }));
    }, [name, text]);
    await drop('broken.svec', '{"format": "subvec", "version": 1}');
    await page.waitForSelector('#error.shown', { timeout: 20000 });
    const error = await page.textContent('#error');
    check(error.startsWith('broken.svec: ') && !error.includes('blob:'), `demo: a dropped bad file: '${error}'`);
    const disk = fileURLToPath(new URL('../../examples/01-disk.svec.json', import.meta.url));
    await drop('01-disk.svec.json', readFileSync(disk, 'utf8'));
    await page.waitForFunction(() => /^01-disk/.test(document.getElementById('status').textContent), null,
      { timeout: 20000 });
    const hidden = await page.$eval('#error', (e) => getComputedStyle(e).display === 'none');
    check(hidden && /96 × 96 pixels/.test(await status()), `demo: a dropped .svec.json shown ('${await status()}')`);
    check(errors.length === 0, `demo: nothing thrown to the page${errors.length ? ': ' + errors.join('; ') : ''}`);
  } finally {
    await page.close();
  }
}
