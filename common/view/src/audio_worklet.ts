// The page's audio output (AudioWorklet, on the browser's audio thread): takes the station's
// audio blocks (audio_block.ts) from the frame worker (a MessagePort handed over by the page)
// or from the page itself, plays them through the jitter buffer (audio_jitter.ts), and reports
// to the page where each block's first sample went out (the context's frame) and the buffer's
// counters. The sound is the station's: nothing is synthesised here.

import { AudioBlockError, decodeAudioBlock } from './audio_block';
import { JitterBuffer, PlayedBlock } from './audio_jitter';

declare const sampleRate: number;
declare const currentFrame: number;
declare class AudioWorkletProcessor {
  readonly port: MessagePort;
  constructor(options?: any);
}
declare function registerProcessor(name: string, ctor: any): void;

class StationAudioProcessor extends AudioWorkletProcessor {
  private jitter: JitterBuffer;
  private played: PlayedBlock[] = [];
  private bad = 0;
  private sumSq = 0;
  private count = 0;
  private lastReport = 0;

  constructor(options: any) {
    super(options);
    const o = options?.processorOptions ?? {};
    this.jitter = new JitterBuffer({
      outRate: sampleRate, targetMs: o.targetMs ?? 30, maxMs: o.maxMs ?? 120, adaptive: o.adaptive ?? true,
    });
    const take = (m: any) => {
      if (m && m.type === 'block') this.take(m.buf, m.receivedMs);
      else if (m && m.type === 'port') (m.port as MessagePort).onmessage = (e) => take(e.data);
    };
    this.port.onmessage = (e: MessageEvent) => take(e.data);
  }

  private take(buf: ArrayBuffer, receivedMs: number): void {
    try {
      const b = decodeAudioBlock(buf, receivedMs);
      this.jitter.push(b.meta, b.pcm);
    } catch (e) {
      if (!(e instanceof AudioBlockError)) throw e;
      ++this.bad;
    }
  }

  process(_inputs: Float32Array[][], outputs: Float32Array[][]): boolean {
    const out = outputs[0];
    const ch0 = out[0];
    this.jitter.pull(ch0, currentFrame, this.played);
    for (let c = 1; c < out.length; ++c) out[c].set(ch0);
    for (let i = 0; i < ch0.length; ++i) this.sumSq += ch0[i] * ch0[i];
    this.count += ch0.length;
    for (const p of this.played) this.port.postMessage({ type: 'played', meta: p.meta, frame: p.frame });
    if (currentFrame - this.lastReport >= sampleRate / 4) {
      this.lastReport = currentFrame;
      this.port.postMessage({
        type: 'stats', frame: currentFrame, stats: { ...this.jitter.stats }, bad: this.bad,
        rms: this.count ? Math.sqrt(this.sumSq / this.count) : 0,
      });
      this.sumSq = 0;
      this.count = 0;
    }
    return true;
  }
}

registerProcessor('station-audio', StationAudioProcessor);
