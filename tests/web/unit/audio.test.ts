// The page's audio path without a browser: audio blocks decoded as view_audio.h lays them out
// (and refused when malformed); the jitter buffer (audio_jitter.ts) waits for its target,
// plays blocks gap-free across block boundaries, resamples 44.1 → 48 kHz at the right pitch,
// reports where each block's first sample went out, counts underruns, gaps and skips, and
// adapts its target.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import {
  AUDIO_END, AUDIO_HEADER_BYTES, AUDIO_MAGIC, AUDIO_START, AUDIO_VERSION, AudioBlockError,
  CAUSE_BEFORE, CAUSE_PROXIMITY, decodeAudioBlock, isAudioBlock,
} from '../../../common/view/src/audio_block';
import { JitterBuffer, PlayedBlock } from '../../../common/view/src/audio_jitter';

interface BlockParts { seq: number; pcm: Float32Array; flags?: number; rate?: number; firstStep?: number;
                       causeOffset?: number; toneHz?: number }

// Writes a block the way view_audio.cc does.
function encode(p: BlockParts): ArrayBuffer {
  const buf = new ArrayBuffer(AUDIO_HEADER_BYTES + 4 * p.pcm.length);
  const v = new DataView(buf);
  v.setUint32(0, AUDIO_MAGIC, true);
  v.setUint16(4, AUDIO_VERSION, true);
  v.setUint16(6, p.flags ?? 0, true);
  v.setUint32(8, p.rate ?? 44100, true);
  v.setUint32(12, p.pcm.length, true);
  v.setUint32(16, p.seq % 4294967296, true);
  v.setUint32(20, Math.floor(p.seq / 4294967296), true);
  const step = p.firstStep ?? p.seq * 10;
  v.setUint32(24, step, true);
  v.setFloat64(32, 1.764e12 + step, true);
  v.setUint32(40, step + 9, true);
  v.setFloat64(48, 1.764e12 + step + 9, true);
  v.setUint32(56, CAUSE_PROXIMITY, true);
  v.setUint32(60, 1 << 10, true);
  v.setFloat32(64, p.toneHz ?? 1000, true);
  v.setFloat32(68, 3e-4, true);
  v.setUint32(76, p.causeOffset ?? CAUSE_BEFORE, true);
  v.setFloat64(80, 1.764e12 + step + 12.5, true);
  new Float32Array(buf, AUDIO_HEADER_BYTES, p.pcm.length).set(p.pcm);
  return buf;
}

function sine(hz: number, rate: number, n: number, from = 0, amp = 0.5): Float32Array {
  const out = new Float32Array(n);
  for (let i = 0; i < n; ++i) out[i] = amp * Math.sin((2 * Math.PI * hz * (from + i)) / rate);
  return out;
}

test('an audio block decodes to its fields and a view of its samples', () => {
  const pcm = sine(1000, 44100, 441);
  const buf = encode({ seq: 2 ** 33 + 5, pcm, flags: AUDIO_START, causeOffset: 397, toneHz: 1650.5 });
  assert.ok(isAudioBlock(buf));
  const b = decodeAudioBlock(buf, 42);
  assert.equal(b.meta.seq, 2 ** 33 + 5);
  assert.equal(b.meta.flags, AUDIO_START);
  assert.equal(b.meta.sampleRate, 44100);
  assert.equal(b.meta.samples, 441);
  assert.equal(b.meta.causeOffset, 397);
  assert.equal(b.meta.cause, CAUSE_PROXIMITY);
  assert.equal(b.meta.toneHz, Math.fround(1650.5));
  assert.ok(Math.abs(b.meta.clearanceM - 3e-4) < 1e-9);
  assert.equal(b.meta.receivedMs, 42);
  assert.equal(b.meta.causeStampMs - b.meta.firstStampMs, 9);
  assert.equal(b.meta.sentMs - b.meta.firstStampMs, 12.5);
  assert.equal(b.pcm.length, 441);
  assert.equal(b.pcm[100], Math.fround(pcm[100]));
});

