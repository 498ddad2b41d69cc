// Speed of the view pages in headless Chromium with software WebGL (SwiftShader): frames per
// second of the station view at 1280 x 720 and of the console with 8 stations, and the
// state-to-screen latency (the tick stamp of the state → the page drawing it, both
// CLOCK_REALTIME on this machine) at p50 / p99. Writes a JSON report and prints a table.
// node measure_view.mjs --bin BUILD/bin --out DIR [--seconds S] [--stations N] [--limit S]
//   [--only station|console] [--replay 0|1] [--instructor_args "ARGS"] (e.g. "--inputs")
//   [--station_args "ARGS"] (the console's stations, e.g. "--mirror-rate 30")
//   [--trace FILE] (a Chrome trace of the live console's measured window, for chrome://tracing
//   or Perfetto)
// Bounded: every wait has its own time-out and the whole run stops after --limit seconds
// (default 300), writing what it measured so far; each step is reported on stderr with the
// time since the start.
import { readFileSync, rmSync, writeFileSync } from 'node:fs';
import { spawnSync } from 'node:child_process';
import { dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { startReplay } from './replay_console.mjs';
import { join } from 'node:path';
import { launchBrowser, sourceDir } from './browser.mjs';
import { loadavg } from 'node:os';
import { args, startProcess, stopProcess, waitFor } from './harness.mjs';


const here = dirname(fileURLToPath(import.meta.url));
const a = args({ web: join(sourceDir, 'build/web'), bin: join(sourceDir, 'build/bin'), out: join(sourceDir, 'build/report'),
                 seconds: '10', stations: '8', scene: 'needle_tube', realtime: '0',
                 width: '1280', height: '720', only: '', query: '', limit: '300', replay: '1',
                 console_query: '', instructor_args: '', station_args: '', trace: '' });
const seconds = Number(a.seconds);
const t0 = Date.now();
const progress = (what) => process.stderr.write(`[${((Date.now() - t0) / 1000).toFixed(0).padStart(4)} s] ${what}\n`);
const rt = a.realtime === '1' ? [] : ['--no-realtime'];
const quantile = (v, q) => {
  if (!v.length) return NaN;
  const s = [...v].sort((x, y) => x - y);
  return s[Math.min(s.length - 1, Math.floor(q * s.length))];
};
// CPU time of a process so far (user + system, s; Linux /proc).
const cpuSeconds = (pid) => {
  try {
    const f = readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
    return (Number(f[11]) + Number(f[12])) / 100;
  } catch {
    return NaN;
  }
};
const summary = (lat) => ({ n: lat.length, p50_ms: quantile(lat, 0.5), p99_ms: quantile(lat, 0.99),
                            max_ms: quantile(lat, 1) });

async function measurePage(page, probeName) {
  // Warm up, then count frames and collect latencies over the window.
  progress(`${probeName}: 2 s warm-up, then ${seconds} s measured`);
  await page.waitForTimeout(2000);
  const start = await page.evaluate((p) => {
    const v = window[p];
    v.latencyMs.length = 0;
    v.receivedMs.length = 0;
    if (v.encodedMs) v.encodedMs.length = 0;
    if (v.waitedMs) v.waitedMs.length = 0;
    window.__frames = 0;
    window.__tileDraws0 = v.tileDrawsTotal ?? 0;
    const count = () => { ++window.__frames; requestAnimationFrame(count); };
    requestAnimationFrame(count);
    return performance.now();
  }, probeName);
  await page.waitForTimeout(seconds * 1000);
  return page.evaluate(([p, t0]) => {
    const v = window[p];
    return { fps: window.__frames / ((performance.now() - t0) / 1000), latency: [...v.latencyMs],
             received: [...v.receivedMs], encoded: [...(v.encodedMs ?? [])],
             waited: [...(v.waitedMs ?? [])],
             tileDrawsPerSecond: ((v.tileDrawsTotal ?? 0) - window.__tileDraws0) / ((performance.now() - t0) / 1000),
             budget: v.budget };
  }, [probeName, start]);
}

const report = { seconds, machine_load: (await import('node:os')).loadavg() };
const W = Number(a.width), H = Number(a.height);
const writeReport = () => {
  report.machine_load_after = loadavg();
  writeFileSync(join(a.out, 'view_speed.json'), JSON.stringify(report, null, 1));
};
// The whole run's bound: past it, what was measured is written and the run stops (the
// harness kills the processes it started on exit).
const limit = setTimeout(() => {
  progress(`time limit ${a.limit} s reached: stopping with what was measured`);
  report.stopped_at_limit = true;
  writeReport();
  process.exit(3);
}, Number(a.limit) * 1000);
limit.unref();
progress('starting the browser');
const { context, close } = await launchBrowser({ width: W, height: H });
try {
  // Station view.
  if (a.only !== 'console') {
  progress(`station view: ${a.scene}`);
  const station = await startProcess(join(a.bin, 'microdex-station'), [
    '--scene', join(sourceDir, `assets/scenes/${a.scene}.yaml`), '--view', '0', ...rt,
    '--duration', String(seconds + 60), '--partition', `measure-${process.pid}-s`,
  ], /view: http:\/\/127\.0\.0\.1:(\d+)\//);
  const page = await context.newPage();
  await page.goto(`http://127.0.0.1:${station.match[1]}/${a.query ? `?${a.query}` : ''}`);
  await waitFor(() => page.evaluate(() => (window.microdexView?.framesDrawn ?? 0) >= 5), 'frames', 30000);
  const s = await measurePage(page, 'microdexView');
  report.station = { scene: a.scene, width: W, height: H, fps: s.fps, latency: summary(s.latency),
                    received: summary(s.received), encoded: summary(s.encoded), load_during: loadavg() };
  progress(`station view: ${s.fps.toFixed(1)} fps`);
  await page.close();
  await stopProcess(station.child);
  }
  if (a.only !== 'station') {

  // Console with N stations.
  const n = Number(a.stations);
  progress(`console: the instructor and ${n} stations`);
  const dds = ['--partition', `measure-${process.pid}-c`];
  const instructor = await startProcess(join(a.bin, 'microdex-instructor'),
                                        ['--http', '0', '--duration', String(seconds + 90), ...dds,
                                         ...a.instructor_args.split(' ').filter(Boolean)],
                                        /console: http:\/\/127\.0\.0\.1:(\d+)\//);
  // The module scenes run until stopped (the training scenes end with their task).
  const scenes = ['needle_tube', 'thread_pull', 'tissue_press', 'suture_on_tissue',
                  'needle_tube_minimal', 'needle_tremor_only', 'needle_tube', 'thread_pull'];
  const stations = [];
  for (let i = 0; i < n; ++i) {
    stations.push(await startProcess(join(a.bin, 'microdex-station'), [
      '--scene', join(sourceDir, `assets/scenes/${scenes[i % scenes.length]}.yaml`),
      '--station-id', `m${i}`, ...rt, '--duration', String(seconds + 60), ...dds,
      ...a.station_args.split(' ').filter(Boolean),
    ], /station|info/));
  }
  const cpage = await context.newPage();
  progress('console: waiting for every tile to be drawn');
  await cpage.goto(`http://127.0.0.1:${instructor.match[1]}/${a.console_query ? `?${a.console_query}` : ''}`);
  await waitFor(() => cpage.evaluate((k) => window.microdexConsole?.tilesDrawn === k, n),
                `${n} tiles drawn`, 60000);
  const cpu0 = [cpuSeconds(instructor.child.pid), stations.reduce((s, st) => s + cpuSeconds(st.child.pid), 0)];
  let cdp = null;
  if (a.trace) {
    cdp = await context.newCDPSession(cpage);
    await cdp.send('Tracing.start', {
      transferMode: 'ReturnAsStream',
      traceConfig: { includedCategories: ['devtools.timeline', 'disabled-by-default-devtools.timeline',
                                          'toplevel', 'gpu', 'viz', 'cc', 'blink', 'v8', 'disabled-by-default-devtools.timeline.frame'] },
    });
  }
  const c = await measurePage(cpage, 'microdexConsole');
  if (cdp) {
    const done = new Promise((resolve) => cdp.once('Tracing.tracingComplete', resolve));
    await cdp.send('Tracing.end');
    const { stream } = await done;
    const parts = [];
    for (;;) {
      const r = await cdp.send('IO.read', { handle: stream, size: 1 << 20 });
      parts.push(r.base64Encoded ? Buffer.from(r.data, 'base64').toString('utf8') : r.data);
      if (r.eof) break;
    }
    await cdp.send('IO.close', { handle: stream });
    writeFileSync(a.trace, parts.join(''));
    progress(`console: trace written to ${a.trace}`);
  }
  const cpu1 = [cpuSeconds(instructor.child.pid), stations.reduce((s, st) => s + cpuSeconds(st.child.pid), 0)];
  const window_s = seconds + 2;
  report.console = { stations: n, width: W, height: H, fps: c.fps, latency: summary(c.latency),
                    received: summary(c.received), encoded: summary(c.encoded),
                    waited_at_instructor: summary(c.waited), tile_draws_per_s: c.tileDrawsPerSecond,
                    budget: c.budget, load_during: loadavg(),
                    instructor_cpu_share: (cpu1[0] - cpu0[0]) / window_s,
                    stations_cpu_share: (cpu1[1] - cpu0[1]) / window_s };
  progress(`console: ${c.fps.toFixed(1)} fps, ${c.tileDrawsPerSecond?.toFixed(1)} tile drawings/s; ` +
           `CPU: instructor ${(100 * report.console.instructor_cpu_share).toFixed(0)} %, ` +
           `8 stations ${(100 * report.console.stations_cpu_share).toFixed(0)} % of a core`);
  await cpage.screenshot({ path: join(a.out, 'console_8_stations.png') });
  await cpage.close();
  if (a.replay === '0') {
    for (const st of stations) await stopProcess(st.child);
    await stopProcess(instructor.child);
  } else {
  progress('console: recording 15 s of it for the replay');
  // A recording of the same console, replayed without the stations: the page's own cost.
  const recFile = join(a.out, 'console_recording.json');
  rmSync(recFile, { force: true });
  const recorder = spawnSync(process.execPath, ['--experimental-websocket', join(here, 'replay_console.mjs'), 'record',
                               '--url', `http://127.0.0.1:${instructor.match[1]}/`, '--seconds', '15',
                               '--out', recFile], { encoding: 'utf8', timeout: 90000 });
  if (recorder.status !== 0) throw new Error(`recording the console failed: ${recorder.stderr}`);
  for (const st of stations) await stopProcess(st.child);
  await stopProcess(instructor.child);
  const rec = JSON.parse(readFileSync(recFile, 'utf8'));
  const replay = await startReplay(rec, a.web);
  const rpage = await context.newPage();
  await rpage.goto(`http://127.0.0.1:${replay.port}/${a.console_query ? `?${a.console_query}` : ''}`);
  await waitFor(() => rpage.evaluate((k) => window.microdexConsole?.tilesDrawn === k, n),
                `${n} replayed tiles drawn`, 60000);
  const r = await measurePage(rpage, 'microdexConsole');
  report.console_replayed = { stations: n, width: W, height: H, fps: r.fps, latency: summary(r.latency),
                              received: summary(r.received), recorded_frames: rec.frames.length };
  await rpage.screenshot({ path: join(a.out, 'console_8_stations_replayed.png') });
  replay.close();
  }
  }
} finally {
  await close();
}
clearTimeout(limit);
writeReport();
progress('done');
const f = (v) => (Number.isFinite(v) ? v.toFixed(1) : '–');
console.log(`| view | fps (goal) | state → drawn p50 / p99 ms (goal 25 / 60) | state → received by the page p50 / p99 ms |`);
for (const [name, r, goal] of [[`station, ${a.scene}, ${W}x${H}`, report.station, 30],
                               [`console, ${report.console?.stations} live stations, ${W}x${H}`, report.console, 15],
                               [`console, ${report.console_replayed?.stations} stations replayed, ${W}x${H}`, report.console_replayed, 15]]) {
  if (!r) continue;
  console.log(`| ${name} | ${f(r.fps)} (${goal}) | ${f(r.latency.p50_ms)} / ${f(r.latency.p99_ms)} | ${f(r.received.p50_ms)} / ${f(r.received.p99_ms)} |`);
}
if (report.station) {
  console.log(`station: tick stamp → frame encoded by the publisher thread p50 / p99 ${f(report.station.encoded.p50_ms)} / ${f(report.station.encoded.p99_ms)} ms`);
}
if (report.console) {
  console.log(`console: tick stamp → frame encoded by the instructor p50 / p99 ${f(report.console.encoded.p50_ms)} / ${f(report.console.encoded.p99_ms)} ms, ` +
              `of which the state waited there ${f(report.console.waited_at_instructor.p50_ms)} / ${f(report.console.waited_at_instructor.p99_ms)} ms`);
}
console.log(`load average before ${report.machine_load.map((x) => x.toFixed(1)).join(' ')}, after ${report.machine_load_after.map((x) => x.toFixed(1)).join(' ')}`);
