// microdex-replay --render DIR: the console page of the replay's own console, rendered by
// headless Chromium (Debian's, software WebGL) while the recording plays.
//   node render.mjs --url URL --out DIR --every-ms MS --stations N [--speed X] [--width W]
//                   [--height H]
// Prints "render: page open" once the page is up (the replay then starts playing). From the
// first state drawn for each of the N stations on, saves the whole console every MS ms as
// DIR/console_NNNNN.png and appends a row to DIR/index.csv: the file, ms since the page
// opened, about how far into the replay that is in session seconds (the ms times the speed:
// the replay starts as the page opens), and per station trainee, score and progress. When its
// standard input closes (the replay has ended) it saves a last picture, then each station's
// tile enlarged as DIR/station_ID.png, and exits 0; 1 when the page never showed the N
// stations.
import { appendFileSync, mkdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { openHeadless } from '../../common/view/headless.mjs';

const opt = { 'every-ms': '1000', stations: '1', speed: '1', width: '1280', height: '720' };
for (let i = 2; i + 1 < process.argv.length; i += 2) opt[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
if (!opt.url || !opt.out) {
  console.error('render.mjs: --url and --out required');
  process.exit(2);
}
const everyMs = Math.max(50, Number(opt['every-ms']));
const stations = Math.max(1, Number(opt.stations));
mkdirSync(opt.out, { recursive: true });

let ended = false;
process.stdin.on('data', () => undefined);
process.stdin.on('end', () => { ended = true; });
process.stdin.on('error', () => { ended = true; });
process.on('SIGTERM', () => { ended = true; });

const csvField = (s) => (/[",\n]/.test(s) ? `"${s.replaceAll('"', '""')}"` : s);
let status = 0;
let browser;
try {
  browser = await openHeadless({ width: Number(opt.width), height: Number(opt.height) });
  const { page } = browser;
  await page.goto(opt.url);
  await page.waitForFunction(() => window.microdexConsole !== undefined, null, { timeout: 30000 });
  const t0 = Date.now();
  console.log('render: page open');
  const allDrawn = () => page.evaluate((n) => {
    const c = window.microdexConsole;
    return c.stations.length >= n && c.tilesDrawn >= n;
  }, stations);
  while (!ended && !(await allDrawn())) await page.waitForTimeout(100);
  if (!(await allDrawn())) {
    throw new Error(`the console never showed ${stations} station(s) drawn`);
  }
  const ids = await page.evaluate(() => window.microdexConsole.stations.map((s) => s.id));
  const index = join(opt.out, 'index.csv');
  writeFileSync(index, ['file', 'page_ms', 'session_s', ...ids.flatMap((id) => [`${id}.trainee`, `${id}.score`,
                                                                    `${id}.progress`])]
    .map(csvField).join(',') + '\n');
  let k = 0;
  const shoot = async () => {
    const name = `console_${String(k++).padStart(5, '0')}.png`;
    const ms = Date.now() - t0;
    await page.screenshot({ path: join(opt.out, name) });
    const list = await page.evaluate(() => window.microdexConsole.stations);
    const cells = ids.flatMap((id) => {
      const s = list.find((x) => x.id === id);
      return s ? [s.trainee, s.score?.toFixed(1) ?? '', s.progress?.toFixed(3) ?? ''] : ['', '', ''];
    });
    appendFileSync(index, [name, String(ms), (ms * Number(opt.speed) / 1000).toFixed(2), ...cells].map(csvField).join(',') + '\n');
  };
  let next = Date.now();
  while (!ended) {
    await shoot();
    next += everyMs;
    while (!ended && Date.now() < next) await page.waitForTimeout(Math.min(50, next - Date.now()));
  }
  await page.waitForTimeout(300);  // the last states on their way to the page
  await shoot();
  for (const id of ids) {
    const tile = page.locator(`.tile[data-station="${id}"]`);
    const viewport = tile.locator('.viewport');
    await viewport.click();
    await page.waitForTimeout(800);  // redrawn at its new size
    await viewport.screenshot({ path: join(opt.out, `station_${id.replace(/[^A-Za-z0-9_.-]/g, '_')}.png`) });
    await viewport.click();
  }
  console.log(`render: ${k} console pictures and ${ids.length} station pictures in ${opt.out}`);
} catch (e) {
  console.error(`render: ${String(e.message ?? e).split('\n')[0]}`);
  status = 1;
} finally {
  await browser?.close();
}
process.exit(status);
