// The page's jitter buffer for the station's audio blocks (audio_block.ts), run inside the
// AudioWorklet (audio_worklet.ts) and testable on its own: blocks go into a ring of source
// samples; the output reads it at the context's rate (linear interpolation when the rates
// differ), starting once `targetMs` of sound is buffered. Running dry in the middle of a stream
// is an underrun: silence, counted, and buffering again (adaptive: the target grows by
// `stepMs` up to `maxMs` after an underrun and shrinks back by `stepMs` after `relaxS` without
// one). A buffer that has grown past `targetMs + slackMs` (a burst after a stall) skips ahead
// to the target at once; one whose lowest fill over `trimS` of playing stayed more than
// `trimMs` above the target (the latency left from an earlier, larger target, or the station's
// clock running ahead of the audio clock) drops that excess, so the delay comes back down. Gaps in the blocks' sequence
// numbers (blocks dropped by a slow page's link) are counted. Nothing allocates per sample.

import { AUDIO_END, AUDIO_START, AudioBlockMeta } from './audio_block';

export interface JitterOptions {
  outRate: number; // the AudioContext's sample rate
  targetMs?: number; // initial and minimum target (default 30)
  maxMs?: number; // adaptive target's ceiling (default 120)
  stepMs?: number; // adaptive step (default 10)
  relaxS?: number; // seconds without underrun before the target shrinks (default 10)
  adaptive?: boolean; // default true
  slackMs?: number; // over-full beyond target + slack: skip (default max(target, 40))
  capacityS?: number; // ring capacity in seconds of source audio (default 2)
  trimS?: number; // window of the lowest fill (default 1)
  trimMs?: number; // excess over the target that is dropped (default 10)
}

// A block whose first sample went out in a pull: its metadata and the output frame (context
// timeline, fractional) of its first sample.
export interface PlayedBlock { meta: AudioBlockMeta; frame: number }

export interface JitterStats {
  blocks: number; // pushed
  played: number; // whose first sample went out
  underruns: number;
  gaps: number; // blocks missing between sequence numbers
  skips: number; // over-full buffer skipped ahead
  skippedMs: number;
  trims: number; // excess dropped after a window with the fill above the target
  trimmedMs: number;
  overflows: number; // blocks refused by a full ring
  targetMs: number;
  fillMs: number;
  state: 'idle' | 'buffering' | 'playing';
}

interface Pending { meta: AudioBlockMeta; start: number }

export class JitterBuffer {
  readonly stats: JitterStats;
  private ring: Float32Array;
  private srcRate = 0;
  private written = 0; // source samples written (stream index)
  private read = 0; // fractional read position (stream index)
  private pending: Pending[] = []; // blocks not yet started, in stream order
  private ended = false; // the last block pushed carried AUDIO_END
  private lastSeq = -1;
  private sinceUnderrunS = 0;
  private readonly baseMs: number;
  private readonly maxMs: number;
  private readonly stepMs: number;
  private readonly relaxS: number;
  private readonly adaptive: boolean;
  private readonly slackMs: number | undefined;
  private readonly capacityS: number;
  private readonly trimS: number;
  private readonly trimMs: number;
  private windowS = 0; // playing time in the current trim window
  private minFill = Infinity; // lowest fill in it (source samples)

  constructor(private readonly opts: JitterOptions) {
    this.baseMs = opts.targetMs ?? 30;
    this.maxMs = Math.max(opts.maxMs ?? 120, this.baseMs);
    this.stepMs = opts.stepMs ?? 10;
    this.relaxS = opts.relaxS ?? 10;
    this.adaptive = opts.adaptive ?? true;
    this.slackMs = opts.slackMs;
    this.capacityS = opts.capacityS ?? 2;
    this.trimS = opts.trimS ?? 1;
    this.trimMs = opts.trimMs ?? 10;
    this.ring = new Float32Array(0);
    this.stats = { blocks: 0, played: 0, underruns: 0, gaps: 0, skips: 0, skippedMs: 0,
                   overflows: 0, trims: 0, trimmedMs: 0, targetMs: this.baseMs, fillMs: 0, state: 'idle' };
  }

  get fill(): number { return this.written - this.read; }

