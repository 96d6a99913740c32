// The screenshot in docs/serve.md: the butterfly of docs/editing.md edited in the page with the
// mouse (the first drag and the first TRANSFORM of docs/figures/butterfly-ops.json), the feature
// overlay on, the dragged feature selected.
//
//   node web/tests/screenshot.mjs BUILD/bin/subvec docs/figures/serve-editor.jpg
import { findChromium, launch, serve, stop, openEditor, idle, client } from './harness.mjs';

const [binary, out] = process.argv.slice(2);
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
  await page.keyboard.press('f');  // feature -> vertex
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
} finally {
  await browser.close();
  await stop(server);
}
