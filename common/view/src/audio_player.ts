// The station page's audio (main thread): an AudioContext with the station-audio worklet
// (audio_worklet.ts) fed by the frame link's audio blocks, an AnalyserNode on its output, and
// the latency from each audio cause at the station to its sound:
//   cause → sound = (page receive − tick stamp)  [publisher thread, block filling, WebSocket]
//                 + jitter-buffer wait           [receive → the sample rendered]
//                 + baseLatency + outputLatency  [rendered → at the output, as the browser says]
// The page's clock (performance.timeOrigin + now) and the station's CLOCK_REALTIME stamps are
// the same host's clock. Where the browser has getOutputTimestamp, the time a context frame
// reaches the output comes from it (which covers the last two terms); otherwise from the render
// clock plus baseLatency + outputLatency. Not included: whatever the OS and the device add
// beyond what the browser reports as outputLatency.

import { CAUSE_BEFORE, AudioBlockMeta } from './audio_block';
import { JitterStats } from './audio_jitter';
import { FrameLink } from './frame_link';

export interface AudioOptions {
  targetMs?: number; // jitter buffer target (initial, minimum)
  adaptive?: boolean;
  sampleRate?: number; // ask the context for this rate (default: the device's)
  keep?: number; // latency samples kept (default 20000)
}

interface ToneSpan { start: number; end: number; toneHz: number; clearanceM: number }

export interface AudioAnalysis {
  rms: number; // of the analyser's window
  peakHz: number; // dominant frequency in 100 Hz .. 5 kHz (parabolic interpolation)
  peakDb: number;
  windowFrames: number;
  blocks: number; // blocks played in the window
  toneMinHz: number; // the station's pitch over those blocks (0: none)
  toneMaxHz: number;
  toneMeanHz: number;
  clearanceMinM: number;
  clearanceMaxM: number;
  reportLagMs: number; // the render clock ahead of the newest block reported played
}

function quantile(v: number[], q: number): number {
  if (!v.length) return NaN;
  const s = [...v].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.floor(q * s.length))];
}

export class AudioPlayer {
  ctx: AudioContext | null = null;
  private node: AudioWorkletNode | null = null;
  private analyser: AnalyserNode | null = null;
  private spans: ToneSpan[] = [];
  // Counters and figures the page shows and the tests read (window.__audioStats).
  readonly stats = {
    on: false,
    contextRate: 0,
    blockRate: 0,
    played: 0,
    jitter: null as JitterStats | null,
    bad: 0,
    workletRms: 0,
    baseLatencyMs: 0,
    outputLatencyMs: 0,
    clock: '' as '' | 'getOutputTimestamp' | 'render clock + latency',
    causeMs: [] as number[], // cause → sound, blocks with their cause in them
    blockMs: [] as number[], // first sample's tick → its sound
    transportMs: [] as number[], // first sample's tick → page receive
    stationMs: [] as number[], // first sample's tick → sent by the station's view server
    waitMs: [] as number[], // receive → rendered (jitter buffer)
    lastMeta: null as AudioBlockMeta | null,
    p50: NaN,
    p99: NaN,
  };

  constructor(private readonly link: FrameLink, private readonly opts: AudioOptions = {}) {}

  async start(): Promise<void> {
    if (this.ctx) return;
    const ctx = new AudioContext({
      latencyHint: 'interactive', ...(this.opts.sampleRate ? { sampleRate: this.opts.sampleRate } : {}),
    });
    this.ctx = ctx;
    await ctx.audioWorklet.addModule('audio_worklet.js');
    const node = new AudioWorkletNode(ctx, 'station-audio', {
      numberOfInputs: 0, numberOfOutputs: 1, outputChannelCount: [1],
      processorOptions: { targetMs: this.opts.targetMs ?? 30, adaptive: this.opts.adaptive ?? true },
    });
    const analyser = new AnalyserNode(ctx, { fftSize: 8192, smoothingTimeConstant: 0 });
    node.connect(analyser).connect(ctx.destination);
    node.port.onmessage = (e: MessageEvent) => this.onWorklet(e.data);
    const channel = new MessageChannel();
    node.port.postMessage({ type: 'port', port: channel.port1 }, [channel.port1]);
    this.link.setAudioPort(channel.port2);
    this.node = node;
    this.analyser = analyser;
    this.stats.contextRate = ctx.sampleRate;
    await ctx.resume();
    this.stats.on = true;
    this.link.send('audio on');
  }

  async stop(): Promise<void> {
    this.link.send('audio off');
    this.stats.on = false;
    const ctx = this.ctx;
    this.ctx = null;
    this.node = null;
    this.analyser = null;
    await ctx?.close();
  }

  // After a reconnect: the station forgets the page's request with its connection.
  relink(): void {
    if (this.stats.on) this.link.send('audio on');
  }

  // Forget the figures so far (a test's warm-up).
  resetFigures(): void {
    const s = this.stats;
    s.causeMs.length = s.blockMs.length = s.transportMs.length = s.waitMs.length = 0;
    s.stationMs.length = 0;
  }

