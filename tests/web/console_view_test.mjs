// The instructor's console in headless Chromium: three live stations on three scenes are
// mirrored as three drawn tiles with their scores; switching a cue on for one station shows
// that station's acknowledgement (applied at step N) beside the command, and the station's
// state reports the cue in force; the other stations get none. A bad cue gets an error. A
// cue from the all-stations panel is one command that every station acknowledges in its tile;
// the score plot draws a line per station.
// The instructor runs in a folder of its own where the stations' scene paths (relative to
// theirs) lead nowhere: it draws their scenes from the SceneDescription topic alone.
// node console_view_test.mjs --bin BUILD/bin --out DIR
import { existsSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { launchBrowser, sourceDir } from './browser.mjs';
import { args, check, decodePng, hsv, startProcess, stopProcess, waitFor } from './harness.mjs';

const a = args({ bin: join(sourceDir, 'build/bin'), out: join(sourceDir, 'build/web-artifacts') });
// A partition of its own: stations of other runs on this machine stay out of this console.
const dds = ['--partition', `web-console-${process.pid}`];
const scenes = ['needle_tube', 'thread_pull', 'tissue_press'];
const ids = scenes.map((s) => `web-${s}`);
const elsewhere = mkdtempSync(join(tmpdir(), 'microdex-console-'));
const scenePath = (s) => `assets/scenes/${s}.yaml`; // relative to the stations' folder
check(!existsSync(join(elsewhere, scenePath(scenes[0]))), 'the instructor\'s folder has no scene files');
const instructor = await startProcess(join(a.bin, 'microdex-instructor'),
                                      ['--http', '0', '--duration', '180', ...dds],
                                      /console: http:\/\/127\.0\.0\.1:(\d+)\//, { cwd: elsewhere });
const stations = [];
for (const [i, s] of scenes.entries()) {
  stations.push(await startProcess(join(a.bin, 'microdex-station'), [
    '--scene', scenePath(s), '--station-id', ids[i],
    '--trainee', `trainee ${i + 1}`, '--no-realtime', '--duration', '150', ...dds,
  ], /station|info/, { cwd: sourceDir }));
}
const url = `http://127.0.0.1:${instructor.match[1]}/`;
const { context, close } = await launchBrowser({ width: 1280, height: 800 });
try {
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.goto(url);
  await waitFor(() => page.evaluate((n) => {
    const c = window.microdexConsole;
    return c && c.stations.length === n && c.tilesDrawn === n &&
        c.framesBySlot.filter((k) => k >= 10).length === n;
  }, ids.length), 'three stations listed, drawn, with frames', 40000);
  const listed = await page.evaluate(() => window.microdexConsole.stations.map((s) => s.id));
  check(JSON.stringify(listed) === JSON.stringify([...ids].sort()),
        `the console lists exactly the three stations (${listed.join(', ')})`);
  check(await page.evaluate(() => window.microdexConsole.badFrames) === 0, 'every frame decodes');
  // The scenes came over DDS (the instructor cannot read the paths the stations name).
  await waitFor(() => page.evaluate((n) => Object.values(window.microdexConsole.sceneNames)
      .filter((x) => x && x !== '(no scene)').length === n, ids.length),
  'every tile has its station\'s scene', 20000);
  const names = await page.evaluate(() => window.microdexConsole.sceneNames);
  check(names['web-needle_tube'] === 'needle-in-tube' && names['web-thread_pull'] === 'thread-pull' &&
        names['web-tissue_press'] === 'tissue-press',
        `each tile has its station's scene, sent over DDS: ${JSON.stringify(names)}`);
  const tiles = await page.locator('.tile').count();
  check(tiles === 3, `three tiles (${tiles})`);
  await page.waitForTimeout(1000);
  const shot = decodePng(await page.screenshot({ path: join(a.out, 'console_three_stations.png') }));
  // Each tile shows its own scene: the needle's colour, the thread's blue, the skin's tone.
  const looks = {
    'web-needle_tube': (c) => c.h >= 170 && c.h <= 205 && c.s >= 0.35 && c.v >= 0.3,
    'web-thread_pull': (c) => c.h >= 220 && c.h <= 245 && c.s >= 0.5 && c.v >= 0.4,
    'web-tissue_press': (c) => c.h >= 5 && c.h <= 30 && c.s >= 0.2 && c.s <= 0.6 && c.v >= 0.5,
  };
  const counts = {};
  for (const id of ids) {
    const r = await page.locator(`.tile[data-station="${id}"] .viewport`).boundingBox();
    for (const [look, is] of Object.entries(looks)) {
      let n = 0;
      for (let y = Math.ceil(r.y); y < r.y + r.height - 1; ++y) {
        for (let x = Math.ceil(r.x); x < r.x + r.width - 1; ++x) {
          const i = (y * shot.width + x) * 4;
          if (is(hsv(shot.rgba[i], shot.rgba[i + 1], shot.rgba[i + 2]))) ++n;
        }
      }
      counts[`${id}/${look}`] = n;
    }
  }
  check(counts['web-needle_tube/web-needle_tube'] > 30 && counts['web-thread_pull/web-needle_tube'] === 0,
        `the needle tile shows the needle (${counts['web-needle_tube/web-needle_tube']} px), the thread tile none`);
  check(counts['web-thread_pull/web-thread_pull'] > 10 && counts['web-needle_tube/web-thread_pull'] === 0,
        `the thread tile shows the thread (${counts['web-thread_pull/web-thread_pull']} px), the needle tile none`);
  check(counts['web-tissue_press/web-tissue_press'] > 5000 && counts['web-needle_tube/web-tissue_press'] < 100,
        `the tissue tile shows the tissue (${counts['web-tissue_press/web-tissue_press']} px)`);
  const scores = await page.locator('#scores tbody tr').count();
  check(scores === 3, 'the score table has three rows');

  // Guidance on for the second station only.
  const target = ids[1];
  const tile = page.locator(`.tile[data-station="${target}"]`);
  await tile.locator('input[data-strength="convergent"]').fill('450');
  await tile.locator('input[data-cue="convergent"]').check();
  const ack = await waitFor(async () => {
    const t = await tile.locator('.ack').first().textContent().catch(() => null);
    return t && /applied at step \d+/.test(t) ? t : null;
  }, 'the acknowledgement of the cue', 20000);
  check(/convergent 450 → applied at step \d+/.test(ack), `acknowledgement shown: "${ack}"`);
  const convergentDot = (t) => t.locator('.cue:has(input[data-cue="convergent"]) .inforce.on');
  await waitFor(() => convergentDot(tile).count().then((n) => n === 1),
                'the station reporting the cue in force', 10000);
  check(true, 'the station reports the guidance cue in force');
  for (const other of [ids[0], ids[2]]) {
    const n = await page.locator(`.tile[data-station="${other}"] .ack`).count();
    const on = await convergentDot(page.locator(`.tile[data-station="${other}"]`)).count();
    check(n === 0 && on === 0, `station ${other}: no cue sent, none in force`);
  }
  // Off: the station switches that kind off.
  await tile.locator('input[data-cue="convergent"]').uncheck();
  await waitFor(() => convergentDot(tile).count().then((n) => n === 0),
                'the cue cleared at the station', 10000);
  const offAck = await waitFor(async () => {
    const t = await tile.locator('.ack').first().textContent().catch(() => null);
    return t && /convergent off → applied at step \d+/.test(t) ? t : null;
  }, 'the acknowledgement of switching it off', 20000);
  check(true, `switching the cue off clears it at the station ("${offAck}")`);
  await page.screenshot({ path: join(a.out, 'console_cue_ack.png') });

  // A bad cue from a page: an error reply naming the reason.
  const reply = await page.evaluate((id) => new Promise((resolve) => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') return;
      const m = JSON.parse(e.data);
      if (m.type === 'error') resolve(m.error);
    };
    ws.onopen = () => ws.send(`cue ${id} convergent 1e9`);
    setTimeout(() => resolve(null), 5000);
  }), target);
  check(reply && reply.includes('stiffness'), `an out-of-range cue is refused: "${reply}"`);
  const kinds = await tile.locator('input[data-cue]').count();
  check(kinds === 13, `the panel offers every cue kind but clear (${kinds})`);

  // The panel for all stations: one command, acknowledged by each station in its own tile.
  const all = page.locator('#all');
  check(await all.locator('input[data-cue]').count() === kinds, 'the all-stations panel offers the same cue kinds');
  await all.locator('input[data-strength="amplified_tremor"]').fill('2.5');
  await all.locator('input[data-cue="amplified_tremor"]').check();
  for (const id of ids) {
    const t = await waitFor(async () => {
      const texts = await page.locator(`.tile[data-station="${id}"] .ack`).allTextContents();
      return texts.find((x) => /amplified_tremor 2\.5 → applied at step \d+/.test(x)) ?? null;
    }, `station ${id} acknowledging the cue sent to all`, 20000);
    check(true, `station ${id} acknowledges the cue sent to all ("${t}")`);
  }
  const allIds = await page.evaluate(() => [...document.querySelectorAll('.tile')].map((t) =>
    [...t.querySelectorAll('.ack')].filter((a) => a.textContent.includes('amplified_tremor 2.5'))
      .map((a) => a.dataset.cueId)).flat());
  check(allIds.length === ids.length && new Set(allIds).size === 1,
        `one command (cue #${allIds[0]}) for all three stations`);
  await all.locator('input[data-cue="amplified_tremor"]').uncheck();

  // The score plot: a line per station, with the scores heard so far.
  const lines = await waitFor(() => page.evaluate((n) => {
    const ps = [...document.querySelectorAll('#plot polyline')];
    return ps.length === n && ps.every((p) => p.getAttribute('points').split(' ').length >= 4)
      ? ps.map((p) => [p.dataset.station, p.getAttribute('points').split(' ').length]) : null;
  }, ids.length), 'a score line per station', 20000);
  check(JSON.stringify(lines.map((l) => l[0]).sort()) === JSON.stringify([...ids].sort()),
        `the score plot has a line per station (${lines.map((l) => l.join(': ')).join(', ')} points)`);
  await page.locator('#plot').screenshot({ path: join(a.out, 'console_score_plot.png') });

  // Enlarge a tile by clicking it.
  const before = await tile.locator('.viewport').boundingBox();
  await tile.locator('.viewport').click();
  await page.waitForTimeout(500);
  const after = await tile.locator('.viewport').boundingBox();
  check(after.width > before.width * 1.5, `clicking a tile enlarges it (${before.width} → ${after.width} px)`);
  await page.screenshot({ path: join(a.out, 'console_enlarged.png') });
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);
  writeFileSync(join(a.out, 'console_view.json'), JSON.stringify({ url, ack }, null, 1));
} finally {
  await close();
  for (const s of stations) await stopProcess(s.child);
  await stopProcess(instructor.child);
  rmSync(elsewhere, { recursive: true, force: true });
}
