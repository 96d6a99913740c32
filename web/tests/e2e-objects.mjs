// End-to-end test of the editor's object tool (issue 26) in headless Chromium: on the disk
// example, drag a rectangle round the disk to make it an object, drag the object 20 px to the
// right, hide it with X, undo the hiding, stylize it alone, save. Asserts on canvas pixels and on the saved file.
//
//   node web/tests/e2e-objects.mjs BUILD/bin/subvec
//
// Exit status 0: all passed; 1: a check failed; 77: skipped (no Chromium or no node_modules).
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { requireBrowser, launch, serve, stop, openEditor, idle, pixel, client, check, finish } from './harness.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, '..', '..');
const binary = process.argv[2];
const chromium = requireBrowser('e2e-objects.mjs', binary);

const red = (p) => p[0] > 150 && p[0] - p[1] > 50 && p[0] - p[2] > 50;  // the disk (a lit red ball)

const dir = mkdtempSync(join(tmpdir(), 'subvec-e2e-objects-'));
const saved = join(dir, 'saved.svec.json');
const server = await serve(binary, [join(root, 'examples', '01-disk.svec.json'), '-o', saved]);
const browser = await launch(chromium);
try {
  const { page, errors } = await openEditor(browser, server.url);
  const status = () => page.evaluate(() => document.getElementById('status').textContent);
  const drag = async (from, to, steps = 8) => {
    let [x, y] = await client(page, ...from);
    await page.mouse.move(x, y);
    await page.mouse.down();
    for (let i = 1; i <= steps; ++i) {
      [x, y] = await client(page, from[0] + ((to[0] - from[0]) * i) / steps, from[1] + ((to[1] - from[1]) * i) / steps);
      await page.mouse.move(x, y);
      await page.waitForTimeout(15);
    }
    await page.mouse.up();
    await idle(page);
  };

  // The disk: centre (48, 48), radius about 28. Its left part (30, 48) and the background right
  // of it (84, 48).
  const left = [30, 48], right = [84, 48];
  check('start: the disk is red on its left', red(await pixel(page, ...left)), `${await pixel(page, ...left)}`);
  check('start: the background right of it is not', !red(await pixel(page, ...right)), `${await pixel(page, ...right)}`);

  // A rectangle round the disk: it becomes an object, and nothing shows it.
  await page.keyboard.press('o');
  await drag([12, 12], [84, 84]);
  check('make: an object', /object 0 .*made of what \[12, 12, 72, 72\] frames/.test(await status()), await status());
  check('make: the disk is still there', red(await pixel(page, ...left)), `${await pixel(page, ...left)}`);

  // Drag it 20 px right: its left part shows the completed background, the right is covered.
  await drag([48, 48], [68, 48]);
  check('move: moved by 20 px', /moved by \[20, 0\]/.test(await status()), await status());
  const uncovered = await pixel(page, ...left);
  check('move: the background shows where it was', !red(uncovered), `${uncovered}`);
  check('move: it covers the right', red(await pixel(page, 70, 48)), `${await pixel(page, 70, 48)}`);

  // Shift+drag turns it about its centre (a quarter turn: the move is kept, the disk stays round).
  await page.keyboard.down('Shift');
  await drag([68, 30], [86, 48]);
  await page.keyboard.up('Shift');
  check('turn: rotated', /rotated by (8\d|9\d)(\.\d+)? degrees/.test(await status()), await status());
  check('turn: still over the right', red(await pixel(page, 70, 48)), `${await pixel(page, 70, 48)}`);

  // X hides it (it stays selected); undo shows it again.
  await page.keyboard.press('x');
  await idle(page);
  check('hide: hidden', /hidden/.test(await status()) && !red(await pixel(page, 70, 48)), `${await status()} ${await pixel(page, 70, 48)}`);
  await page.keyboard.press('Control+z');
  await idle(page);
  check('undo: shown again', red(await pixel(page, 70, 48)), `${await pixel(page, 70, 48)}`);

  // The Objects panel lists it: its checkbox hides it and shows it again.
  const box = page.locator('#object-list input[type=checkbox]');
  check('panel: one object listed, shown', (await box.count()) === 1 && (await box.first().isChecked()));
  await box.first().uncheck();
  await idle(page);
  check('panel: unchecked hides it', !red(await pixel(page, 70, 48)), `${await pixel(page, 70, 48)}`);
  await page.locator('#object-list input[type=checkbox]').first().check();
  await idle(page);
  check('panel: checked shows it', red(await pixel(page, 70, 48)), `${await pixel(page, 70, 48)}`);

  // Selected in the panel, Stylize (Y) strokes the object alone, into its own strokes; Esc
  // deselects it, and Stylize then acts on the level again.
  await page.locator('#object-list li span, #object-list li label').first().click();
  await page.keyboard.press('y');
  await idle(page);
  check('stylize: the object', /^stylize \(object 0\): [1-9]\d* strokes/.test(await status()), await status());
  const stroked = await page.evaluate(async () => (await (await fetch('/api/document')).json()).objects[0]);
  check('stylize: its strokes', stroked && stroked.strokes > 0, JSON.stringify(stroked));
  await page.keyboard.press('Escape');
  check('escape: deselected', /no object selected/.test(await status()), await status());

  // Save in place: version 2 with one visible object, moved right.
  await page.keyboard.press('Control+s');
  await page.waitForFunction(() => /saved/.test(document.getElementById('status').textContent));
  const file = JSON.parse(readFileSync(saved, 'utf8'));
  const objects = file.objects ?? [];
  const xs = objects.length ? objects[0].mesh.vertices.map((v) => v[0]) : [];
  const meanX = xs.reduce((a, b) => a + b, 0) / Math.max(1, xs.length);
  check('saved: version 2, one visible object moved right',
    file.version === 2 && objects.length === 1 && objects[0].visible !== false && meanX > 60,
    `version ${file.version}, ${objects.length} objects, mean x ${meanX}`);
  check('saved: the object\'s strokes with it', objects.length === 1 && (objects[0].strokes ?? []).length > 0 &&
    (file.strokes ?? []).length === 0, `${(objects[0]?.strokes ?? []).length} object strokes, ${(file.strokes ?? []).length} level strokes`);
  check('no page errors', errors.length === 0, errors.join('; '));
} catch (e) {
  check('ran to its end', false, e && e.stack ? e.stack : String(e));
} finally {
  await browser.close();
  await stop(server);
  rmSync(dir, { recursive: true, force: true });
}
finish();
