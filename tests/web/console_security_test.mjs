// The console with --security (instructor/README.md "Security") in headless Chromium: a course
// made by deploy/security/make-course, a secure instructor and a secure station. An
// unauthenticated visitor gets the login form and nothing else: no page script, no scene, no
// WebSocket. An observer who logs in sees the station but may not send cues; an instructor
// sees it and sends a cue that the station acknowledges. The session cookie is HttpOnly,
// Secure and SameSite=Strict; a WebSocket from another origin is refused even with the
// cookie; plain HTTP gets nothing; logging out closes the open page's WebSocket. The
// station's own page listens on loopback only.
// node console_security_test.mjs --bin BUILD/bin --out DIR
import { spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { request as httpsRequest } from 'node:https';
import { connect } from 'node:net';
import { networkInterfaces, tmpdir } from 'node:os';
import { join } from 'node:path';
import { launchBrowser, sourceDir } from './browser.mjs';
import { args, check, startProcess, stopProcess, waitFor } from './harness.mjs';

const a = args({ bin: join(sourceDir, 'build/bin'), out: join(sourceDir, 'build/web-artifacts') });
const course = mkdtempSync(join(tmpdir(), 'microdex-course-'));
const made = spawnSync(join(sourceDir, 'deploy/security/make-course'),
                       [join(course, 'c'), '--course', `web${process.pid}`, '--station', 's1',
                        '--instructor', 'i1'], { encoding: 'utf8' });
if (made.status !== 0) throw new Error(`make-course failed:\n${made.stdout}${made.stderr}`);
const instructorDir = join(course, 'c/instructor-i1');
const users = { ada: ['instructor', 'ada correct horse'], obs: ['observer', 'obs battery staple'] };
for (const [name, [role, password]] of Object.entries(users)) {
  const r = spawnSync(join(a.bin, 'microdex-instructor'),
                      ['--security', instructorDir, '--add-user', name, '--role', role],
                      { input: `${password}\n`, encoding: 'utf8' });
  check(r.status === 0, `--add-user ${name} (${role}): ${r.stdout.trim()}${r.stderr.trim()}`);
}

const domain = ['--domain', '86'];
const instructor = await startProcess(join(a.bin, 'microdex-instructor'),
                                      ['--security', instructorDir, '--http', '0',
                                       '--duration', '120', ...domain],
                                      /console: https:\/\/127\.0\.0\.1:(\d+)\//);
const station = await startProcess(join(a.bin, 'microdex-station'), [
  '--scene', join(sourceDir, 'assets/scenes/needle_tube.yaml'), '--station-id', 's1',
  '--security', join(course, 'c/station-s1'), '--no-realtime', '--duration', '100',
  '--view', '0', ...domain,
], /view: http:\/\/127\.0\.0\.1:(\d+)\//);
const port = instructor.match[1];
const origin = `https://127.0.0.1:${port}`;

// A WebSocket upgrade by hand: the status the server answers.
function upgradeStatus(headers) {
  return new Promise((resolve) => {
    const req = httpsRequest({
      host: '127.0.0.1', port, path: '/ws', rejectUnauthorized: false,
      headers: { Connection: 'Upgrade', Upgrade: 'websocket', 'Sec-WebSocket-Version': '13',
                 'Sec-WebSocket-Key': 'dGhlIHNhbXBsZSBub25jZQ==', ...headers },
    });
    req.on('upgrade', (res, socket) => { socket.destroy(); resolve(res.statusCode); });
    req.on('response', (res) => { res.resume(); resolve(res.statusCode); });
    req.on('error', (e) => resolve(`error ${e.code}`));
    req.end();
  });
}

const { context, close } = await launchBrowser({ width: 1280, height: 800, ignoreHTTPSErrors: true });
try {
  // Plain HTTP on the console's port: no answer.
  const plain = await fetch(`http://127.0.0.1:${port}/`).then((r) => r.status, (e) => e.cause?.code ?? 'error');
  check(typeof plain !== 'number', `plain HTTP gets no page (${plain})`);

  // --- an unauthenticated visitor
  const visitor = await context.newPage();
  const sockets = [];
  visitor.on('websocket', (ws) => sockets.push(ws.url()));
  await visitor.goto(`${origin}/`);
  check(visitor.url() === `${origin}/login`, `/ leads to the login form (${visitor.url()})`);
  check(await visitor.evaluate(() => window.microdexConsole === undefined),
        'the visitor runs no console script');
  for (const path of ['/console.js', '/console.html', '/frame_worker.js', '/scene/s1.json']) {
    const r = await context.request.get(`${origin}${path}`, { maxRedirects: 0 });
    check(r.status() === 401 || (r.status() === 303 && r.headers().location === '/login'),
          `${path} without a session: ${r.status()}, no data`);
  }
  const wsAttempt = await visitor.evaluate((url) => new Promise((resolve) => {
    const ws = new WebSocket(url);
    ws.onopen = () => resolve('open');
    ws.onmessage = () => resolve('message');
    ws.onerror = () => resolve('refused');
    setTimeout(() => resolve('timeout'), 5000);
  }), `wss://127.0.0.1:${port}/ws`);
  check(wsAttempt === 'refused', `the visitor's WebSocket is refused (${wsAttempt})`);
  check(await upgradeStatus({ Origin: origin }) === 401, 'an upgrade without a session: 401');
  await visitor.fill('#user', 'ada');
  await visitor.fill('#password', 'not the password');
  await visitor.click('#login');
  await visitor.waitForSelector('#error');
  check(visitor.url() === `${origin}/login` &&
        (await context.cookies()).every((c) => c.name !== 'microdex_session'),
        'a wrong password: the form again, no session cookie');
  await visitor.close();
  await new Promise((r) => setTimeout(r, 1100));  // the failed-login delay

  // Logs in as `name` in a fresh page; resolves when the console lists s1 with frames.
  async function logIn(name) {
    await context.clearCookies();
    const page = await context.newPage();
    const errors = [];
    page.on('pageerror', (e) => errors.push(e.message));
    await page.goto(`${origin}/login`);
    await page.fill('#user', name);
    await page.fill('#password', users[name][1]);
    await Promise.all([page.waitForURL(`${origin}/`), page.click('#login')]);
    await waitFor(() => page.evaluate(() => {
      const c = window.microdexConsole;
      return c && c.stations.length === 1 && c.stations[0].id === 's1' &&
          (c.framesBySlot[0] ?? 0) >= 10;
    }), `${name}: the console lists s1 with frames`, 40000);
    return { page, errors };
  }

  // --- an observer: page data and WebSocket, but no cues
  const observer = await logIn('obs');
  check(true, 'the observer gets the page, the station list and frames over the WebSocket');
  const cookie = (await context.cookies()).find((c) => c.name === 'microdex_session');
  check(cookie && cookie.httpOnly && cookie.secure && cookie.sameSite === 'Strict',
        `the session cookie is HttpOnly, Secure, SameSite=Strict (${JSON.stringify(cookie && { httpOnly: cookie.httpOnly, secure: cookie.secure, sameSite: cookie.sameSite })})`);
  check(await upgradeStatus({ Origin: 'https://evil.example', Cookie: `microdex_session=${cookie.value}` }) === 403,
        'a WebSocket from another origin with the cookie: 403');
  check(await upgradeStatus({ Origin: origin, Cookie: `microdex_session=${cookie.value}` }) === 101,
        'the same with the console\'s origin: 101');
  const tile = observer.page.locator('.tile[data-station="s1"]');
  await tile.locator('input[data-cue="convergent"]').check();
  const refused = await waitFor(() => observer.page.evaluate(
      () => window.microdexConsole.errors.find((e) => e.includes('only an instructor'))),
      'the observer\'s cue refused', 10000);
  check(true, `the observer's cue is refused: "${refused}"`);
  // Recording and replay are the instructor's too (refused before anything else is looked at).
  const sessionRefused = await observer.page.evaluate(() => new Promise((resolve) => {
    const ws = new WebSocket(`wss://${location.host}/ws`);
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') return;
      const m = JSON.parse(e.data);
      if (m.type === 'error') resolve(m.error);
    };
    ws.onopen = () => ws.send('record start lesson');
    setTimeout(() => resolve(null), 5000);
  }));
  check(sessionRefused && sessionRefused.includes('only an instructor records and replays'),
        `the observer's recording is refused: "${sessionRefused}"`);
  await observer.page.close();

  // --- an instructor: page data, WebSocket and cues
  const ada = await logIn('ada');
  check(sockets.length === 1,
        `the login page opened no WebSocket but the one the test tried (${sockets.length})`);
  const adaTile = ada.page.locator('.tile[data-station="s1"]');
  await adaTile.locator('input[data-cue="convergent"]').check();
  const ack = await waitFor(async () => {
    const t = await adaTile.locator('.ack').first().textContent().catch(() => null);
    return t && /applied at step \d+/.test(t) ? t : null;
  }, 'the acknowledgement of the instructor\'s cue', 20000);
  check(true, `the instructor's cue is applied by the secure station: "${ack}"`);
  await ada.page.screenshot({ path: join(a.out, 'console_secure.png') });
  check(ada.errors.length === 0, `no page errors (${ada.errors.join('; ')})`);

  // Logging out ends the session: the page data is refused again, and the open page's
  // WebSocket is closed (no more frames).
  await ada.page.evaluate(() => fetch('/logout', { method: 'POST' }));
  const after = await context.request.get(`${origin}/console.js`, { maxRedirects: 0 });
  check(after.status() === 401, `after logging out, /console.js: ${after.status()}`);
  const frames = () => ada.page.evaluate(() => window.microdexConsole.framesBySlot[0] ?? 0);
  await new Promise((r) => setTimeout(r, 1000));
  const f0 = await frames();
  await new Promise((r) => setTimeout(r, 2000));
  const f1 = await frames();
  check(f1 === f0, `after logging out the open page gets no more frames (${f0} → ${f1})`);

  // The station's page: loopback only.
  const viewPort = Number(station.match[1]);
  const external = Object.values(networkInterfaces()).flat()
      .find((i) => i && i.family === 'IPv4' && !i.internal);
  if (!external) {
    console.log('skip: the station page on a non-loopback address (this host has none)');
  } else {
    const outcome = await new Promise((resolve) => {
      const s = connect({ host: external.address, port: viewPort });
      s.on('connect', () => { s.destroy(); resolve('connected'); });
      s.on('error', (e) => resolve(e.code));
      setTimeout(() => { s.destroy(); resolve('timeout'); }, 3000);
    });
    check(outcome === 'ECONNREFUSED',
          `the station page is not reachable on ${external.address}:${viewPort} (${outcome})`);
  }
  writeFileSync(join(a.out, 'console_security.json'), JSON.stringify({ origin, ack }, null, 1));
} finally {
  await close();
  await stopProcess(station.child);
  await stopProcess(instructor.child);
  rmSync(course, { recursive: true, force: true });
}
