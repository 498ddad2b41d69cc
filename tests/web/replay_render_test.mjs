// microdex-replay --render: a session recorded by the instructor (one needle_tube station, 5 s)
// is replayed at 2x and drawn through the console page in headless Chromium. The folder gets
// a console picture per second of the session with its row in index.csv (the station's score
// in every row), each picture drawn (not blank), the last one with the needle in the station's
// tile, and the station's enlarged view with the needle larger still. The replay runs where the
// recorded scene path leads nowhere: without --scene-dir it names the station whose scene is
// missing; with it, it sends the scene to its console over DDS. A bad --render-every is refused
// before anything starts.
// node replay_render_test.mjs --bin BUILD/bin --out DIR
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readdirSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { sourceDir } from './browser.mjs';
import { args, check, decodePng, hsv, startProcess } from './harness.mjs';

const a = args({ bin: join(sourceDir, 'build/bin'), out: join(sourceDir, 'build/web-artifacts') });
const work = mkdtempSync(join(tmpdir(), 'microdex-render-test-'));
const recording = join(work, 'session.db');
const dir = join(a.out, 'replay_render');
rmSync(dir, { recursive: true, force: true });
const exited = (child) => new Promise((resolve) => {
  if (child.exitCode !== null) resolve(child.exitCode);
  else child.on('exit', (code) => resolve(code));
});
try {
  // Record: the instructor outlives the station, which stops by itself after 5 s.
  const recordDds = ['--partition', `web-render-rec-${process.pid}`];
  const instructor = await startProcess(join(a.bin, 'microdex-instructor'), [
    '--headless', '--table-period', '0', '--record', recording, '--duration', '12', ...recordDds,
  ], /instructor \S+ on domain/);
  const station = await startProcess(join(a.bin, 'microdex-station'), [
    '--scene', 'assets/scenes/needle_tube.yaml', '--station-id', 'web-render',
    '--trainee', 'render trainee', '--no-realtime', '--duration', '5', ...recordDds,
  ], /station|info/, { cwd: sourceDir });
  const stationCode = await exited(station.child);
  check(stationCode === 0, `the station ran its 5 s (exit ${stationCode}: ${station.output().slice(-400)})`);
  check(await exited(instructor.child) === 0 && existsSync(recording), 'the session was recorded');

  const refused = spawnSync(join(a.bin, 'microdex-replay'),
                            [recording, '--render', dir, '--render-every', '0'], { encoding: 'utf8' });
  check(refused.status === 2 && /--render-every: expected/.test(refused.stderr) && !existsSync(dir),
        `--render-every 0 is refused before anything starts ("${refused.stderr.trim()}")`);

  // From a folder where the recorded scene path (relative to the station's) leads nowhere: the
  // scene must be found by name and sent over DDS to the replay's console.
  const play = ['--render', dir, '--speed', '2', '--partition', `web-render-play-${process.pid}`];
  const lost = spawnSync(join(a.bin, 'microdex-replay'), [recording, ...play],
                         { encoding: 'utf8', cwd: work, timeout: 60000 });
  check(lost.status === 2 && /station web-render: scene 'assets\/scenes\/needle_tube\.yaml' not found \(give its folder with --scene-dir\)/.test(lost.stderr) &&
        !existsSync(dir), `without the scene's files --render says which station's scene is missing ("${lost.stderr.trim()}")`);
  const t0 = Date.now();
  const replay = spawnSync(join(a.bin, 'microdex-replay'), [
    recording, ...play, '--scene-dir', join(sourceDir, 'assets/scenes'),
  ], { encoding: 'utf8', cwd: work, timeout: 120000 });
  console.log(replay.stdout.trim());
  check(replay.status === 0, `microdex-replay --render exits 0 (${replay.status}; ${replay.stderr.trim()})`);
  console.log(`replayed and rendered in ${((Date.now() - t0) / 1000).toFixed(1)} s`);

  const pictures = readdirSync(dir).filter((f) => /^console_\d{5}\.png$/.test(f)).sort();
  const rows = readFileSync(join(dir, 'index.csv'), 'utf8').trim().split('\n').map((l) => l.split(','));
  check(rows[0].join(',') === 'file,page_ms,session_s,web-render.trainee,web-render.score,web-render.progress',
        `index.csv names its columns (${rows[0].join(',')})`);
  const body = rows.slice(1);
  // 5 s of session, a picture a second from the first drawn state, and one at the end.
  check(pictures.length >= 4 && pictures.length <= 8, `a console picture per second of the session (${pictures.length})`);
  check(body.length === pictures.length && body.every((r, i) => r[0] === pictures[i]),
        'index.csv has a row per picture, in order');
  check(body.every((r) => r[3] === 'render trainee' && Number.isFinite(Number(r[4])) && r[4] !== ''),
        `every row has the trainee and a score (${body.map((r) => r[4]).join(' ')})`);
  const sessionS = body.map((r) => Number(r[2]));
  check(sessionS.every((s, i) => i === 0 || s > sessionS[i - 1]), `the pictures' session times rise (${sessionS.join(' ')})`);

  const needle = (c) => c.h >= 170 && c.h <= 205 && c.s >= 0.35 && c.v >= 0.3;
  const count = (png, is) => {
    let n = 0;
    for (let i = 0; i < png.width * png.height; ++i) {
      if (is(hsv(png.rgba[4 * i], png.rgba[4 * i + 1], png.rgba[4 * i + 2]))) ++n;
    }
    return n;
  };
  for (const f of pictures) {
    const png = decodePng(readFileSync(join(dir, f)));
    const lit = count(png, (c) => c.v > 0.35);
    check(png.width === 1280 && png.height === 720 && lit > 2000, `${f} is drawn (${lit} bright px)`);
  }
  const last = decodePng(readFileSync(join(dir, pictures.at(-1))));
  const inLast = count(last, needle);
  check(inLast > 30, `the last console picture shows the needle (${inLast} px)`);
  const big = decodePng(readFileSync(join(dir, 'station_web-render.png')));
  const inBig = count(big, needle);
  check(big.width > 600 && inBig > 2 * inLast, `the station's enlarged view shows the needle larger (${inBig} px, ${big.width}x${big.height})`);
} finally {
  rmSync(work, { recursive: true, force: true });
}
process.exit(0);
