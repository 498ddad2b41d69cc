// microdex-station --screenshot FILE.png: the station's own view page, rendered by headless
// Chromium (Debian's, software WebGL), saved once it has drawn `--frames` state frames.
// node screenshot.mjs --url URL --out FILE.png [--frames N] [--width W] [--height H]
import { openHeadless } from '../../common/view/headless.mjs';

const opt = { frames: '10', width: '1280', height: '720' };
for (let i = 2; i + 1 < process.argv.length; i += 2) opt[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!opt.url || !opt.out) {
  console.error('screenshot.mjs: --url and --out required');
  process.exit(2);
}
let status = 0;
let browser;
try {
  browser = await openHeadless({ width: Number(opt.width), height: Number(opt.height) });
  const { page } = browser;
  await page.goto(opt.url);
  await page.waitForFunction((n) => (window.microdexView?.framesDrawn ?? 0) >= n,
                             Number(opt.frames), { timeout: 60000, polling: 100 });
  await page.evaluate(() => { window.microdexView.freeze = true; });
  await page.waitForTimeout(200);
  await page.screenshot({ path: opt.out });
  console.log(`screenshot: ${opt.out}`);
} catch (e) {
  console.error(`screenshot: ${String(e.message ?? e).split('\n')[0]}`);
  status = 1;
} finally {
  await browser?.close();
}
process.exit(status);