  // The epoch ms at which context frame `frame` reaches the output.
  private heardMs(frame: number): number {
    const ctx = this.ctx!;
    const rate = ctx.sampleRate;
    const ts = typeof ctx.getOutputTimestamp === 'function' ? ctx.getOutputTimestamp() : null;
    if (ts && ts.contextTime && ts.performanceTime && ts.contextTime > 0) {
      this.stats.clock = 'getOutputTimestamp';
      return performance.timeOrigin + ts.performanceTime + (frame / rate - ts.contextTime) * 1000;
    }
    this.stats.clock = 'render clock + latency';
    return performance.timeOrigin + performance.now() + (frame / rate - ctx.currentTime) * 1000 +
        this.stats.baseLatencyMs + this.stats.outputLatencyMs;
  }

  private onWorklet(m: any): void {
    const ctx = this.ctx;
    if (!ctx) return;
    const s = this.stats;
    if (m.type === 'stats') {
      s.jitter = m.stats;
      s.bad = m.bad;
      s.workletRms = m.rms;
      s.baseLatencyMs = (ctx.baseLatency ?? 0) * 1000;
      s.outputLatencyMs = ((ctx as any).outputLatency ?? 0) * 1000;
      return;
    }
    if (m.type !== 'played') return;
    const meta = m.meta as AudioBlockMeta;
    ++s.played;
    s.blockRate = meta.sampleRate;
    s.lastMeta = meta;
    const ratio = ctx.sampleRate / meta.sampleRate;
    this.spans.push({ start: m.frame, end: m.frame + meta.samples * ratio, toneHz: meta.toneHz,
                      clearanceM: meta.clearanceM });
    if (this.spans.length > 400) this.spans.splice(0, this.spans.length - 400);
    const keep = this.opts.keep ?? 20000;
    if (s.blockMs.length >= keep) return;
    const heard = this.heardMs(m.frame);
    const block = heard - meta.firstStampMs;
    const transport = meta.receivedMs - meta.firstStampMs;
    s.blockMs.push(block);
    s.transportMs.push(transport);
    s.stationMs.push(meta.sentMs - meta.firstStampMs);
    s.waitMs.push(block - transport - s.baseLatencyMs - s.outputLatencyMs);
    if (meta.causeOffset !== CAUSE_BEFORE) {
      s.causeMs.push(this.heardMs(m.frame + meta.causeOffset * ratio) - meta.causeStampMs);
    }
    if (s.played % 25 === 0) {
      s.p50 = quantile(s.causeMs, 0.5);
      s.p99 = quantile(s.causeMs, 0.99);
    }
  }

  figures(): Record<string, number> {
    const s = this.stats;
    const q = (v: number[], p: number) => quantile(v, p);
    return {
      causeP50: q(s.causeMs, 0.5), causeP99: q(s.causeMs, 0.99), causeN: s.causeMs.length,
      blockP50: q(s.blockMs, 0.5), blockP99: q(s.blockMs, 0.99),
      transportP50: q(s.transportMs, 0.5), transportP99: q(s.transportMs, 0.99),
      stationP50: q(s.stationMs, 0.5), stationP99: q(s.stationMs, 0.99),
      waitP50: q(s.waitMs, 0.5), waitP99: q(s.waitMs, 0.99),
      baseLatencyMs: s.baseLatencyMs, outputLatencyMs: s.outputLatencyMs,
    };
  }

  // The analyser's window now: loudness, dominant frequency, and the station's pitch over the
  // blocks played in that window.
  analyse(): AudioAnalysis | null {
    const ctx = this.ctx, an = this.analyser;
    if (!ctx || !an) return null;
    const end = ctx.currentTime * ctx.sampleRate;
    const wave = new Float32Array(an.fftSize);
    an.getFloatTimeDomainData(wave);
    const spec = new Float32Array(an.frequencyBinCount);
    an.getFloatFrequencyData(spec);
    let sum = 0;
    for (const x of wave) sum += x * x;
    const binHz = ctx.sampleRate / an.fftSize;
    let k = -1;
    for (let i = Math.ceil(100 / binHz); i < Math.min(spec.length - 1, 5000 / binHz); ++i) {
      if (k < 0 || spec[i] > spec[k]) k = i;
    }
    let peakHz = NaN;
    if (k > 0) {
      const a = spec[k - 1], b = spec[k], c = spec[k + 1];
      const d = a - 2 * b + c;
      peakHz = (k + (d !== 0 ? (0.5 * (a - c)) / d : 0)) * binHz;
    }
    const start = end - an.fftSize;
    const inWindow = this.spans.filter((p) => p.end > start && p.start < end);
    const tones = inWindow.map((p) => p.toneHz);
    const cl = inWindow.map((p) => p.clearanceM);
    return {
      rms: Math.sqrt(sum / wave.length), peakHz, peakDb: k >= 0 ? spec[k] : -Infinity,
      windowFrames: an.fftSize, blocks: inWindow.length,
      toneMinHz: tones.length ? Math.min(...tones) : 0, toneMaxHz: tones.length ? Math.max(...tones) : 0,
      toneMeanHz: tones.length ? tones.reduce((x, y) => x + y, 0) / tones.length : 0,
      clearanceMinM: cl.length ? Math.min(...cl) : NaN, clearanceMaxM: cl.length ? Math.max(...cl) : NaN,
      reportLagMs: this.spans.length ? ((end - this.spans[this.spans.length - 1].end) / ctx.sampleRate) * 1000 : NaN,
    };
  }
}
