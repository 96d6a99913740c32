// End-to-end test of `subvec serve` in headless Chromium (playwright-core, software WebGL):
// open a served example, drag a feature, change a color, undo and redo, switch levels, save, and
// two tabs at once; filter a two-level image through its pyramid. Asserts on canvas pixels and on
// the saved file.
//
//   node web/tests/e2e.mjs BUILD/bin/subvec [SCREENSHOT.png]
//
// Exit status 0: all passed; 1: a check failed; 77: skipped (no Chromium or no node_modules),
// with the reason on stdout. The last line is "N passed, M failed".
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, writeFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { requireBrowser, launch, serve, stop, openEditor, idle, pixel, client, check, finish, diff } from './harness.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');
const binary = process.argv[2];
const screenshot = process.argv[3];

const chromium = requireBrowser('e2e.mjs', binary);


// A two-level copy of the disk example: level 1 is level 0 with its channels swapped (r, g, b) ->
// (b, g, r), so switching levels changes the colors while the geometry stays.
const dir = mkdtempSync(join(tmpdir(), 'subvec-e2e-'));
const disk = JSON.parse(readFileSync(join(root, 'examples', '01-disk.svec.json'), 'utf8'));
const level1 = JSON.parse(JSON.stringify(disk.levels[0]));
level1.colors = level1.colors.map(([r, g, b]) => [b, g, r]);
disk.levels.push(level1);
const input = join(dir, 'disk.svec.json');
writeFileSync(input, JSON.stringify(disk));
const saved = join(dir, 'saved.svec.json');

