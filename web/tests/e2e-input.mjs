// Quick input in the editor page (issue 29, problems 1-6 and 8-11), in headless Chromium with
// software WebGL: the page queues its requests, so quick clicks with every tool make exactly the
// edits they ask for (a click is no drag), quick undos raise no conflict, a drag the mesh refuses
// at its end commits where it last fitted, a press outside the image grabs nothing, the status
// line speaks plainly, and a photograph's SVG download starts within 5 s. Asserts on the
// document's version and history, the status line, canvas pixels and the downloaded file.
//
//   node web/tests/e2e-input.mjs BUILD/bin/subvec
//
// Exit status 0: all passed; 1: a check failed; 77: skipped (no Chromium or no node_modules).
import { existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { check, client, diff, finish, idle, launch, openEditor, pixel, requireBrowser, serve, stop } from './harness.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');
const binary = process.argv[2];

const chromium = requireBrowser('e2e-input.mjs', binary);


// The disk example: a closed tear of radius 28 around (48, 48) in a 96 x 96 image.
const onTear = (degrees) => [48 + 28 * Math.cos((degrees * Math.PI) / 180), 48 + 28 * Math.sin((degrees * Math.PI) / 180)];
const dir = mkdtempSync(join(tmpdir(), 'subvec-e2e-input-'));
const input = join(dir, 'disk.svec.json');
writeFileSync(input, readFileSync(join(root, 'examples', '01-disk.svec.json')));

