// The station's view page in headless Chromium: a station with --view draws its scene; the
// needle's colour appears where the needle's projection lies; the frames decode; stereo modes
// draw; malformed WebSocket messages get an error and the station keeps running.
// node station_view_test.mjs --bin BUILD/bin --out DIR --source SRC
import { readFileSync, rmSync, writeFileSync } from 'node:fs';
import { spawnSync } from 'node:child_process';
import { join } from 'node:path';
import { launchBrowser, sourceDir } from './browser.mjs';
import { args, check, decodePng, hsv, startProcess, stopProcess, waitFor } from './harness.mjs';

const a = args({ bin: join(sourceDir, 'build/bin'), out: join(sourceDir, 'build/web-artifacts') });
const station = await startProcess(join(a.bin, 'microdex-station'), [
  '--scene', join(sourceDir, 'assets/scenes/needle_tube.yaml'), '--view', '0', '--no-realtime',
  '--duration', '120', '--station-id', `web-view-${process.pid}`,
], /view: http:\/\/127\.0\.0\.1:(\d+)\//);
const url = `http://127.0.0.1:${station.match[1]}/`;
const { context, close } = await launchBrowser({ width: 1280, height: 720 });
try {
  const page = await context.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.goto(url);
  await waitFor(() => page.evaluate(() => (window.microdexView?.framesDrawn ?? 0) >= 10),
                'ten frames drawn', 30000);
  const probe = () => page.evaluate(() => {
    const v = window.microdexView;
    return { received: v.framesReceived, drawn: v.framesDrawn, bad: v.badFrames,
             step: v.lastFrame.scalars[1], needle: v.needleScreen() };
  });
  const p0 = await probe();
  await page.waitForTimeout(1000);
  const p1 = await probe();
  check(p0.bad === 0 && p1.bad === 0, 'every frame from the station decodes');
  check(p1.step > p0.step, `the mirrored step advances (${p0.step} → ${p1.step})`);

  // Freeze the drawn state, then compare the screenshot with the needle's projection.
  await page.evaluate(() => { window.microdexView.freeze = true; });
  await page.waitForTimeout(500);
  const needle = (await probe()).needle;
  const png = await page.screenshot({ path: join(a.out, 'station_view.png') });
  const img = decodePng(png);
  check(img.width === 1280 && img.height === 720, 'the screenshot is 1280 x 720');
  const colours = new Set();
  const isNeedle = (i) => {
    const c = hsv(img.rgba[i], img.rgba[i + 1], img.rgba[i + 2]);
    return c.h >= 170 && c.h <= 205 && c.s >= 0.35 && c.v >= 0.3;
  };
  let near = 0, total = 0, sx = 0, sy = 0;
  for (let y = 0; y < img.height; ++y) {
    for (let x = 0; x < img.width; ++x) {
      const i = (y * img.width + x) * 4;
      colours.add((img.rgba[i] << 16) | (img.rgba[i + 1] << 8) | img.rgba[i + 2]);
      if (!isNeedle(i)) continue;
      ++total; sx += x; sy += y;
      if (Math.hypot(x - needle[0], y - needle[1]) <= 8) ++near;
    }
  }
  check(colours.size > 200, `the canvas is not blank (${colours.size} colours)`);
  check(needle[0] > 0 && needle[0] < 1280 && needle[1] > 0 && needle[1] < 720,
        `the needle projects into the view (${needle.map((v) => v.toFixed(0))})`);
  check(near >= 10, `needle-coloured pixels within 8 px of its projected midpoint: ${near}`);
  const cx = sx / total, cy = sy / total;
  check(Math.hypot(cx - needle[0], cy - needle[1]) < 60,
        `the needle colour's centroid (${cx.toFixed(0)}, ${cy.toFixed(0)}) lies by its projection`);

  // Stereo: anaglyph and side by side (screenshots kept). Anaglyph: the red vessel of the
  // mono view turns into the eyes' colour channels; side by side: the needle appears once in
  // each half, half a screen apart.
  const stats = (shot) => {
    let red = 0;
    const needleX = [[], []];
    for (let y = 0; y < shot.height; ++y) {
      for (let x = 0; x < shot.width; ++x) {
        const i = (y * shot.width + x) * 4;
        const c = hsv(shot.rgba[i], shot.rgba[i + 1], shot.rgba[i + 2]);
        if (c.s > 0.3 && c.v > 0.25 && (c.h < 15 || c.h > 340)) ++red;
        if (c.h >= 170 && c.h <= 205 && c.s >= 0.35 && c.v >= 0.3) {
          needleX[x < shot.width / 2 ? 0 : 1].push(x);
        }
      }
    }
    const mean = (v) => v.reduce((p, q) => p + q, 0) / Math.max(v.length, 1);
    return { red, left: needleX[0].length, right: needleX[1].length,
             leftX: mean(needleX[0]), rightX: mean(needleX[1]) };
  };
  const mono = stats(img);
  await page.evaluate(() => { window.microdexView.freeze = false; });
  for (const mode of ['anaglyph', 'side-by-side']) {
    await page.goto(`${url}?stereo=${mode}`);
    await waitFor(() => page.evaluate(() => (window.microdexView?.framesDrawn ?? 0) >= 5),
                  `${mode}: frames drawn`, 30000);
    await page.evaluate(() => { window.microdexView.freeze = true; });
    await page.waitForTimeout(300);
    const st = stats(decodePng(await page.screenshot({ path: join(a.out, `station_view_${mode}.png`) })));
    if (mode === 'anaglyph') {
      check(mono.red > 5000 && st.red < mono.red / 5,
            `anaglyph: the red vessel (${mono.red} px in mono) split into eye channels (${st.red} px)`);
    } else {
      check(st.left > 20 && st.right > 20 && Math.abs(st.rightX - st.leftX - 640) < 40,
            `side by side: the needle in both halves, ${(st.rightX - st.leftX).toFixed(0)} px apart`);
    }
  }

  // Bad input on the page's WebSocket: an error reply, the connection kept; an oversized
  // message: that connection dropped; the station keeps serving frames.
  const replies = await page.evaluate(() => new Promise((resolve) => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    const got = [];
    ws.onmessage = (e) => { if (typeof e.data === 'string') got.push(JSON.parse(e.data)); };
    ws.onopen = () => {
      ws.send('move 1 2');
      ws.send('move 1e9 0 0');
      ws.send('\u0000\u0001garbage');
      ws.send(new Uint8Array([1, 2, 3]));
      setTimeout(() => {
        const big = new WebSocket(`ws://${location.host}/ws`);
        big.onopen = () => big.send('x'.repeat(100000));
        big.onclose = (e) => resolve({ got, bigClosed: true, code: e.code });
        setTimeout(() => resolve({ got, bigClosed: false }), 5000);
      }, 1000);
    };
  }));
  check(replies.got.filter((m) => m.type === 'error').length === 4,
        `four malformed messages, four error replies: ${replies.got.map((m) => m.error).join(' | ')}`);
  check(replies.bigClosed, `an oversized message closes that connection (code ${replies.code})`);
  await page.evaluate(() => { window.microdexView.freeze = false; });
  const before = (await probe()).received;
  await page.waitForTimeout(1000);
  check((await probe()).received > before, 'the station still streams frames');
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);
  writeFileSync(join(a.out, 'station_view.json'), JSON.stringify({ url, p0, p1, needle }, null, 1));
} finally {
  await close();
  const code = await stopProcess(station.child);
  check(code === 0, `the station exits cleanly on SIGTERM (status ${code})`);
}

// --screenshot: the same page rendered headless by the station itself, then it stops.
{
  const out = join(a.out, 'station_screenshot.png');
  rmSync(out, { force: true });
  const r = spawnSync(join(a.bin, 'microdex-station'), [
    '--scene', join(sourceDir, 'assets/scenes/needle_tube.yaml'), '--screenshot', out,
    '--no-realtime', '--partition', `web-shot-${process.pid}`], { timeout: 120000 });
  check(r.status === 0, `--screenshot exits 0 (${r.status}; ${String(r.stderr).split('\n').slice(-2).join(' ')})`);
  const shot = decodePng(readFileSync(out));
  let needle = 0;
  for (let i = 0; i < shot.rgba.length; i += 4) {
    const c = hsv(shot.rgba[i], shot.rgba[i + 1], shot.rgba[i + 2]);
    if (c.h >= 170 && c.h <= 205 && c.s >= 0.35 && c.v >= 0.3) ++needle;
  }
  check(shot.width === 1280 && shot.height === 720 && needle > 100,
        `--screenshot wrote a 1280 x 720 view with the needle in it (${needle} px)`);
}
