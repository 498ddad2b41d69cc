// A stand-in for microdex-instructor's console server that replays a recording of it (the
// station list, each station's scene JSON and state frames), so that the console page's own
// cost can be measured without eight live stations competing for the same cores.
//   record: node replay_console.mjs record --url http://127.0.0.1:PORT/ --seconds S --out FILE.json
//   serve:  startReplay(recording, webDir) → { port, close }
import { createServer } from 'node:http';
import { createHash } from 'node:crypto';
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';

// Records the console's messages for up to `seconds`, stopping early once every station has
// `perStation` frames (needs node --experimental-websocket).
export async function record(url, seconds, perStation = 60) {
  const ws = new WebSocket(url.replace(/^http/, 'ws') + 'ws');
  ws.binaryType = 'arraybuffer';
  const frames = [];
  let stations = null;
  const t0 = Date.now();
  ws.onmessage = (e) => {
    if (typeof e.data === 'string') {
      const m = JSON.parse(e.data);
      if (m.type === 'stations') stations = m;
      return;
    }
    frames.push({ t: Date.now() - t0, b64: Buffer.from(e.data).toString('base64') });
    ws.send('credit 1');
  };
  const end = Date.now() + seconds * 1000;
  while (Date.now() < end) {
    await new Promise((r) => setTimeout(r, 200));
    const n = stations?.stations.length ?? 0;
    const bySlot = new Array(n).fill(0);
    for (const f of frames) bySlot[Buffer.from(f.b64, 'base64').readUInt32LE(8)] += 1;
    if (n > 0 && bySlot.every((k) => k >= perStation)) break;
  }
  ws.close();
  const scenes = {};
  for (const s of stations?.stations ?? []) {
    scenes[s.id] = await (await fetch(`${url}scene/${encodeURIComponent(s.id)}.json`)).text();
  }
  return { stations, scenes, frames };
}

function wsAccept(key) {
  return createHash('sha1').update(key + '258EAFA5-E914-47DA-95CA-C5AB0DC85B11').digest('base64');
}
function wsFrame(payload, binary) {
  const n = payload.length;
  const head = n < 126 ? Buffer.from([binary ? 0x82 : 0x81, n])
    : n < 65536 ? Buffer.from([binary ? 0x82 : 0x81, 126, n >> 8, n & 255])
    : Buffer.concat([Buffer.from([binary ? 0x82 : 0x81, 127, 0, 0, 0, 0]),
                     Buffer.from([(n >>> 24) & 255, (n >>> 16) & 255, (n >>> 8) & 255, n & 255])]);
  return Buffer.concat([head, payload]);
}

// Serves the console page and replays the recording in a loop, each frame re-stamped with
// the current time (so that the page's latency figures stay meaningful).
export function startReplay(rec, webDir) {
  const files = { '/': 'console.html', '/console.html': 'console.html', '/console.js': 'console.js',
                  '/frame_worker.js': 'frame_worker.js' };
  const server = createServer((req, res) => {
    const headers = { 'Cross-Origin-Opener-Policy': 'same-origin',
                      'Cross-Origin-Embedder-Policy': 'require-corp', 'Cache-Control': 'no-store' };
    const path = req.url.split('?')[0];
    if (files[path]) {
      const type = path.endsWith('.js') ? 'text/javascript' : 'text/html';
      res.writeHead(200, { ...headers, 'Content-Type': type });
      res.end(readFileSync(join(webDir, files[path])));
    } else if (path.startsWith('/scene/')) {
      const id = decodeURIComponent(path.slice(7, -5));
      res.writeHead(200, { ...headers, 'Content-Type': 'application/json' });
      res.end(rec.scenes[id] ?? '{"error":"none"}');
    } else {
      res.writeHead(404, headers);
      res.end();
    }
  });
  const sockets = new Set();
  server.on('upgrade', (req, socket) => {
    socket.write('HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n' +
                 `Sec-WebSocket-Accept: ${wsAccept(req.headers['sec-websocket-key'])}\r\n\r\n`);
    socket.on('data', () => undefined); // credits and the like: not needed here
    socket.on('error', () => sockets.delete(socket));
    socket.on('close', () => sockets.delete(socket));
    socket.write(wsFrame(Buffer.from(JSON.stringify(rec.stations)), false));
    sockets.add(socket);
  });
  const frames = rec.frames.map((f) => ({ t: f.t, buf: Buffer.from(f.b64, 'base64') }));
  const span = frames.length ? frames[frames.length - 1].t + 33 : 1000;
  const start = Date.now();
  let next = 0;
  let loop = 0;
  const timer = setInterval(() => {
    const now = Date.now() - start;
    while (frames.length && loop * span + frames[next].t <= now) {
      const b = Buffer.from(frames[next].buf);
      b.writeDoubleLE(Date.now(), 16); // the tick stamp: now
      for (const s of sockets) s.write(wsFrame(b, true));
      if (++next === frames.length) { next = 0; ++loop; }
    }
  }, 2);
  const status = setInterval(() => {
    for (const s of sockets) s.write(wsFrame(Buffer.from(JSON.stringify(rec.stations)), false));
  }, 250);
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve({
    port: server.address().port,
    close: () => { clearInterval(timer); clearInterval(status); for (const s of sockets) s.destroy(); server.close(); },
  })));
}

if (process.argv[2] === 'record') {
  const o = {};
  for (let i = 3; i + 1 < process.argv.length; i += 2) o[process.argv[i].slice(2)] = process.argv[i + 1];
  writeFileSync(o.out, JSON.stringify(await record(o.url, Number(o.seconds ?? 5))));
}