const server = await serve(binary, [input]);
const browser = await launch(chromium);
try {
  const { page, errors } = await openEditor(browser, server.url);
  const doc = () => page.evaluate(() => ({
    version: window.subvec.state.version,
    undo: window.subvec.state.doc.undo,
    busy: window.subvec.state.busy,
    status: document.getElementById('status').textContent,
    error: document.getElementById('status').classList.contains('error'),
  }));
  // Clicks as fast as the mouse sends them: no wait for the page between them.
  const clicks = async (points) => {
    for (const p of points) {
      const [x, y] = await client(page, ...p);
      await page.mouse.click(x, y);
    }
    await idle(page);
  };
  // Partial redraws (gl.ts) against a full redraw: at each call, the frame the page draws for
  // what changed since the last one must equal a full redraw pixel for pixel.
  const inexact = [];
  let compared = 0;
  const exact = async (label) => {
    const r = await page.evaluate(() => window.subvec.partialFrameErrors());
    compared++;
    if (r.differ > 0) inexact.push(`${label}: ${r.differ} pixels`);
  };
  // Every status line the page shows, for problem 10 (no internal terms).
  await page.evaluate(() => {
    window.statuses = [];
    new MutationObserver(() => window.statuses.push(document.getElementById('status').textContent))
      .observe(document.getElementById('status'), { childList: true, characterData: true, subtree: true });
  });
  const start = await doc();
  const probe = await pixel(page, 80, 48);

  // Problem 1: ten quick clicks 5 degrees apart along the tear, then ten on one spot, with each
  // tool that presses on the image. None of them is an edit; the page stays in step.
  for (const [key, tool] of [['d', 'drag'], ['m', 'move'], ['v', 'select'], ['h', 'pan']]) {
    await page.keyboard.press(key);
    await clicks([...Array.from({ length: 10 }, (_, i) => onTear(-20 + 5 * i)), ...Array(10).fill(onTear(0))]);
    const d = await doc();
    check(`${tool}: 20 quick clicks make no edit`, d.version === start.version && d.undo === 0,
      `version ${start.version} -> ${d.version}, ${d.undo} undo steps, status "${d.status}"`);
    check(`${tool}: the page is in step after them`, d.busy === 0 && !d.error, `busy ${d.busy}, status "${d.status}"`);
  }
  check('the image is unchanged by the clicks', diff(await pixel(page, 80, 48), probe) < 2);

  // Problem 5 (in part): with the color tool, hovering shows the region a click would change;
  // I takes the color under the mouse; a typed color sets the picker.
  await page.keyboard.press('c');
  const [hx, hy] = await client(page, 48, 48);
  await page.mouse.move(hx, hy);
  await page.waitForFunction(() => /^a click here changes the \d+ control colors shown white$/.test(document.getElementById('status').textContent), null, { timeout: 10000 })
    .then(() => check('color: hovering previews the region', true), async () => check('color: hovering previews the region', false, `status "${(await doc()).status}"`));
  await exact('the hover preview');
  await page.keyboard.press('i');
  const picked = await page.evaluate(() => document.getElementById('color').value);
  const under = await pixel(page, 48, 48);
  const pickedRgb = [1, 3, 5].map((i) => parseInt(picked.slice(i, i + 2), 16));
  check('color: the eyedropper takes the color under the mouse', diff(pickedRgb, under) <= 1, `${picked} vs ${under}`);
  await page.locator('#color-text').fill('0, 255, 0');
  await page.locator('#color-text').press('Enter');
  check('color: a typed color sets the picker', (await page.evaluate(() => document.getElementById('color').value)) === '#00ff00');
  await page.locator('#color-text').fill('300, 0, 0');
  await page.locator('#color-text').press('Enter');
  check('color: a typed non-color is refused', (await page.evaluate(() => document.getElementById('color').value)) === '#00ff00' &&
    /is not a color/.test((await doc()).status));
  await page.locator('#canvas').focus().catch(() => undefined);
  await page.evaluate(() => document.activeElement.blur());
  const [hx2, hy2] = await client(page, 8, 8);
  await page.mouse.move(hx2, hy2);
  await page.waitForTimeout(300);
  await exact('a second hover preview');

  // Problem 2: twenty quick color clicks are twenty edits, none refused as another tab's.
  await page.evaluate(() => {
    for (const [id, v] of [['amount', '0.2'], ['radius', '40']]) {
      const el = document.getElementById(id);
      el.value = v;
      el.dispatchEvent(new Event('input'));
    }
  });
  await clicks(Array.from({ length: 20 }, (_, i) => [44 + (i % 5) * 2, 44 + Math.floor(i / 5) * 2]));
  let d = await doc();
  check('color: 20 quick clicks are 20 edits', d.version === start.version + 20 && d.undo === 20,
    `version ${start.version} -> ${d.version}, ${d.undo} undo steps, status "${d.status}"`);
  check('color: no conflict and no error', !d.error && !/another tab/.test(d.status), `status "${d.status}"`);
  await exact('20 color clicks');

  // A real drag after all that: 8 px to the right, committed once.
  await page.keyboard.press('d');
  // The mouse from `from` to `to` (image pixels) in `steps` moves, pressed at `from` first when
  // `press`; drag() releases at the end and waits for the page.
  const sweep = async (from, to, steps, press = false) => {
    if (press) {
      const [sx, sy] = await client(page, ...from);
      await page.mouse.move(sx, sy);
      await page.mouse.down();
    }
    for (let i = 1; i <= steps; ++i) {
      const [x, y] = await client(page, from[0] + ((to[0] - from[0]) * i) / steps, from[1] + ((to[1] - from[1]) * i) / steps);
      await page.mouse.move(x, y);
      await page.waitForTimeout(15);
    }
  };
  const drag = async (from, to, steps = 10) => {
    await sweep(from, to, steps, true);
    await page.mouse.up();
    await idle(page);
    return doc();
  };
  // With the overlays on, compared with a full redraw halfway.
  await page.keyboard.press('1');
  await page.keyboard.press('2');
  await sweep([76, 48], [80, 46], 5, true);
  await exact('a drag preview with the overlays');
  const drawn = () => page.evaluate(() => [window.subvec.renderer().drawnTriangles, window.subvec.state.view.depth]);
  const [previewTriangles, depth] = await drawn();
  await sweep([80, 46], [84, 48], 5);
  await page.mouse.up();
  await idle(page);
  await exact('the drag\'s commit');
  const [viewTriangles] = await drawn();
  check('software WebGL: a drag previews the view one level coarser, the release draws it',
    depth >= 2 && previewTriangles * 4 === viewTriangles, `depth ${depth}: ${previewTriangles} triangles in the preview, ${viewTriangles} after`);
  await page.keyboard.press('1');
  await page.keyboard.press('2');
  d = await doc();
  check('drag: one edit', d.version === start.version + 21 && d.undo === 21 && /dragged/.test(d.status),
    `version ${d.version}, ${d.undo} undo steps, status "${d.status}"`);

  // Twenty-five quick undos: 21 steps back to the start, then "nothing to undo"; no conflict.
  for (let i = 0; i < 25; i++) await page.keyboard.press('Control+z');
  await idle(page);
  d = await doc();
  check('undo: 25 quick presses undo all 21 edits', d.undo === 0 && d.version === start.version + 42,
    `${d.undo} undo steps left, version ${d.version}, status "${d.status}"`);
  check('undo: no conflict, and the last press says why it did nothing',
    !d.error && d.status === 'nothing to undo', `status "${d.status}"`);
  check('undo: the image is back', diff(await pixel(page, 80, 48), probe) < 2);
  await page.keyboard.press('Control+Shift+z');
  await idle(page);
  d = await doc();
  check('redo names the edit in plain words', /^redid: color blend at \(\d+, \d+\)$/.test(d.status), `status "${d.status}"`);
  await page.keyboard.press('Control+z');
  await idle(page);

  // Problem 8: Stylize twice gives one stroke along the outline, and a drag carries it along;
  // undo brings it back.
  const strokes = () => page.evaluate(async () => (await (await fetch('/api/strokes?level=0')).json()).length);
  await page.keyboard.press('y');
  await idle(page);
  const once = await strokes();
  await page.keyboard.press('y');
  await idle(page);
  check('stylize twice: the strokes are replaced, not doubled', once > 0 && (await strokes()) === once, `${once} then ${await strokes()}`);
  // The stroke runs just inside the outline; a closed one tapers to nothing at its first vertex
  // (angle 0 here), so it is looked for on the left, along row 48: where is it darkest?
  const strokeX = async () => {
    let best = [Infinity, 0];
    for (let x = 14; x <= 40; x += 0.25) {
      const p = await pixel(page, x, 48);
      if (Math.max(...p.slice(0, 3)) < best[0]) best = [Math.max(...p.slice(0, 3)), x];
    }
    return best[0] < 80 ? best[1] : NaN;
  };
  const x0 = await strokeX();
  d = await drag([21, 48], [29, 48]);
  const x1 = await strokeX();
  check('a drag moves its stroke', x1 - x0 > 6 && x1 - x0 < 10, `stroke at x ${x0} -> ${x1} after a drag of 8 px`);
  await page.keyboard.press('Control+z');
  await idle(page);
  const x2 = await strokeX();
  check('undo puts the stroke back', x2 === x0, `stroke at x ${x2}, was ${x0}`);
  await page.keyboard.press('Control+z');
  await page.keyboard.press('Control+z');
  await idle(page);

  // A drag whose pointer capture the browser takes away (no pointerup follows) ends there and
  // commits: its task must not hold the queue waiting for a release.
  const lost = await doc();
  await sweep([76, 48], [80, 48], 4, true);
  const [lx, ly] = await client(page, 76, 48);
  await page.evaluate(() => document.getElementById('canvas').releasePointerCapture(window.subvec.state.drag.pointer));
  await page.mouse.move(lx + 40, ly + 40);  // the capture's loss is delivered with the next pointer event
  await idle(page);
  d = await doc();
  await page.mouse.up();
  check('a lost pointer capture ends the drag', d.version === lost.version + 1 && /dragged by/.test(d.status) && d.busy === 0,
    `version ${lost.version} -> ${d.version}, status "${d.status}"`);

  // A press outside the image grabs nothing.
  const outsideBefore = await doc();
  d = await drag([-2, 60], [30, 60]);  // in the margin left of the image
  check('a drag that starts outside the image does nothing', d.version === outsideBefore.version && /outside the image/.test(d.status),
    `version ${outsideBefore.version} -> ${d.version}, status "${d.status}"`);

  // Problem 9: the image re-fits when the window changes size, until the user zooms; below 800 px
  // the panel folds away and the canvas takes the width.
  const layout = () => page.evaluate(() => {
    const c = document.getElementById('canvas');
    const { width, height } = window.subvec.state.doc;
    const t = window.subvec.state.transform;
    const fitZoom = Math.min(c.width / width, c.height / height) * 0.96;
    return { canvas: c.getBoundingClientRect().width, fitted: Math.abs(t.zoom - fitZoom) < 1e-9, zoom: t.zoom };
  });
  await page.setViewportSize({ width: 1200, height: 760 });
  await page.waitForTimeout(300);
  const wide = await layout();
  await page.setViewportSize({ width: 400, height: 300 });
  await page.waitForTimeout(300);
  const narrow = await layout();
  check('resize: the image re-fits', wide.fitted && narrow.fitted && narrow.zoom < wide.zoom, JSON.stringify([wide, narrow]));
  check('resize: at 400 px the panel folds away', narrow.canvas === 400, `canvas ${narrow.canvas} px wide`);
  await page.click('#panel-toggle');
  await page.waitForTimeout(300);
  const panelOpen = await page.evaluate(() => document.getElementById('panel').getBoundingClientRect().right > 200);
  await page.click('#panel-toggle');
  check('resize: the toggle shows the panel', panelOpen);
  const [wx, wy] = await client(page, 48, 48);
  await page.mouse.move(wx, wy);
  await page.mouse.wheel(0, -200);
  await page.waitForTimeout(100);
  const zoomed = await layout();
  await page.setViewportSize({ width: 700, height: 500 });
  await page.waitForTimeout(300);
  const kept = await layout();
  check('resize: after a zoom the view is kept', !zoomed.fitted && kept.zoom === zoomed.zoom, JSON.stringify([zoomed, kept]));
  await page.setViewportSize({ width: 1000, height: 700 });

  // Direct handles: the points tool shows the control points; a box selects the ones inside it,
  // Shift+click takes one out; the arrow keys nudge the selection (one edit each), a drag of a
  // selected point moves them all, R recolors them; undo takes each back.
  await page.keyboard.press('0');
  await idle(page);
  const control = () => page.evaluate(async () => (await (await fetch(`/api/control?level=${window.subvec.state.level}`)).json()).positions);
  const rest = await control();
  const inBox = (pos, x0, y0, x1, y1) => Array.from({ length: pos.length / 2 }, (_, i) => i)
    .filter((i) => pos[2 * i] >= x0 && pos[2 * i] <= x1 && pos[2 * i + 1] >= y0 && pos[2 * i + 1] <= y1);
  // The right-hand side of the disk's outline: the points inside the square swept below
  // (image px 57-93 x 27-69; no point of the disk lies within a pixel of its sides).
  const boxed = inBox(rest, 57, 27, 93, 69);
  await page.keyboard.press('p');
  const handle = await pixel(page, rest[2 * boxed[0]], rest[2 * boxed[0] + 1]);
  check('points: the control points are drawn', diff(handle, [26, 230, 255]) < 40 || diff(handle, [255, 140, 13]) < 40, `${handle}`);
  const v1 = (await doc()).version;
  await sweep([57, 27], [93, 69], 6, true);
  await page.mouse.up();
  await idle(page);
  let selection = await page.evaluate(() => window.subvec.state.selection);
  check(`points: a box selects the ${boxed.length} points inside it`, boxed.length >= 3 &&
    JSON.stringify(selection) === JSON.stringify(boxed), `${selection} vs ${boxed}`);
  // The same square drawn as a lasso (Alt): the same points.
  await page.keyboard.press('Escape');
  await page.keyboard.down('Alt');
  await sweep([57, 27], [93, 27], 4, true);
  await sweep([93, 27], [93, 69], 4);
  await sweep([93, 69], [57, 69], 4);
  await sweep([57, 69], [57, 29], 4);
  await page.mouse.up();
  await page.keyboard.up('Alt');
  await idle(page);
  selection = await page.evaluate(() => window.subvec.state.selection);
  check('points: an Alt lasso selects the points inside it', JSON.stringify(selection) === JSON.stringify(boxed), `${selection} vs ${boxed}`);
  const [ox, oy] = await client(page, rest[2 * boxed[0]], rest[2 * boxed[0] + 1]);
  await page.keyboard.down('Shift');
  await page.mouse.click(ox, oy);
  await page.keyboard.up('Shift');
  selection = await page.evaluate(() => window.subvec.state.selection);
  check('points: Shift+click takes a point out', selection.length === boxed.length - 1 && !selection.includes(boxed[0]), `${selection}`);
  for (let i = 0; i < 3; i++) await page.keyboard.press('ArrowRight');
  await page.keyboard.press('Shift+ArrowUp');
  await idle(page);
  d = await doc();
  let now = await control();
  const shifted = (i, dx, dy) => Math.abs(now[2 * i] - rest[2 * i] - dx) < 1e-3 && Math.abs(now[2 * i + 1] - rest[2 * i + 1] - dy) < 1e-3;
  await exact('points nudged');
  check('points: arrow keys nudge the selection, one edit each', d.version === v1 + 4 &&
    selection.every((i) => shifted(i, 3, -10)) && shifted(boxed[0], now[2 * boxed[0]] - rest[2 * boxed[0]], now[2 * boxed[0] + 1] - rest[2 * boxed[0] + 1]) &&
    /^moved \d+ control points by \(0, -10\) px$/.test(d.status), `version ${v1} -> ${d.version}, status "${d.status}"`);
  const grab = [now[2 * selection[0]], now[2 * selection[0] + 1]];
  await drag(grab, [grab[0] - 6, grab[1] + 4]);
  d = await doc();
  now = await control();
  check('points: a drag of a selected point moves the selection', d.version === v1 + 5 &&
    selection.every((i) => Math.hypot(now[2 * i] - rest[2 * i] + 3, now[2 * i + 1] - rest[2 * i + 1] + 6) < 0.6) &&
    /^moved \d+ control points by \(-6, 4\) px$/.test(d.status), `status "${d.status}"`);
  await page.locator('#color-text').fill('#ff0000');
  await page.locator('#color-text').press('Enter');
  await page.evaluate(() => { const el = document.getElementById('amount'); el.value = '1'; el.dispatchEvent(new Event('input')); document.activeElement.blur(); });
  await page.keyboard.press('r');
  await idle(page);
  d = await doc();
  await exact('points recolored');
  check('points: R recolors the selected points', d.version === v1 + 6 &&
    new RegExp(`^color blend of ${selection.length} control points: \\d+ control colors moved toward \\(255, 0, 0\\)$`).test(d.status), `status "${d.status}"`);
  await page.keyboard.press('Escape');
  check('points: Esc clears the selection', (await page.evaluate(() => window.subvec.state.selection.length)) === 0);
  for (let i = 0; i < 6; i++) await page.keyboard.press('Control+z');
  await idle(page);
  const back = await control();
  check('points: undo takes the moves back', (await doc()).version === v1 + 12 && back.every((v, i) => Math.abs(v - rest[i]) < 1e-4));
  await page.keyboard.press('d');

  // Problem 11: two tabs. Another tab's edit during a drag does not throw the drag away, and undo
  // takes back a tab's own edits only.
  await page.keyboard.press('0');
  await page.keyboard.press('d');
  await idle(page);
  const { page: tabB } = await openEditor(browser, server.url);
  const v0 = (await doc()).version;
  await sweep([76, 48], [80, 48], 4, true);
  await tabB.keyboard.press('c');
  const [bx, by] = await client(tabB, 6, 6);
  await tabB.mouse.click(bx, by);  // tab B recolors the corner while tab A drags
  await idle(tabB);
  await sweep([80, 48], [84, 48], 4);
  await page.mouse.up();
  await idle(page);
  d = await doc();
  const cornerA = await pixel(page, 6, 6), cornerB = await pixel(tabB, 6, 6);
  check('two tabs: a drag outlives the other tab\'s edit', d.version === v0 + 2 && /^dragged by \(8, 0\) px$/.test(d.status),
    `version ${v0} -> ${d.version}, status "${d.status}"`);
  check('two tabs: the other tab\'s edit is kept and shown', diff(cornerA, cornerB) < 3, `${cornerA} vs ${cornerB}`);
  await page.keyboard.press('Control+z');  // undoes A's drag
  await idle(page);
  await page.keyboard.press('Control+z');  // B's edit is next: not A's to undo
  await idle(page);
  d = await doc();
  check('two tabs: undo takes back this tab\'s edit and waits at the other\'s', d.version === v0 + 3 &&
    /^undo waits: the last edit was made in another window/.test(d.status), `version ${d.version}, status "${d.status}"`);
  await tabB.waitForFunction((v) => window.subvec.state.version === v, d.version, { timeout: 10000 });
  await tabB.keyboard.press('Control+z');
  await idle(tabB);
  const lineB = await tabB.evaluate(() => document.getElementById('status').textContent);
  check('two tabs: the other tab undoes its own edit', /^undid: color blend at \(6, 6\)$/.test(lineB), `status "${lineB}"`);
  await tabB.close();

  // A duplicated tab starts with a copy of this tab's sessionStorage, and so of its id: it takes
  // an id of its own (or both tabs would share one undo history), and keeps it across a reload.
  const context = await browser.newContext({ viewport: { width: 1000, height: 700 } });
  const ready = (p) => p.waitForFunction(() => window.subvec && window.subvec.ready, null, { timeout: 60000 });
  const original = await context.newPage();
  await original.goto(server.url);
  await ready(original);
  const idA = await original.evaluate(() => window.subvec.tab());
  const dup = await context.newPage();
  await dup.addInitScript((id) => {
    if (!sessionStorage.getItem('copied')) sessionStorage.setItem('subvec-tab', id), sessionStorage.setItem('copied', '1');
  }, idA);
  await dup.goto(server.url);
  await ready(dup);
  const idDup = await dup.evaluate(() => window.subvec.tab());
  await dup.reload();
  await ready(dup);
  const idReloaded = await dup.evaluate(() => window.subvec.tab());
  check('a duplicated tab takes its own id and keeps it across a reload',
    idDup !== idA && idReloaded === idDup && (await original.evaluate(() => window.subvec.tab())) === idA,
    `original ${idA}, duplicate ${idDup}, reloaded ${idReloaded}`);
  await context.close();

  // Problem 3: a drag through the disk and out of its other side, sigma 12, so that the far side
  // of the outline stays. The outline would cross itself: the preview and the release stop at the
  // last fold-free position (issue 25), and say so. (With the auto sigma the whole disk moves, and
  // it now arrives, flattened against the frame.) Last of the disk's checks: the outline ends most
  // of the way across the disk.
  const before = await doc();
  const inside = await pixel(page, 73, 48);  // just inside the tear
  const setSigma = (v) => page.evaluate((value) => {
    const input = document.getElementById('sigma');
    input.value = String(value);
    input.dispatchEvent(new Event('input', { bubbles: true }));
    input.dispatchEvent(new Event('change', { bubbles: true }));
  }, v);
  await setSigma(12);
  d = await drag([76, 48], [4, 48], 24);
  await setSigma(0);
  check('refused drag: committed at its last valid position', d.version === before.version + 1 && d.undo === before.undo + 1,
    `version ${before.version} -> ${d.version}, status "${d.status}"`);
  check('refused drag: says it stopped', /^stopped at the last position the mesh could take: dragged/.test(d.status), `status "${d.status}"`);
  const moved = await pixel(page, 73, 48);
  check('refused drag: the feature moved left', diff(moved, inside) > 20, `${inside} -> ${moved}`);

  // Problem 10: the status lines of all of the above speak plainly: no versions, vertex or
  // triangle numbers or solver internals.
  const lines = [...new Set(await page.evaluate(() => window.statuses))];
  const internal = lines.filter((l) => /version|vertex \d|triangle \d|feature \d|id \d|scale adjustment|held back|handle vertices/.test(l));
  check(`status lines are plain (${lines.length} different ones)`, lines.length > 10 && internal.length === 0, internal.join(' | '));

  const frames = await page.evaluate(() => window.subvec.renderer().frames);
  check(`partial redraws are exact (${compared} compared; ${frames.partial} partial frames, ${frames.full} full)`,
    inexact.length === 0 && frames.partial >= 20, inexact.join('; '));

  check('no page errors', errors.length === 0, errors.join('; '));
} catch (e) {
  check('the test ran', false, e.stack);
} finally {
  await stop(server);
}

