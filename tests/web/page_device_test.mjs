// The view page's keyboard and mouse as the station's device (--device page): holding a key
// moves the station's tool along the view's axes (the tool pose comes back in the station's
// mirrored state), a mouse drag moves it in the image plane, and malformed device messages are
// refused with a reason while the station keeps running.
// node page_device_test.mjs --bin BUILD/bin --out DIR
import { join } from 'node:path';
import { launchBrowser, sourceDir } from './browser.mjs';
import { args, check, startProcess, stopProcess, waitFor } from './harness.mjs';

const a = args({ bin: join(sourceDir, 'build/bin'), out: join(sourceDir, 'build/web-artifacts') });
const station = await startProcess(join(a.bin, 'microdex-station'), [
  '--scene', join(sourceDir, 'assets/scenes/tremor_hold.yaml'), '--device', 'page',
  '--view', '0', '--no-realtime', '--duration', '120', '--partition', `web-device-${process.pid}`,
], /view: http:\/\/127\.0\.0\.1:(\d+)\//);
const url = `http://127.0.0.1:${station.match[1]}/`;
const { context, close } = await launchBrowser({ width: 1280, height: 720 });
const dot = (u, v) => u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
const sub = (u, v) => [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
try {
  const page = await context.newPage();
  await page.goto(url);
  await waitFor(() => page.evaluate(() => (window.microdexView?.framesDrawn ?? 0) >= 5),
                'frames drawn', 30000);
  const axes = await page.evaluate(() => window.microdexView.screenAxes());
  // The tool as the station last published it (the frame's p_WT), and that frame's step.
  const tool = () => page.evaluate(() => {
    const s = window.microdexView.lastFrame.scalars;
    return { p: [s[3], s[4], s[5]], step: s[1] };
  });
  // Still: the tool does not move by itself.
  const t0 = await tool();
  await page.waitForTimeout(700);
  const t1 = await tool();
  check(t1.step > t0.step && Math.hypot(...sub(t1.p, t0.p)) === 0,
        `without input the tool stays put (steps ${t0.step} → ${t1.step})`);

  await page.mouse.click(640, 400); // focus
  await page.keyboard.down('ArrowRight');
  await page.waitForTimeout(1500);
  await page.keyboard.up('ArrowRight');
  await page.waitForTimeout(500);
  const t2 = await tool();
  const d = sub(t2.p, t1.p);
  const right = dot(d, axes.right);
  check(right > 1e-3, `ArrowRight for 1.5 s moved the tool ${(right * 1e3).toFixed(2)} mm to the right`);
  check(Math.abs(dot(d, axes.up)) < 0.1 * right && Math.abs(dot(d, axes.forward)) < 0.1 * right,
        'and not up or in depth');

  await page.keyboard.down('r');
  await page.waitForTimeout(1000);
  await page.keyboard.up('r');
  await page.waitForTimeout(500);
  const t3 = await tool();
  const towards = -dot(sub(t3.p, t2.p), axes.forward);
  check(towards > 0.5e-3, `R moved the tool ${(towards * 1e3).toFixed(2)} mm towards the objective`);

  await page.mouse.move(640, 400);
  await page.mouse.down();
  for (let i = 1; i <= 10; ++i) await page.mouse.move(640, 400 - 10 * i);
  await page.mouse.up();
  await page.waitForTimeout(600);
  const t4 = await tool();
  const up = dot(sub(t4.p, t3.p), axes.up);
  check(up > 0.5e-3, `dragging the mouse 100 px up moved the tool ${(up * 1e3).toFixed(2)} mm up`);
  await page.screenshot({ path: join(a.out, 'page_device.png') });

  const errors = await page.evaluate(() => new Promise((resolve) => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    const got = [];
    ws.onmessage = (e) => { if (typeof e.data === 'string') got.push(JSON.parse(e.data).error); };
    ws.onopen = () => {
      for (const m of ['move 1', 'move nan 0 0', 'move 0.5 0 0', 'turn 0 0 3', 'grip 2',
                       'buttons 1.5', 'fly 0 0 0', 'move 0 0 0 extra']) ws.send(m);
      setTimeout(() => resolve(got), 1500);
    };
  }));
  check(errors.length === 8, `eight malformed device messages refused:\n    ${errors.join('\n    ')}`);
  const t5 = await tool();
  await page.waitForTimeout(500);
  const t6 = await tool();
  check(Math.hypot(...sub(t5.p, t4.p)) === 0 && t6.step > t5.step,
        'the refused messages did not move the tool; the station runs on');
} finally {
  await close();
  const code = await stopProcess(station.child);
  check(code === 0, `the station exits cleanly on SIGTERM (status ${code})`);
}