  push(meta: AudioBlockMeta, pcm: Float32Array): void {
    if (meta.sampleRate !== this.srcRate) {
      // A new source rate (the first block): a fresh ring.
      this.srcRate = meta.sampleRate;
      this.ring = new Float32Array(Math.ceil(this.capacityS * this.srcRate));
      this.written = 0;
      this.read = 0;
      this.pending.length = 0;
      this.stats.state = 'buffering';
    }
    if (this.lastSeq >= 0 && meta.seq > this.lastSeq + 1 && !(meta.flags & AUDIO_START)) {
      this.stats.gaps += meta.seq - this.lastSeq - 1;
    }
    this.lastSeq = meta.seq;
    ++this.stats.blocks;
    if (this.written + pcm.length - this.read > this.ring.length) {
      ++this.stats.overflows;
      return;
    }
    if (this.stats.state === 'idle') this.stats.state = 'buffering';
    this.pending.push({ meta, start: this.written });
    const cap = this.ring.length;
    for (let i = 0; i < pcm.length; ++i) this.ring[(this.written + i) % cap] = pcm[i];
    this.written += pcm.length;
    this.ended = (meta.flags & AUDIO_END) !== 0;
    this.stats.fillMs = (this.fill / this.srcRate) * 1000;
  }

  // Fills `out` (one render quantum) whose first sample is output frame `frame`; the blocks
  // whose first sample went out are appended to `played` (cleared first).
  pull(out: Float32Array, frame: number, played: PlayedBlock[]): void {
    played.length = 0;
    out.fill(0);
    const st = this.stats;
    const quantumS = out.length / this.opts.outRate;
    this.sinceUnderrunS += quantumS;
    if (this.adaptive && this.sinceUnderrunS > this.relaxS && st.targetMs > this.baseMs) {
      st.targetMs = Math.max(this.baseMs, st.targetMs - this.stepMs);
      this.sinceUnderrunS = 0;
    }
    if (this.srcRate === 0 || st.state === 'idle') return;
    const msToSamples = this.srcRate / 1000;
    if (st.state === 'buffering') {
      // Start once the target is buffered (or the stream ended short of it).
      if (this.fill < st.targetMs * msToSamples && !this.ended) return;
      st.state = 'playing';
      this.windowS = 0;
      this.minFill = Infinity;
    }
    // The lowest fill of each window: more than trimMs above the target all along is delay
    // that no jitter needed.
    this.minFill = Math.min(this.minFill, this.fill);
    this.windowS += quantumS;
    if (this.windowS >= this.trimS) {
      const excess = this.minFill - st.targetMs * msToSamples;
      if (excess > this.trimMs * msToSamples && !this.ended) {
        this.read += excess;
        ++st.trims;
        st.trimmedMs += excess / msToSamples;
      }
      this.windowS = 0;
      this.minFill = Infinity;
    }
    const slack = this.slackMs ?? Math.max(st.targetMs, 40);
    if (this.fill > (st.targetMs + slack) * msToSamples) {
      const skip = this.fill - st.targetMs * msToSamples;
      this.read += skip;
      ++st.skips;
      st.skippedMs += skip / msToSamples;
    }
    const step = this.srcRate / this.opts.outRate;
    const cap = this.ring.length;
    for (let i = 0; i < out.length; ++i) {
      // Blocks that start at or before this read position go out with this sample.
      while (this.pending.length && this.pending[0].start <= this.read) {
        const p = this.pending.shift()!;
        if (this.read - p.start < step) {
          played.push({ meta: p.meta, frame: frame + i - (this.read - p.start) / step });
          ++st.played;
        }
      }
      const k = Math.floor(this.read);
      if (k >= this.written) {
        if (this.ended) {
          st.state = 'idle';
          this.ended = false;
        } else {
          ++st.underruns;
          this.sinceUnderrunS = 0;
          if (this.adaptive) st.targetMs = Math.min(this.maxMs, st.targetMs + this.stepMs);
          st.state = 'buffering';
        }
        break;
      }
      const a = this.ring[k % cap];
      // The next sample, or the last one held when it has not arrived yet.
      const b = k + 1 < this.written ? this.ring[(k + 1) % cap] : a;
      const t = this.read - k;
      out[i] = a + (b - a) * t;
      this.read += step;
    }
    st.fillMs = (Math.max(this.fill, 0) / this.srcRate) * 1000;
  }
}