test('malformed audio blocks are refused with their reason', () => {
  const good = encode({ seq: 1, pcm: sine(1000, 44100, 441) });
  const refused = (buf: ArrayBuffer, reason: RegExp) =>
    assert.throws(() => decodeAudioBlock(buf), (e: unknown) => e instanceof AudioBlockError && reason.test((e as Error).message));
  refused(good.slice(0, 87), /shorter than its header/);
  refused(good.slice(0, good.byteLength - 4), /441 samples in/);
  const edit = (f: (v: DataView) => void) => { const c = good.slice(0); f(new DataView(c)); return c; };
  refused(edit((v) => v.setUint32(0, 0x4658444d, true)), /bad magic/);
  assert.equal(isAudioBlock(edit((v) => v.setUint32(0, 0x4658444d, true))), false); // a state frame
  refused(edit((v) => v.setUint16(4, 9, true)), /version 9/);
  refused(edit((v) => v.setUint32(8, 1000, true)), /sample rate 1000/);
  refused(edit((v) => v.setUint32(76, 441, true)), /cause at sample 441/);
  refused(edit((v) => v.setFloat32(AUDIO_HEADER_BYTES + 8, NaN, true)), /sample 2 /);
  refused(edit((v) => v.setFloat32(AUDIO_HEADER_BYTES, 1.5, true)), /sample 0 /);
});

// Pushes blocks of a continuous tone and pulls 128-frame quanta, as the worklet does.
function run(jb: JitterBuffer, opts: { blocks: number; rate: number; hz: number; arrive?: (seq: number) => boolean }) {
  const out: number[] = [];
  const played: PlayedBlock[] = [];
  const starts: { seq: number; frame: number }[] = [];
  const quantum = new Float32Array(128);
  let frame = 0;
  let seq = 0;
  const blockS = 441 / 44100;
  // Each quantum, the blocks due by then arrive (one every 10 ms of output time).
  while (seq < opts.blocks || jb.stats.state === 'playing') {
    while (seq < opts.blocks && seq * blockS <= frame / opts.rate + 0.03) {
      if (!opts.arrive || opts.arrive(seq)) {
        const b = decodeAudioBlock(encode({ seq, pcm: sine(opts.hz, 44100, 441, seq * 441),
          flags: (seq === 0 ? AUDIO_START : 0) | (seq === opts.blocks - 1 ? AUDIO_END : 0) }));
        jb.push(b.meta, b.pcm);
      }
      ++seq;
    }
    jb.pull(quantum, frame, played);
    for (const p of played) starts.push({ seq: p.meta.seq, frame: p.frame });
    out.push(...quantum);
    frame += 128;
    if (frame > opts.rate * 10) break;
  }
  return { out: Float32Array.from(out), starts };
}

// Frequency from zero crossings (rising) over a stretch of the output.
function pitch(x: Float32Array, rate: number, from: number, to: number): number {
  let first = -1, last = -1, n = 0;
  for (let i = from + 1; i < to; ++i) {
    if (x[i - 1] < 0 && x[i] >= 0) {
      const t = i - 1 + (-x[i - 1]) / (x[i] - x[i - 1]);
      if (first < 0) first = t; else ++n;
      last = t;
    }
  }
  return (n * rate) / (last - first);
}