const server = await serve(binary, [input, '-o', saved]);
const browser = await launch(chromium);
try {
  const { page, errors } = await openEditor(browser, server.url);

  // The disk: centre (48, 48), a closed tear of control radius 28 around it.
  const inside0 = await pixel(page, 48, 48);
  const probe = [80, 48];  // outside the disk, inside the dragged-to outline
  const before = await pixel(page, ...probe);
  const corner = await pixel(page, 3, 3);
  check('the disk and its surroundings differ', diff(inside0, before) > 40, `${inside0} vs ${before}`);

  // Drag the feature at its right-hand side 10 px to the right (drag tool, feature picking).
  await page.keyboard.press('d');
  const [sx, sy] = await client(page, 76, 48);
  await page.mouse.move(sx, sy);
  await page.mouse.down();
  for (let i = 1; i <= 10; ++i) {
    const [x, y] = await client(page, 76 + i, 48);
    await page.mouse.move(x, y);
    await page.waitForTimeout(20);
  }
  await page.mouse.up();
  await idle(page);
  const afterDrag = await pixel(page, ...probe);
  // Before: the bluish background; after: the disk's red (darker near its outline).
  const reddish = (p) => p[0] > p[1] + 50 && p[0] > p[2] + 50;
  check('drag: the feature moved over the probe pixel', !reddish(before) && reddish(afterDrag) && diff(afterDrag, before) > 40,
    `${before} -> ${afterDrag} (disk ${inside0})`);
  const cornerAfter = await pixel(page, 3, 3);
  check('drag: the image corner stays', diff(cornerAfter, corner) < 3, `${corner} -> ${cornerAfter}`);

  // Color: BLEND the inside of the disk to pure green, amount 1, the feature's side grown by 40 px.
  const centreBefore = await pixel(page, 48, 48);
  const outsideBefore = await pixel(page, 8, 48);
  await page.keyboard.press('c');
  await page.locator('input[name=pick][value=feature]').check();
  await page.locator('#color').fill('#00ff00');
  await page.evaluate(() => {
    for (const [id, v] of [['amount', '1'], ['radius', '40']]) {
      const el = document.getElementById(id);
      el.value = v;
      el.dispatchEvent(new Event('input'));
    }
  });
  const [cx, cy] = await client(page, 50, 46);
  await page.mouse.click(cx, cy);
  await idle(page);
  const green = await pixel(page, 48, 48);
  check('color: the disk turned green', green[1] > 200 && green[0] < 60 && green[2] < 60, `${green}`);
  const outside = await pixel(page, 8, 48);
  check('color: outside the tear is unchanged', diff(outside, outsideBefore) < 2, `${outside} vs ${outsideBefore}`);

  // Undo (the color) and redo.
  await page.keyboard.press('Control+z');
  await idle(page);
  const undone = await pixel(page, 48, 48);
  check('undo: the disk has its color back', diff(undone, centreBefore) < 2, `${undone} vs ${centreBefore}`);
  await page.keyboard.press('Control+Shift+z');
  await idle(page);
  const redone = await pixel(page, 48, 48);
  check('redo: green again', diff(redone, green) < 3, `${redone} vs ${green}`);

  // Levels: level 1 has the original colors with r and b swapped.
  await page.keyboard.press(']');
  await page.waitForFunction(() => window.subvec.state.level === 1);
  await idle(page);
  await page.waitForTimeout(200);
  const level1px = await pixel(page, 48, 48);
  const swapped = [inside0[2], inside0[1], inside0[0]];
  check('level 1: the other level is drawn', diff(level1px, swapped) < 8, `${level1px} vs ${swapped}`);
  await page.keyboard.press('[');
  await page.waitForFunction(() => window.subvec.state.level === 0);
  await idle(page);
  await page.waitForTimeout(200);
  check('level 0 again: green', diff(await pixel(page, 48, 48), green) < 3);

  // Save in place (Ctrl+S writes the -o file) and check the file.
  await page.keyboard.press('Control+s');
  await page.waitForFunction(() => /saved/.test(document.getElementById('status').textContent));
  const file = JSON.parse(readFileSync(saved, 'utf8'));
  const l0 = file.levels[0];
  check('saved: two levels', file.levels.length === 2);
  check('saved: the dragged feature vertex moved right', l0.vertices[9][0] > 83 && Math.abs(l0.vertices[9][1] - 48) < 1,
    `vertex 9 at ${l0.vertices[9]}`);
  const centreColor = l0.colors[l0.triangle_colors[l0.triangles.findIndex((t) => t.includes(0))][0]];
  check('saved: the inside is green', centreColor[1] > 250 && centreColor[0] < 1 && centreColor[2] < 1, `${centreColor}`);
  check('saved: level 1 untouched', file.levels[1].colors.length === level1.colors.length &&
    file.levels[1].colors.every((c, i) => diff(c, level1.colors[i]) < 1e-3));

  // Download the .svec (binary, magic "SUBVEC").
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('.downloads a[data-format=svec]')]);
  const got = join(dir, 'download.svec');
  await download.saveAs(got);
  check('download: a binary .svec', readFileSync(got).subarray(0, 6).toString() === 'SUBVEC');

  if (screenshot) {
    await page.evaluate(() => { document.getElementById('show-features').click(); });
    await page.waitForTimeout(100);
    await page.screenshot({ path: screenshot });
  }

  // Two tabs: an edit in the second tab shows in the first (poll), and an edit the first tab
  // sends from a stale version is refused (409) and reloads instead of overwriting.
  const second = await openEditor(browser, server.url);
  await second.page.keyboard.press('c');
  await second.page.locator('#color').fill('#ff0000');
  await second.page.evaluate(() => {
    for (const [id, v] of [['amount', '1'], ['radius', '40']]) {
      const el = document.getElementById(id);
      el.value = v;
      el.dispatchEvent(new Event('input'));
    }
  });
  const [tx, ty] = await client(second.page, 50, 46);
  await second.page.mouse.click(tx, ty);
  await idle(second.page);
  const red2 = await pixel(second.page, 48, 48);
  check('two tabs: the second tab colored the disk red', red2[0] > 200 && red2[1] < 60, `${red2}`);
  await page.waitForFunction(() => window.subvec.pixelAt(48, 48)[0] > 200, null, { timeout: 5000 })
    .then(() => check('two tabs: the first tab shows the change', true))
    .catch(async () => check('two tabs: the first tab shows the change', false, `${await pixel(page, 48, 48)}`));
  const stale = await page.evaluate(async () => {
    const r = await fetch('/api/color', {
      method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ session: window.subvec.state.session, version: 1, level: 0, at: [48, 48], color: [0, 0, 255] }),
    });
    return { status: r.status, body: await r.json() };
  });
  check('two tabs: a stale version is refused with 409', stale.status === 409 && /another tab/.test(stale.body.error), JSON.stringify(stale));

  // Stylize: a stroke along the disk's outline (its one feature) darkens the outline.
  const rim = await page.evaluate(async () => {
    const c = await (await fetch('/api/control?level=0')).json();
    // The limit curve at the middle of the chain (away from the stroke's tapered ends): the
    // uniform cubic B-spline at a vertex is (previous + 4 vertex + next) / 6.
    const chain = c.features[0];
    const i = Math.floor(chain.length / 2);
    const p = (k) => [c.positions[2 * chain[k]], c.positions[2 * chain[k] + 1]];
    const [a, b, d] = [p(i - 1), p(i), p(i + 1)];
    return [(a[0] + 4 * b[0] + d[0]) / 6, (a[1] + 4 * b[1] + d[1]) / 6];
  });
  const rimBefore = await pixel(page, ...rim);
  await page.evaluate(() => { document.getElementById('threshold').value = '0'; });
  await page.keyboard.press('y');
  await idle(page);
  await page.waitForTimeout(300);
  const rimAfter = await pixel(page, ...rim);
  check('stylize: a dark stroke on the outline', Math.max(...rimAfter.slice(0, 3)) < 60 && diff(rimAfter, rimBefore) > 60,
    `${rimBefore} -> ${rimAfter} at ${rim}`);

  // Errors answer as JSON with a status.
  const bad = await page.evaluate(async () => {
    const r = await fetch('/api/select', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: '{"at": [1]}' });
    return { status: r.status, body: await r.json() };
  });
  check('errors: JSON with status 400', bad.status === 400 && typeof bad.body.error === 'string', JSON.stringify(bad));
  check('no page errors', errors.length === 0 && second.errors.length === 0, errors.concat(second.errors).join('; '));
} catch (e) {
  check('the test ran to its end', false, e && e.stack ? e.stack : String(e));
} finally {
  await browser.close();
  const code = await stop(server);
  check('serve stops cleanly on SIGTERM', code === 0, `exit ${code}: ${server.stderr()}`);
  rmSync(dir, { recursive: true, force: true });
}
// Filter: a two-level vectorization of the rocket (a real pyramid). Releasing the finest band's η
// slider at 0 smooths the colors (pixels away from the features change); η = 1 restores them. 1,500
// control vertices: the kept features' edge profiles (below) are three rings of triangles wide, and
// at 600 vertices (triangles about 17 px across) they covered nearly all of this small image.
{
  const fdir = mkdtempSync(join(tmpdir(), 'subvec-e2e-filter-'));
  const levels = join(fdir, 'rocket.svec');
  try {
    execFileSync(binary, ['vectorize', join(root, 'examples', '04-rocket.png'), '-o', levels, '--vertices', '1500',
      '--levels', '2'], { stdio: 'ignore' });
    const fserver = await serve(binary, [levels]);
    const b = await launch(chromium);
    try {
      const { page, errors } = await openEditor(b, fserver.url);
      const doc = await page.evaluate(async () => (await fetch('/api/document')).json());
      check('filter: the panel is enabled with one slider per band',
        doc.filter.available && doc.filter.bands === 1 && await page.evaluate(() =>
          !document.getElementById('eta-0').disabled && !document.getElementById('filter-color').disabled),
        JSON.stringify(doc.filter));
      // Probe points on a grid, at least 6 px from every feature's control chain.
      const probes = await page.evaluate(async ([w, h]) => {
        const c = await (await fetch('/api/control?level=0')).json();
        const segs = [];
        for (const chain of c.features) {
          for (let k = 0; k + 1 < chain.length; ++k) {
            segs.push([c.positions[2 * chain[k]], c.positions[2 * chain[k] + 1],
              c.positions[2 * chain[k + 1]], c.positions[2 * chain[k + 1] + 1]]);
          }
        }
        const dist = (x, y) => Math.min(...segs.map(([ax, ay, bx, by]) => {
          const dx = bx - ax, dy = by - ay;
          const t = Math.max(0, Math.min(1, ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy || 1)));
          return Math.hypot(x - ax - t * dx, y - ay - t * dy);
        }));
        const out = [];
        for (let y = 4; y < h - 4; y += 6) for (let x = 4; x < w - 4; x += 6) if (dist(x, y) >= 6) out.push([x, y]);
        return out;
      }, [doc.width, doc.height]);
      const sample = () => page.evaluate((pts) => window.subvec.pixelsAt(pts), probes);
      const before = await sample();
      const setEta = (v) => page.evaluate((value) => {
        const el = document.getElementById('eta-0');
        el.value = value;
        el.dispatchEvent(new Event('input'));
        el.dispatchEvent(new Event('change'));  // what releasing the slider fires
      }, v);
      await setEta('0');
      await idle(page);
      const smoothed = await sample();
      const changes = smoothed.map((p, i) => diff(p, before[i]));
      const changed = changes.filter((d) => d >= 4).length;
      // Not all of them: the edge profiles of kept features (their control one-ring whole, the
      // next two rings by 2/3 and 1/3) keep their color detail at every eta (docs/levels.md).
      check('filter: η = 0 changes pixels away from the features',
        probes.length > 50 && changed >= probes.length / 20 && Math.max(...changes) >= 10,
        `${changed} of ${probes.length} probes changed by >= 4, max ${Math.max(...changes)}`);
      const after = await page.evaluate(async () => (await fetch('/api/document')).json());
      check('filter: one undo step, the slider state kept', after.undo === 1 && after.filter.current &&
        after.filter.current.eta[0] === 0, JSON.stringify(after.filter));
      await setEta('1');
      await idle(page);
      const restored = await sample();
      const back = Math.max(...restored.map((p, i) => diff(p, before[i])));
      check('filter: η = 1 restores the image', back <= 1, `max difference ${back}`);
      check('filter: no page errors', errors.length === 0, errors.join('; '));
    } finally {
      await b.close();
      await stop(fserver);
    }
  } catch (e) {
    check('filter: ran to its end', false, e && e.stack ? e.stack : String(e));
  } finally {
    rmSync(fdir, { recursive: true, force: true });
  }
}

