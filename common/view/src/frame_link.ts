// How a page gets its frames. Where the page is cross-origin isolated (the apps send
// COOP/COEP headers; a loopback or https origin), a dedicated worker owns the WebSocket and
// writes each frame into a SharedArrayBuffer slot under a sequence lock, so frames are taken
// the moment they arrive even while the main thread is busy drawing (a software renderer
// blocks it for tens of ms), and the main thread reads the newest one when it draws.
// Elsewhere the main thread's own WebSocket does the same job, later.

import { AppSocket } from './socket';
import { isAudioBlock } from './audio_block';

export const MAX_SLOTS = 8;
// Header (seq i32, length i32, received-at f64) + the largest frame (view_frame.h kMaxFrameBytes).
export const SLOT_HEADER = 16;
export const SLOT_BYTES = SLOT_HEADER + 16 + 48 * 8 + 512 * 12 + 16384 * 4;

export interface LinkHandlers {
  onText?(message: any): void;
  onStatus?(open: boolean): void;
}

export interface TakenFrame { buffer: ArrayBuffer; receivedMs: number }

export class FrameLink {
  readonly shared: boolean;
  private worker: Worker | null = null;
  private socket: AppSocket | null = null;
  private sab: SharedArrayBuffer | null = null;
  private lastSeq = new Int32Array(MAX_SLOTS);
  private pending: (TakenFrame | null)[] = new Array(MAX_SLOTS).fill(null);
  private taken = 0;
  private audioPort: MessagePort | null = null;

  constructor(url: string, workerUrl: string, handlers: LinkHandlers) {
    this.shared = typeof SharedArrayBuffer !== 'undefined' && (self as any).crossOriginIsolated === true;
    if (this.shared) {
      this.sab = new SharedArrayBuffer(SLOT_BYTES * MAX_SLOTS);
      this.worker = new Worker(workerUrl);
      this.worker.onmessage = (e: MessageEvent) => {
        const m = e.data;
        if (m.type === 'text') handlers.onText?.(m.message);
        else if (m.type === 'status') handlers.onStatus?.(m.open);
      };
      this.worker.postMessage({ type: 'open', url, sab: this.sab });
    } else {
      this.socket = new AppSocket(url, {
        onFrame: (data) => {
          if (isAudioBlock(data)) {
            const receivedMs = performance.timeOrigin + performance.now();
            this.audioPort?.postMessage({ type: 'block', buf: data, receivedMs }, [data]);
            return;
          }
          ++this.taken;
          const slot = data.byteLength >= 12 ? new DataView(data).getUint32(8, true) : 0;
          if (slot < MAX_SLOTS) {
            this.pending[slot] = { buffer: data, receivedMs: performance.timeOrigin + performance.now() };
          }
        },
        onText: handlers.onText,
        onStatus: handlers.onStatus,
      });
    }
  }

  // Where the station's audio blocks go (the AudioWorklet's end of a MessageChannel); with the
  // worker, they go there straight from the worker.
  setAudioPort(port: MessagePort): void {
    if (this.worker) this.worker.postMessage({ type: 'audio-port', port }, [port]);
    else this.audioPort = port;
  }

  send(text: string): boolean {
    if (this.worker) {
      this.worker.postMessage({ type: 'send', text });
      return true;
    }
    return this.socket!.send(text);
  }

  // The newest frame of `slot` not taken before, or null.
  take(slot: number): TakenFrame | null {
    if (!this.sab) {
      const f = this.pending[slot];
      this.pending[slot] = null;
      return f;
    }
    return readSlot(this.sab, slot, this.lastSeq);
  }

  // After drawing: return the credit of the frames received since (view_server.h), so that
  // the app sends about as many frames as the page draws.
  drew(): void {
    if (this.worker) {
      this.worker.postMessage({ type: 'drew' });
      return;
    }
    if (this.taken > 0 && this.socket!.send(`credit ${Math.min(this.taken, 1024)}`)) this.taken = 0;
  }
}

// Sequence lock, reader side: copies the slot when its sequence is even and unchanged across
// the copy (bounded retries; a frame being written is taken on the next call).
export function readSlot(sab: SharedArrayBuffer, slot: number, lastSeq: Int32Array): TakenFrame | null {
  const base = slot * SLOT_BYTES;
  const head = new Int32Array(sab, base, 2);
  for (let attempt = 0; attempt < 4; ++attempt) {
    const seq = Atomics.load(head, 0);
    if (seq === lastSeq[slot]) return null;
    if (seq & 1) continue;
    const length = Atomics.load(head, 1);
    const receivedMs = new Float64Array(sab, base + 8, 1)[0];
    if (length <= 0 || length > SLOT_BYTES - SLOT_HEADER) return null;
    const copy = new Uint8Array(length);
    copy.set(new Uint8Array(sab, base + SLOT_HEADER, length));
    if (Atomics.load(head, 0) !== seq) continue;
    lastSeq[slot] = seq;
    return { buffer: copy.buffer, receivedMs };
  }
  return null;
}

// Sequence lock, writer side (the worker).
export function writeSlot(sab: SharedArrayBuffer, data: ArrayBuffer, receivedMs: number): boolean {
  if (data.byteLength < 12 || data.byteLength > SLOT_BYTES - SLOT_HEADER) return false;
  const slot = new DataView(data).getUint32(8, true);
  if (slot >= MAX_SLOTS) return false;
  const base = slot * SLOT_BYTES;
  const head = new Int32Array(sab, base, 2);
  Atomics.add(head, 0, 1); // odd: being written
  new Uint8Array(sab, base + SLOT_HEADER, data.byteLength).set(new Uint8Array(data));
  new Float64Array(sab, base + 8, 1)[0] = receivedMs;
  Atomics.store(head, 1, data.byteLength);
  Atomics.add(head, 0, 1); // even: complete
  return true;
}