test('the jitter buffer waits for its target, then plays gap-free at the source pitch', () => {
  const jb = new JitterBuffer({ outRate: 44100, targetMs: 30, adaptive: false });
  const { out, starts } = run(jb, { blocks: 100, rate: 44100, hz: 1000 });
  // Silence until 30 ms are buffered, then the blocks' samples exactly, in order.
  const first = out.findIndex((v) => v !== 0);
  assert.ok(first > 0 && first < 44100 * 0.05, `sound starts at ${first}`);
  assert.equal(starts.length, 100);
  for (let i = 0; i < 100; ++i) {
    assert.equal(starts[i].seq, i);
    assert.ok(Math.abs(starts[i].frame - (starts[0].frame + 441 * i)) < 1e-6, `block ${i} at ${starts[i].frame}`);
  }
  const src = sine(1000, 44100, 44100);
  const s0 = Math.round(starts[0].frame);
  for (let i = 0; i < 44100; ++i) assert.equal(out[s0 + i], Math.fround(src[i]), `sample ${i}`);
  assert.equal(jb.stats.underruns, 0);
  assert.equal(jb.stats.gaps, 0);
  assert.equal(jb.stats.state, 'idle'); // the last block ended the stream: not an underrun
});

test('resampling 44.1 kHz to 48 kHz keeps the pitch and the blocks 480 frames apart', () => {
  const jb = new JitterBuffer({ outRate: 48000, targetMs: 30, adaptive: false });
  const { out, starts } = run(jb, { blocks: 200, rate: 48000, hz: 1650 });
  const s0 = Math.ceil(starts[0].frame);
  const hz = pitch(out, 48000, s0 + 100, s0 + 48000 * 1.5);
  assert.ok(Math.abs(hz - 1650) < 0.5, `pitch ${hz} Hz`);
  for (let i = 1; i < starts.length; ++i) {
    assert.ok(Math.abs(starts[i].frame - starts[i - 1].frame - 480) < 1e-6);
  }
  // Gap-free: no sample of the stream's body is silent where a sine of 0.5 should be.
  let quiet = 0;
  for (let i = s0 + 10; i < s0 + 48000 * 1.9; ++i) if (Math.abs(out[i]) < 1e-3 && Math.abs(out[i - 1]) < 1e-3) ++quiet;
  assert.equal(quiet, 0);
  assert.equal(jb.stats.underruns, 0);
});

test('a late block is an underrun: silence, counted, buffering again with a larger target', () => {
  const jb = new JitterBuffer({ outRate: 44100, targetMs: 30, stepMs: 10, maxMs: 60 });
  const played: PlayedBlock[] = [];
  const q = new Float32Array(128);
  let frame = 0;
  const push = (seq: number) => {
    const b = decodeAudioBlock(encode({ seq, pcm: sine(1000, 44100, 441, seq * 441) }));
    jb.push(b.meta, b.pcm);
  };
  for (let s = 0; s < 4; ++s) push(s); // 40 ms
  let sounding = 0;
  for (let i = 0; i < 20; ++i) { jb.pull(q, frame, played); frame += 128; if (q.some((v) => v !== 0)) ++sounding; }
  assert.ok(sounding > 0);
  assert.equal(jb.stats.underruns, 1); // 40 ms played out in 20 × 2.9 ms = 58 ms
  assert.equal(jb.stats.state, 'buffering');
  assert.equal(jb.stats.targetMs, 40);
  // Buffering again: silent until 40 ms are there.
  push(4); push(5); push(6);
  jb.pull(q, frame, played);
  assert.ok(q.every((v) => v === 0));
  push(7);
  jb.pull(q, frame, played);
  assert.ok(q.some((v) => v !== 0));
  assert.equal(jb.stats.state, 'playing');
});

