// The console's recording and replay controls in headless Chromium (microdex-instructor --http
// --record-dir DIR): with a live station, "record" starts a recording into DIR and "stop" ends
// it; the recording is listed with its station and length. Playing it while the station is
// live is refused with the reason shown on the page; once the station has left, playing it
// brings the station back into the grid (alive, drawn, new frames), pause holds it, and it
// plays to its end, and the position slider seeks it back; played again from 1.5 s at ×2 it
// starts there. A second station's recording plays alongside ("+ alongside"), one stop ending
// both. A recording is renamed and deleted once the page has asked. A name that would leave
// DIR is refused. With --db, the final scores of two
// earlier runs of a trainee are drawn as a line over past sessions, with their scores.
// node console_session_test.mjs --bin BUILD/bin --out DIR
import { mkdtempSync, readFileSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { launchBrowser, sourceDir } from './browser.mjs';
import { args, check, startProcess, stopProcess, waitFor } from './harness.mjs';

const a = args({ bin: join(sourceDir, 'build/bin'), out: join(sourceDir, 'build/web-artifacts') });
const dds = ['--partition', `web-session-${process.pid}`];
const id = 'web-session';
const work = mkdtempSync(join(tmpdir(), 'microdex-console-session-'));
const recordings = join(work, 'recordings');
const instructor = await startProcess(join(a.bin, 'microdex-instructor'),
                                      ['--http', '0', '--record-dir', recordings, '--scene-dir',
                                       join(sourceDir, 'assets/scenes'), '--db', join(work, 'scores.db'),
                                       '--duration', '200', ...dds],
                                      /console: http:\/\/127\.0\.0\.1:(\d+)\//, { cwd: work });
// Two earlier runs of one trainee, to their task's end (unpaced), each scored in the database.
const pastScores = [];
const pastOutputs = [];  // for the failure message
for (const [k, skill] of ['0.3', '0.9'].entries()) {
  const out = join(work, `past-${k}.json`);
  const run = await startProcess(join(a.bin, 'microdex-station'), [
    '--scene', 'assets/scenes/tremor_hold.yaml', '--station-id', `web-past-${k}`, '--trainee', 'trainee P',
    '--skill', skill, '--seed', String(k + 1), '--unpaced', '--wait-for-recorder', '20', '--score-out', out, ...dds,
  ], /steps, score/, { cwd: sourceDir, timeoutMs: 40000 });
  await stopProcess(run.child);
  pastOutputs.push(run.output());
  pastScores.push(JSON.parse(readFileSync(out, 'utf8')).score);
}
const station = await startProcess(join(a.bin, 'microdex-station'), [
  '--scene', 'assets/scenes/needle_tube.yaml', '--station-id', id, '--trainee', 'trainee R',
  '--no-realtime', '--duration', '120', ...dds,
], /station|info/, { cwd: sourceDir });
const url = `http://127.0.0.1:${instructor.match[1]}/`;
const { context, close } = await launchBrowser({ width: 1280, height: 900 });
const probe = (page) => page.evaluate(() => {
  const c = window.microdexConsole;
  const s = c.stations.find((x) => x.id === 'web-session');
  return { session: c.session, station: s ?? null, frames: c.framesReceived, messages: c.sessionMessages.slice(),
           rejected: c.rejected.total };
});
try {
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.goto(url);
  await waitFor(() => page.evaluate(() => {
    const c = window.microdexConsole;
    const s = c && c.stations.find((x) => x.id === 'web-session');
    return c && c.session && s && s.presence === 'alive' && c.tilesDrawn >= 1 && c.framesReceived > 20;
  }), 'the live station drawn and the session controls listed', 40000);
  // The past sessions' plot: trainee P's two runs, with the scores they wrote.
  const past = await waitFor(() => page.evaluate(() => {
    const l = window.microdexConsole.past.lines.find((x) => x.trainee === 'trainee P');
    return l && l.sessions.length === 2 ? l : null;
  }), 'trainee P\'s two past sessions on the plot', 20000).catch(async (e) => {
    const lines = await page.evaluate(() => JSON.stringify(window.microdexConsole.past.lines));
    throw new Error(`${e.message}\nthe page's lines: ${lines}\ninstructor:\n${instructor.output().slice(-6000)}\n` +
                    `past runs:\n${pastOutputs.map((o) => o.slice(-3000)).join('\n---\n')}`);
  });
  const drawn = past.sessions.map((x) => x.score);
  check(drawn.every((v, i) => Math.abs(v - pastScores[i]) < 0.05) && past.scene.endsWith('tremor_hold.yaml'),
        `the past sessions' line holds the two runs' final scores in order (${drawn.map((v) => v.toFixed(1)).join(', ')} ` +
        `against --score-out ${pastScores.map((v) => v.toFixed(1)).join(', ')})`);
  check(await page.locator('#past polyline[data-trainee="trainee P"]').count() === 1 &&
        await page.locator('#past circle').count() >= 2, 'the plot draws the line with a dot per session');
  await page.locator('#past').screenshot({ path: join(a.out, 'console_past_scores.png') });
  check(await page.locator('#rec-start').isEnabled(), 'the record button is enabled');
  check(await page.locator('#rec-stop').isDisabled(), 'the stop button is disabled while not recording');

  // Record about 3 s of the live station.
  await page.locator('#rec-name').fill('lesson-1');
  await page.locator('#rec-start').click();
  const rec = await waitFor(async () => {
    const p = await probe(page);
    return p.session.recording && p.session.recording.written > 200 ? p.session.recording : null;
  }, 'the recording running with samples written', 15000);
  check(rec.file === 'lesson-1.db', `recording into lesson-1.db (${rec.file})`);
  check(/● recording lesson-1\.db/.test(await page.locator('#rec-status').textContent()),
        'the page shows the recording');
  await page.waitForTimeout(2500);
  await page.locator('#rec-stop').click();
  const listed = await waitFor(async () => {
    const p = await probe(page);
    const f = p.session.recordings.find((x) => x.file === 'lesson-1.db');
    return !p.session.recording && f && !f.recording && f.seconds > 0 ? f : null;
  }, 'the stopped recording listed', 15000);
  check(JSON.stringify(listed.stations) === JSON.stringify([id]) && listed.seconds >= 2,
        `lesson-1.db holds ${listed.stations.join(', ')} for ${listed.seconds.toFixed(1)} s`);
  check(readdirSync(recordings).includes('lesson-1.db'), 'the file is in the recording folder');
  const row = page.locator('#recordings tr[data-file="lesson-1.db"]');
  check(await row.count() === 1, 'the recordings table lists it');
  await page.locator('#session').screenshot({ path: join(a.out, 'console_session_recorded.png') });

  // Playing it while the station is live is refused, and the page says why.
  await row.locator('button[data-play]').click();
  const refused = await waitFor(async () => {
    const m = (await probe(page)).messages;
    return m.find((x) => /is live here/.test(x)) ?? null;
  }, 'the refusal of a replay of a live station', 10000);
  check(/station web-session of lesson-1\.db is live here/.test(refused), `refused: "${refused}"`);
  check((await page.locator('#session .msg').textContent()).includes('is live here'),
        'the refusal is shown under the controls');
  // A name that would leave the folder.
  await page.locator('#rec-name').fill('../escape');
  await page.locator('#rec-start').click();
  const badName = await waitFor(async () => (await probe(page)).messages.find((x) => /NAME/.test(x)) ?? null,
                                'the refusal of a bad name', 10000);
  check(/record start: NAME '\.\.\/escape' starts with '\.'/.test(badName), `refused: "${badName}"`);
  check(!readdirSync(work).some((f) => f.includes('escape')) && readdirSync(recordings).length >= 1,
        'nothing written outside the folder');

  // The station leaves; its recording replays into the console.
  await stopProcess(station.child);
  await waitFor(async () => (await probe(page)).station?.presence === 'left',
                'the station departed', 15000);
  const framesBefore = (await probe(page)).frames;
  await row.locator('button[data-play]').click();
  const playing = await waitFor(async () => {
    const p = await probe(page);
    return p.session.replay && !p.session.replay.done && p.station?.presence === 'alive' &&
        p.frames > framesBefore + 10 ? p : null;
  }, 'the replayed station alive again with new frames', 20000);
  check(playing.session.replay.file === 'lesson-1.db', 'the replay of lesson-1.db is playing');
  check(await page.locator('#rec-start').isDisabled(), 'recording is not offered during a replay');
  await page.screenshot({ path: join(a.out, 'console_session_replaying.png') });
  await page.locator('#rp-pause').click();
  await waitFor(async () => (await probe(page)).session.replay.paused, 'the replay paused', 5000);
  const at = (await probe(page)).session.replay.position_s;
  await page.waitForTimeout(1000);
  const still = (await probe(page)).session.replay.position_s;
  check(Math.abs(still - at) < 0.05, `paused, the position holds (${at.toFixed(2)} → ${still.toFixed(2)} s)`);
  check((await page.locator('#rp-pause').textContent()) === 'resume', 'the pause button offers resume');
  await page.locator('#rp-pause').click();
  // Dragged back on the position slider: the replay goes on from there, the station alive.
  const before = (await probe(page)).session.replay.position_s;
  await page.locator('#rp-seek').evaluate((el) => {
    el.value = '0.3';
    el.dispatchEvent(new Event('input'));
    el.dispatchEvent(new Event('change'));
  });
  const sought = await waitFor(async () => {
    const p = await probe(page);
    const r = p.session.replay;
    return r && !r.done && r.seeks === 1 ? { r, presence: p.station?.presence } : null;
  }, 'the replay sought back', 5000);
  check(sought.r.position_s < before && sought.r.position_s < 1.2 && sought.presence === 'alive',
        `sought back from ${before.toFixed(2)} to ${sought.r.position_s.toFixed(2)} s, the station ${sought.presence}`);
  const ended = await waitFor(async () => {
    const r = (await probe(page)).session.replay;
    return r && r.done ? r : null;
  }, 'the replay played to its end', 20000);
  check(!ended.stopped && ended.error === '' && ended.published > 100,
        `played to the end: ${ended.published} samples republished`);
  check(ended.scenes_missing.length === 0, `the recorded scene was found in --scene-dir (${ended.scenes_missing.join('; ')})`);
  const rejected = (await probe(page)).rejected;
  check(rejected === 0, `the console took every replayed sample, though it had seen the run live (${rejected} rejected)`);
  await waitFor(async () => (await probe(page)).station?.presence === 'left',
                'the replayed station left at the end', 10000);
  check(/played to the end/.test(await page.locator('#rp-status').textContent()), 'the page says it played to the end');
  // Again, from 1.5 s into the recording, at ×2: it starts there.
  await page.locator('#rp-from').fill('1.5');
  await page.locator('#rp-speed').selectOption('2');
  await row.locator('button[data-play]').click();
  const from = await waitFor(async () => {
    const r = (await probe(page)).session.replay;
    return r && !r.done && r.position_s > 0 ? r : null;
  }, 'the replay from 1.5 s playing', 10000);
  check(from.position_s >= 1.5 && from.speed === 2, `played from ${from.position_s.toFixed(2)} s at ×${from.speed}`);
  await waitFor(async () => (await probe(page)).session.replay.done, 'the second replay at its end', 15000);
  await page.locator('#session').screenshot({ path: join(a.out, 'console_session_played.png') });
  // A second station's recording, played alongside the first from the page.
  const other = await startProcess(join(a.bin, 'microdex-station'), [
    '--scene', 'assets/scenes/tremor_hold.yaml', '--station-id', 'web-session-b', '--trainee', 'trainee S',
    '--no-realtime', '--duration', '4', ...dds,
  ], /station|info/, { cwd: sourceDir });
  const presenceOf = async (sid) => page.evaluate((x) => window.microdexConsole.stations.find((s) => s.id === x)?.presence ?? null, sid);
  await waitFor(async () => (await presenceOf('web-session-b')) === 'alive', 'the second station alive', 20000);
  await page.locator('#rec-name').fill('lesson-2');
  await page.locator('#rec-start').click();
  await waitFor(async () => (await probe(page)).session.recording?.file === 'lesson-2.db', 'recording lesson-2', 5000);
  await page.waitForTimeout(2000);
  await page.locator('#rec-stop').click();
  await waitFor(async () => (await presenceOf('web-session-b')) === 'left', 'the second station left', 15000);
  await stopProcess(other.child);
  await waitFor(async () => (await page.locator('#recordings tr[data-file="lesson-2.db"] button[data-play]').count()) === 1 || null,
                'lesson-2 listed', 5000);
  await page.locator('#rp-from').fill('0');
  await page.locator('#rp-speed').selectOption('0.5');
  await row.locator('button[data-play]').click();
  await waitFor(async () => (await page.locator('#recordings tr[data-file="lesson-2.db"] button[data-add]').count()) === 1 || null,
                'lesson-2 offered alongside', 10000);
  await page.locator('#recordings tr[data-file="lesson-2.db"] button[data-add]').click();
  const both = await waitFor(async () => {
    const r = (await probe(page)).session.replay;
    return r && !r.done && r.files.length === 2 && (await presenceOf('web-session')) === 'alive' &&
        (await presenceOf('web-session-b')) === 'alive' ? r : null;
  }, 'both recordings playing, both stations alive', 15000);
  check(both.files.join(',') === 'lesson-1.db,lesson-2.db' && /lesson-1\.db \+ lesson-2\.db/.test(await page.locator('#rp-status').textContent()),
        `one replay of two files (${both.files.join(' + ')}: ${both.stations.join(', ')})`);
  await page.waitForTimeout(500);
  await page.screenshot({ path: join(a.out, 'console_session_two.png') });
  await page.locator('#rp-stop').click();
  await waitFor(async () => (await presenceOf('web-session')) === 'left' && (await presenceOf('web-session-b')) === 'left',
                'one stop ends both', 10000);
  // Renamed from the table: the page asks for the new name.
  page.once('dialog', (d) => d.accept('lesson-2b'));
  await page.locator('#recordings tr[data-file="lesson-2.db"] button[data-rename]').click();
  await waitFor(async () => (await probe(page)).messages.find((x) => /^renamed lesson-2\.db to lesson-2b\.db/.test(x)) ?? null,
                'the rename confirmed', 10000);
  check(readdirSync(recordings).includes('lesson-2b.db') && !readdirSync(recordings).includes('lesson-2.db'),
        'lesson-2.db renamed lesson-2b.db in the folder');
  await waitFor(async () => (await page.locator('#recordings tr[data-file="lesson-2b.db"]').count()) === 1 || null,
                'the renamed row in the table', 5000);
  // Deleted from the table, once confirmed.
  let asked = '';
  page.once('dialog', (d) => { asked = d.message(); d.accept(); });
  await row.locator('button[data-delete]').click();
  await waitFor(async () => (await probe(page)).messages.find((x) => /^deleted lesson-1\.db/.test(x)) ?? null,
                'the deletion confirmed', 10000);
  check(/Delete the recording lesson-1\.db\?/.test(asked), `the page asked first ("${asked}")`);
  check(!readdirSync(recordings).includes('lesson-1.db'), 'the file is gone from the folder');
  await waitFor(async () => (await page.locator('#recordings tr[data-file="lesson-1.db"]').count()) === 0 || null,
                'the row gone from the table', 5000);
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);
} finally {
  await close();
  await stopProcess(station.child);
  await stopProcess(instructor.child);
  rmSync(work, { recursive: true, force: true });
}