// A photograph is vectorized first: the page shows the progress, then the editor.
try {
  const photo = await serve(binary, [join(root, 'examples', '04-rocket.png'), '--vertices', '400']);
  const b = await launch(chromium);
  try {
    const page = await b.newPage({ viewport: { width: 900, height: 600 } });
    await page.goto(photo.url);
    const first = await page.evaluate(async () => (await (await fetch('/api/status')).json()).state);
    check('photograph: vectorizing when the page opens', first === 'vectorizing' || first === 'ready', first);
    let sawProgress = false;
    for (let i = 0; i < 600 && !(await page.evaluate(() => window.subvec && window.subvec.ready)); ++i) {
      sawProgress ||= await page.evaluate(() => !document.getElementById('progress').hidden &&
        /Vectorizing/.test(document.getElementById('progress-text').textContent));
      await page.waitForTimeout(100);
    }
    check('photograph: progress shown in the page', sawProgress || first === 'ready');
    const ready = await page.evaluate(() => window.subvec.ready);
    const doc = ready ? await page.evaluate(async () => (await fetch('/api/document')).json()) : {};
    check('photograph: the editor opens on the vectorized image', ready && doc.width === 384 && doc.levels[0].vertices > 100,
      JSON.stringify(doc));
    const sky = ready ? await pixel(page, 20, 20) : [0, 0, 0];
    check('photograph: drawn', sky[3] === 255 && diff(sky, [32, 33, 36]) > 10, `${sky}`);
  } finally {
    await b.close();
    await stop(photo);
  }
} catch (e) {
  check('photograph: served', false, e && e.stack ? e.stack : String(e));
}
finish();