// Problem 6: the SVG download of a photograph (the butterfly, or the project's rocket
// without ../shared) starts within 5 s, with a progress line from the click on. It took 112 s
// while the server brotli-compressed the answer at its highest effort.
const photo = [join(root, '..', 'shared', 'images', 'butterfly.png'), join(root, 'examples', '04-rocket.png')].find(existsSync);
const photoServer = await serve(binary, [photo]);
try {
  const { page, errors } = await openEditor(browser, photoServer.url);
  const t0 = Date.now();
  const [download] = await Promise.all([
    page.waitForEvent('download', { timeout: 60000 }),
    page.click('.downloads a[data-format=svg]'),
  ]);
  const seconds = (Date.now() - t0) / 1000;
  const saved = join(dir, 'photo.svg');
  await download.saveAs(saved);
  const svg = readFileSync(saved);
  check(`svg download: starts within 5 s (${seconds.toFixed(1)} s, ${(svg.length / 1e6).toFixed(1)} MB)`, seconds <= 5);
  check('svg download: a whole SVG file', svg.subarray(0, 200).toString().includes('<svg') && svg.subarray(-10).toString().includes('</svg>'));
  await idle(page);
  const line = await page.evaluate(() => document.getElementById('status').textContent);
  check('svg download: the status line says what came', /^downloaded \S+\.svg \(\d+(\.\d)? MB\)$/.test(line), `status "${line}"`);

  // Problem 5: a color fill stops at the wing's outline. The page's defaults pick the region
  // around the click (no radius cap, tolerance 60): a click on the right wing's black paints it
  // red, and the leaf around the wing keeps its green. (A 200 px disk painted straight through the
  // outline before.) On the butterfly only: the points are the wing's.
  if (photo.endsWith('butterfly.png')) {
    const { width, height } = await page.evaluate(() => window.subvec.state.doc);
    const grid = [];
    for (let y = 2; y < height; y += 4) for (let x = 2; x < width; x += 4) grid.push([x, y]);
    const before = await page.evaluate((g) => window.subvec.pixelsAt(g), grid);
    await page.keyboard.press('c');
    await page.locator('#color-text').fill('255, 0, 0');
    await page.locator('#color-text').press('Enter');
    await page.evaluate(() => {
      const el = document.getElementById('amount');
      el.value = '1';
      el.dispatchEvent(new Event('input'));
      document.activeElement.blur();
    });
    const [wx, wy] = await client(page, 400, 180);
    await page.mouse.move(wx, wy);
    await page.waitForTimeout(300);  // the hover preview
    await page.mouse.click(wx, wy);
    await idle(page);
    const after = await page.evaluate((g) => window.subvec.pixelsAt(g), grid);
    const dark = (p) => p[0] + p[1] + p[2] < 150;
    const green = (p) => p[1] > 90 && p[1] > p[0] + 30 && p[1] > p[2] + 30;
    const red = (p) => p[0] > 150 && p[1] < 90 && p[2] < 90;
    // The right wing: dark samples right of the body (x > 270) within 90 px of the click.
    const wing = grid.map(([x, y], i) => x > 270 && Math.hypot(x - 400, y - 180) < 90 && dark(before[i]));
    const painted = wing.filter((w, i) => w && red(after[i])).length / Math.max(1, wing.filter(Boolean).length);
    // Leaf samples at least a sample step (4 px) inside the green: all eight neighbours green too.
    // The outline's own pixels mix wing and leaf, and may take some red.
    const columns = Math.ceil((width - 2) / 4);
    const leaf = grid.map((_, i) => [-1, 0, 1].every((dy) => [-1, 0, 1].every((dx) => {
      const j = i + dy * columns + dx;
      return j >= 0 && j < grid.length && green(before[j]);
    })));
    const leafChanged = leaf.filter((l, i) => l && diff(before[i], after[i]) > 12).length;
    const leafCount = leaf.filter(Boolean).length;
    check(`color fill: the wing turns red (${(100 * painted).toFixed(0)} % of its dark samples near the click)`, painted > 0.8);
    check(`color fill: the leaf keeps its green (${leafChanged} of ${leafCount} green samples changed)`,
      leafCount > 1000 && leafChanged <= leafCount / 200);
    await page.keyboard.press('Control+z');
    await idle(page);
  }

  // Problem 4: a 25 px drag of a small closed shape (the butterfly's white spots) moves it and
  // leaves the rest of the picture where it was (it shifted the whole butterfly before: 220k of
  // its 250k pixels changed). The extent is the page's default, "auto".
  const spot = await page.evaluate(async () => {
    const { width, height } = window.subvec.state.doc;
    const c = await (await fetch('/api/control?level=0')).json();
    let best = null;
    for (const f of c.features) {
      if (f.length < 4 || f[0] !== f[f.length - 1]) continue;
      const xs = f.map((v) => c.positions[2 * v]), ys = f.map((v) => c.positions[2 * v + 1]);
      const diag = Math.hypot(Math.max(...xs) - Math.min(...xs), Math.max(...ys) - Math.min(...ys));
      const cx = (Math.max(...xs) + Math.min(...xs)) / 2, cy = (Math.max(...ys) + Math.min(...ys)) / 2;
      if (diag < 10 || diag > 40 || cx < 80 || cy < 80 || cx > width - 80 || cy > height - 80) continue;
      if (!best || diag < best.diag) best = { diag, center: [cx, cy], at: [Math.max(...xs), ys[xs.indexOf(Math.max(...xs))]], size: [width, height] };
    }
    return best;
  });
  if (spot) {
    const grid = [];
    for (let y = 4; y < spot.size[1]; y += 8) for (let x = 4; x < spot.size[0]; x += 8) grid.push([x, y]);
    const before = await page.evaluate((g) => window.subvec.pixelsAt(g), grid);
    await page.keyboard.press('d');
    const [sx, sy] = await client(page, ...spot.at);
    await page.mouse.move(sx, sy);
    await page.mouse.down();
    for (let i = 1; i <= 10; i++) {
      const [x, y] = await client(page, spot.at[0] + 2.5 * i, spot.at[1]);
      await page.mouse.move(x, y);
      await page.waitForTimeout(15);
    }
    await page.mouse.up();
    await idle(page);
    const after = await page.evaluate((g) => window.subvec.pixelsAt(g), grid);
    // The auto extent (subvec::suggested_drag_extent): sigma 2 D for a closed shape of diagonal
    // D, the region 3 sigma around its vertices; beyond it, and the control ring the limit
    // surface reaches across (20 px here), nothing may change.
    const region = Math.max(3 * Math.max(2 * spot.diag, 8), 30);
    const far = grid.map(([x, y]) => Math.hypot(x - spot.center[0], y - spot.center[1]) > spot.diag / 2 + region + 20);
    const changed = before.filter((p, i) => diff(p, after[i]) > 10).length / grid.length;
    const farChanged = before.filter((p, i) => far[i] && diff(p, after[i]) > 2).length;
    const line = await page.evaluate(() => document.getElementById('status').textContent);
    check(`a small shape's drag stays local (${(100 * changed).toFixed(1)} % of the picture changed, ` +
      `${far.filter(Boolean).length} samples beyond its region, spot ${spot.diag.toFixed(0)} px)`,
      changed > 0 && farChanged === 0 && /^(stopped at the last position the mesh could take: )?dragged by/.test(line),
      `${farChanged} far samples changed, status "${line}"`);
  } else {
    console.log('     (no small closed feature in this photograph: the local-drag check is skipped)');
  }
  check('no page errors (photograph)', errors.length === 0, errors.join('; '));
} catch (e) {
  check('the download test ran', false, e.stack);
} finally {
  await browser.close();
  await stop(photoServer);
  rmSync(dir, { recursive: true, force: true });
}
finish();