test('missing blocks are counted as gaps; an over-full buffer skips ahead to its target', () => {
  const jb = new JitterBuffer({ outRate: 44100, targetMs: 30, adaptive: false, slackMs: 40 });
  const { starts } = run(jb, { blocks: 100, rate: 44100, hz: 1000, arrive: (s) => s !== 50 && s !== 51 });
  assert.equal(jb.stats.gaps, 2);
  assert.ok(!starts.some((s) => s.seq === 50 || s.seq === 51));
  // A burst: 200 ms arrive at once; the buffer keeps 30 ms of it.
  const jb2 = new JitterBuffer({ outRate: 44100, targetMs: 30, adaptive: false, slackMs: 40 });
  for (let s = 0; s < 20; ++s) {
    const b = decodeAudioBlock(encode({ seq: s, pcm: sine(1000, 44100, 441, s * 441) }));
    jb2.push(b.meta, b.pcm);
  }
  const played: PlayedBlock[] = [];
  jb2.pull(new Float32Array(128), 0, played);
  assert.equal(jb2.stats.skips, 1);
  assert.ok(Math.abs(jb2.stats.skippedMs - 170) < 0.1, `skipped ${jb2.stats.skippedMs} ms`);
  assert.ok(Math.abs(jb2.stats.fillMs - (30 - (128 / 44100) * 1000)) < 0.1);
  // The skipped blocks never went out: block 17 (at 170 ms) is the first.
  assert.deepEqual(played.map((p) => [p.meta.seq, p.frame]), [[17, 0]]);
});

test('the adaptive target shrinks back after a quiet spell', () => {
  const jb = new JitterBuffer({ outRate: 44100, targetMs: 30, stepMs: 10, relaxS: 1 });
  const played: PlayedBlock[] = [];
  const b = decodeAudioBlock(encode({ seq: 0, pcm: sine(1000, 44100, 441) }));
  jb.push(b.meta, b.pcm);
  const q = new Float32Array(128);
  for (let i = 0; i < 5; ++i) jb.pull(q, i * 128, played); // 10 ms buffered but 30 wanted: waits
  assert.equal(jb.stats.underruns, 0);
  // Force two underruns: play 10 ms blocks with nothing behind them.
  for (let k = 0; k < 2; ++k) {
    for (let s = 0; s < 6; ++s) {
      const x = decodeAudioBlock(encode({ seq: 1 + k * 6 + s, pcm: sine(1000, 44100, 441) }));
      jb.push(x.meta, x.pcm);
    }
    for (let i = 0; i < 40; ++i) jb.pull(q, i * 128, played);
  }
  assert.equal(jb.stats.underruns, 2);
  assert.equal(jb.stats.targetMs, 50);
  for (let i = 0; i < 400; ++i) jb.pull(q, i * 128, played); // 1.16 s without underrun
  assert.equal(jb.stats.targetMs, 40);
});

test('delay left above the target is trimmed after a window', () => {
  // 100 ms arrive before playing starts (target 30, no skip below 200 ms), then one block per
  // 10 ms: the lowest fill stays ~90 ms, so after a second the excess over 30 ms is dropped.
  const jb = new JitterBuffer({ outRate: 44100, targetMs: 30, adaptive: false, slackMs: 200, trimS: 1, trimMs: 10 });
  const played: PlayedBlock[] = [];
  const q = new Float32Array(128);
  let seq = 0;
  const push = () => {
    const b = decodeAudioBlock(encode({ seq, pcm: sine(1000, 44100, 441, seq * 441) }));
    jb.push(b.meta, b.pcm);
    ++seq;
  };
  for (let i = 0; i < 10; ++i) push();
  let frame = 0;
  const fills: number[] = [];
  while (frame < 44100 * 2) {
    while (seq - 10 < frame / 441) push(); // steady arrival after the first 100 ms
    jb.pull(q, frame, played);
    fills.push(jb.stats.fillMs);
    frame += 128;
  }
  assert.equal(jb.stats.trims, 1);
  assert.ok(jb.stats.trimmedMs > 55 && jb.stats.trimmedMs < 75, `trimmed ${jb.stats.trimmedMs} ms`);
  assert.equal(jb.stats.underruns, 0);
  const late = fills.slice(-100);
  // The fill after each quantum: the target less one quantum (2.9 ms) at the trough, one
  // block (10 ms) more at the peak.
  const quantumMs = (128 / 44100) * 1000;
  assert.ok(Math.min(...late) >= 30 - quantumMs - 0.1 && Math.max(...late) <= 40 + 0.1,
            `fill ${Math.min(...late)}..${Math.max(...late)} ms`);
});
