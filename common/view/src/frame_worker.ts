// The frame worker (frame_link.ts): owns the page's WebSocket, writes each binary frame into
// its SharedArrayBuffer slot the moment it arrives, and returns the credit of the frames
// received whenever the page has drawn; text messages go to the page. Audio blocks
// (audio_block.ts) go straight to the page's AudioWorklet through the port the page handed
// over, stamped with their arrival, never through the page's busy main thread.
import { writeSlot } from './frame_link';
import { isAudioBlock } from './audio_block';

let ws: WebSocket | null = null;
let sab: SharedArrayBuffer | null = null;
let url = '';
let delayMs = 250;
let received = 0; // frames since the page last drew
let audioPort: MessagePort | null = null;
// Counters for diagnosis (a test can read them from the worker).
const stats = { frames: 0, credited: 0, drew: 0, texts: 0, refused: 0, audio: 0, error: '' };
(self as any).microdexWorker = stats;

function connect(): void {
  const socket = new WebSocket(url);
  socket.binaryType = 'arraybuffer';
  socket.onopen = () => { delayMs = 250; postMessage({ type: 'status', open: true }); };
  socket.onmessage = (e: MessageEvent) => {
    if (typeof e.data === 'string') {
      ++stats.texts;
      try {
        postMessage({ type: 'text', message: JSON.parse(e.data) });
      } catch {
        // not JSON: ignored
      }
      return;
    }
    const receivedMs = performance.timeOrigin + performance.now();
    if (isAudioBlock(e.data as ArrayBuffer)) {
      ++stats.audio;
      audioPort?.postMessage({ type: 'block', buf: e.data, receivedMs }, [e.data as ArrayBuffer]);
      return;
    }
    try {
      if (!writeSlot(sab!, e.data as ArrayBuffer, receivedMs)) {
        ++stats.refused;
      }
    } catch (err) {
      stats.error = String(err);
    }
    ++received;
    ++stats.frames;
  };
  socket.onclose = () => {
    postMessage({ type: 'status', open: false });
    setTimeout(connect, delayMs);
    delayMs = Math.min(delayMs * 2, 4000);
  };
  ws = socket;
}

self.onmessage = (e: MessageEvent) => {
  const m = e.data;
  if (m.type === 'open') {
    sab = m.sab;
    url = m.url;
    connect();
  } else if (m.type === 'audio-port') {
    audioPort = m.port;
  } else if (m.type === 'send' && ws && ws.readyState === WebSocket.OPEN) {
    ws.send(m.text);
  } else if (m.type === 'drew') {
    ++stats.drew;
  }
  if (m.type === 'drew' && ws && ws.readyState === WebSocket.OPEN && received > 0) {
    // The page has drawn: the frames taken since may be replaced (view_server.h credits), so
    // the app sends about as many frames as the page draws, each the newest.
    ws.send(`credit ${Math.min(received, 1024)}`);
    stats.credited += received;
    received = 0;
  }
};
