// microdex-station --screenshot FILE.png: the station's own view page, rendered by headless
// Chromium (Debian's, software WebGL), saved once it has drawn `--frames` state frames.
// node screenshot.mjs --url URL --out FILE.png [--frames N] [--width W] [--height H]
import { createRequire } from 'node:module';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const require = createRequire(join(here, '../../common/view/package.json'));
const { chromium } = require('playwright-core');

const opt = { frames: '10', width: '1280', height: '720' };
for (let i = 2; i + 1 < process.argv.length; i += 2) opt[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!opt.url || !opt.out) {
  console.error('screenshot.mjs: --url and --out required');
  process.exit(2);
}
const profile = mkdtempSync(join(tmpdir(), 'microdex-shot-'));
let status = 0;
let context;
try {
  context = await chromium.launchPersistentContext(profile, {
    executablePath: process.env.MICRODEX_CHROMIUM || '/usr/bin/chromium',
    headless: true,
    viewport: { width: Number(opt.width), height: Number(opt.height) },
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
  });
  const page = await context.newPage();
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
  await context?.close().catch(() => undefined);
  rmSync(profile, { recursive: true, force: true });
}
process.exit(status);
