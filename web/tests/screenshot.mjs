// The screenshots in docs/serve.md: the butterfly of docs/editing.md edited in the page with the
// mouse (the first drag and the first TRANSFORM of docs/figures/butterfly-ops.json), the feature
// overlay on, the dragged feature selected; then, when asked for, a region fill of the black
// wings with the preview of the next click, and a box selection of control points.
//
//   node web/tests/screenshot.mjs BUILD/bin/subvec docs/figures/serve-editor.jpg \
//       [docs/figures/serve-fill.jpg docs/figures/serve-points.jpg]
import { findChromium, launch, serve, stop, openEditor, idle, client } from './harness.mjs';

const [binary, out, fillOut, pointsOut] = process.argv.slice(2);
const server = await serve(binary, ['docs/figures/butterfly.svec']);
const browser = await launch(findChromium());
try {
  const { page } = await openEditor(browser, server.url, { width: 1280, height: 900 });
  // Drag the left wing's upper edge up.
  await page.keyboard.press('d');
  await page.evaluate(() => {
    const el = document.getElementById('sigma');
    el.value = '45';
    el.dispatchEvent(new Event('input'));
  });
  const path = [[111, 126], [104, 104]];
  const [x0, y0] = await client(page, ...path[0]);
  await page.mouse.move(x0, y0);
  await page.mouse.down();
  for (let i = 1; i <= 12; ++i) {
    const t = i / 12;
    const [x, y] = await client(page, 111 + (104 - 111) * t, 126 + (104 - 126) * t);
    await page.mouse.move(x, y);
    await page.waitForTimeout(30);
  }
  await page.mouse.up();
  await idle(page);
  // TRANSFORM the white patch of the left wing to yellow.
  await page.keyboard.press('c');
  await page.keyboard.press('b');  // blend -> transform
  await page.locator('input[name=pick][value=vertex]').check();
  await page.locator('#color').fill('#ffbe14');
  await page.evaluate(() => {
    const el = document.getElementById('radius');
    el.value = '40';
    el.dispatchEvent(new Event('input'));
  });
  const [cx, cy] = await client(page, 160, 175);
  await page.mouse.click(cx, cy);
  await idle(page);
  await page.evaluate(() => document.getElementById('show-features').click());
  await page.keyboard.press('d');
  await page.evaluate(() => { document.getElementById('panel').scrollTop = 0; });
  await page.waitForTimeout(300);
  await page.screenshot({ path: out });
  if (fillOut) {
    // A fill: the region pick, one click on a black wing; the mouse then rests on the other
    // wing's white spot, whose region (white points) a click would change.
    await page.evaluate(() => document.getElementById('show-features').click());
    await page.keyboard.press('c');
    await page.keyboard.press('b');  // transform -> blend
    await page.locator('input[name=pick][value=region]').check();
    await page.evaluate(() => {
      for (const [id, v] of [['radius', '201'], ['amount', '0.85']]) {
        const el = document.getElementById(id);
        el.value = v;
        el.dispatchEvent(new Event('input'));
      }
    });
    await page.locator('#color').fill('#c81e3c');
    const [wx, wy] = await client(page, 400, 180);
    await page.mouse.click(wx, wy);
    await idle(page);
    const [sx, sy] = await client(page, 330, 185);
    await page.mouse.move(sx, sy, { steps: 4 });
    await page.waitForTimeout(600);
    await page.screenshot({ path: fillOut });
  }
  if (pointsOut) {
    // A box selection of control points, the box still held.
    await page.keyboard.press('p');
    const [bx, by] = await client(page, 250, 90), [ex, ey] = await client(page, 330, 150);
    await page.mouse.move(bx, by);
    await page.mouse.down();
    await page.mouse.move(ex, ey, { steps: 6 });
    await page.mouse.up();
    await idle(page);
    const [cx2, cy2] = await client(page, 230, 200), [dx2, dy2] = await client(page, 300, 245);
    await page.keyboard.down('Shift');
    await page.mouse.move(cx2, cy2);
    await page.mouse.down();
    await page.mouse.move(dx2, dy2, { steps: 6 });
    await page.waitForTimeout(300);
    await page.screenshot({ path: pointsOut });
    await page.mouse.up();
    await page.keyboard.up('Shift');
  }
} finally {
  await browser.close();
  await stop(server);
}
