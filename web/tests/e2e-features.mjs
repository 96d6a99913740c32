// End-to-end test of the editor's pen (issue 25) in headless Chromium: draw a closed feature with
// the pen tool on the disk example's background, fill it, drag it, undo, redo, save; then delete
// it with the Select tool and Delete, and undo that. Asserts on canvas pixels, on the document and
// on the saved file.
//
//   node web/tests/e2e-features.mjs BUILD/bin/subvec
//
// Exit status 0: all passed; 1: a check failed; 77: skipped (no Chromium or no node_modules).
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { requireBrowser, launch, serve, stop, openEditor, idle, pixel, client, check, finish, diff } from './harness.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');
const binary = process.argv[2];
const chromium = requireBrowser('e2e-features.mjs', binary);

const yellow = (p) => p[0] > 200 && p[1] > 200 && p[2] < 80;

const dir = mkdtempSync(join(tmpdir(), 'subvec-e2e-features-'));
const saved = join(dir, 'saved.svec.json');
const server = await serve(binary, [join(root, 'examples', '01-disk.svec.json'), '-o', saved]);
const browser = await launch(chromium);
try {
  const { page, errors } = await openEditor(browser, server.url);
  const features = async () => (await page.evaluate(async () => (await fetch('/api/document')).json())).levels[0].features;
  const status = () => page.evaluate(() => document.getElementById('status').textContent);

  // The background below left of the disk (centre (48, 48), control radius 28): a ring of radius
  // 9 around (14, 82), drawn with the pen as a mouse would, ending where it started.
  const centre = [14, 82], probe = [25, 82];
  const inside0 = await pixel(page, ...centre), probe0 = await pixel(page, ...probe);
  check('features: one at the start', (await features()) === 1);
  await page.keyboard.press('n');
  const ring = (i) => [centre[0] + 9 * Math.cos((2 * Math.PI * i) / 48), centre[1] + 9 * Math.sin((2 * Math.PI * i) / 48)];
  let [x, y] = await client(page, ...ring(0));
  await page.mouse.move(x, y);
  await page.mouse.down();
  for (let i = 1; i <= 48; ++i) {
    [x, y] = await client(page, ...ring(i));
    await page.mouse.move(x, y);
  }
  await page.mouse.up();
  await idle(page);
  check('pen: a closed tear was added', (await features()) === 2 && /closed tear feature 1/.test(await status()), await status());
  const inside1 = await pixel(page, ...centre), probe1 = await pixel(page, ...probe);
  check('pen: the picture did not change', diff(inside1, inside0) <= 3 && diff(probe1, probe0) <= 3,
    `${inside0} -> ${inside1}, ${probe0} -> ${probe1}`);

  // Fill inside it: the region stops at the new tear.
  await page.keyboard.press('c');
  await page.locator('input[name=pick][value=region]').check();
  await page.locator('#color').fill('#ffff00');
  await page.evaluate(() => {
    const el = document.getElementById('amount');
    el.value = '1';
    el.dispatchEvent(new Event('input'));
  });
  [x, y] = await client(page, ...centre);
  await page.mouse.click(x, y);
  await idle(page);
  const filled = await pixel(page, ...centre);
  check('fill: inside the new tear is yellow', yellow(filled), `${filled}`);
  check('fill: stops at the tear', diff(await pixel(page, ...probe), probe0) <= 3, `${await pixel(page, ...probe)}`);

  // Drag the new feature 6 px to the right by its right-hand side: the yellow covers the probe.
  await page.keyboard.press('d');
  await page.locator('input[name=pick][value=feature]').check().catch(() => {});
  [x, y] = await client(page, centre[0] + 9, centre[1]);
  await page.mouse.move(x, y);
  await page.mouse.down();
  for (let i = 1; i <= 6; ++i) {
    [x, y] = await client(page, centre[0] + 9 + i, centre[1]);
    await page.mouse.move(x, y);
    await page.waitForTimeout(20);
  }
  await page.mouse.up();
  await idle(page);
  const dragged = await pixel(page, ...probe);
  check('drag: the new feature moved over the probe', yellow(dragged), `${dragged}`);

  // Undo the drag, redo it.
  await page.keyboard.press('Control+z');
  await idle(page);
  const undone = await pixel(page, ...probe);
  check('undo: the feature is back', diff(undone, probe0) <= 3 && yellow(await pixel(page, ...centre)), `${undone}`);
  await page.keyboard.press('Control+Shift+z');
  await idle(page);
  check('redo: moved again', yellow(await pixel(page, ...probe)), `${await pixel(page, ...probe)}`);

  // Save in place: the file has the new closed feature, moved right.
  await page.keyboard.press('Control+s');
  await page.waitForFunction(() => /saved/.test(document.getElementById('status').textContent));
  const file = JSON.parse(readFileSync(saved, 'utf8'));
  const l0 = file.levels[0];
  const added = l0.features.find((f) => f.id === 1);
  const xs = added ? added.vertices.map((v) => l0.vertices[v][0]) : [];
  const meanX = xs.reduce((a, b) => a + b, 0) / Math.max(1, xs.length);
  check('saved: two features, the new one closed and moved right',
    l0.features.length === 2 && added && added.vertices[0] === added.vertices.at(-1) && meanX > centre[0] + 3,
    `${l0.features.length} features, mean x ${meanX}`);

  // Select it, Delete: gone, and the yellow with it where the tear was; undo brings it back.
  await page.keyboard.press('v');
  [x, y] = await client(page, centre[0] + 15, centre[1]);
  await page.mouse.click(x, y);
  await page.waitForFunction(() => /Delete deletes the feature/.test(document.getElementById('status').textContent));
  await page.keyboard.press('Delete');
  await idle(page);
  check('delete: one feature left', (await features()) === 1 && /deleted/.test(await status()), await status());
  await page.keyboard.press('Control+z');
  await idle(page);
  check('delete: undone', (await features()) === 2 && yellow(await pixel(page, ...probe)));
  check('no page errors', errors.length === 0, errors.join('; '));
} catch (e) {
  check('ran to its end', false, e && e.stack ? e.stack : String(e));
} finally {
  await browser.close();
  await stop(server);
  rmSync(dir, { recursive: true, force: true });
}
finish();
