// Frame decoding (common/view/src/frame.ts) against frames laid out as view_frame.h writes
// them, and its refusals of short, foreign and inconsistent messages.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import {
  decodeFrame, FrameError, FRAME_MAGIC, FRAME_VERSION, HAS_NEEDLE, HAS_OVERLAY, HAS_THREAD, HAS_TISSUE,
  HEADER_BYTES, S, SCALAR_COUNT, activeCueNames,
} from '../../../common/view/src/frame';

interface Parts { flags: number; slot?: number; scalars: Record<number, number>;
                  thread?: number[]; tissue?: number[]; extraBytes?: number; overlay?: number[];
                  magic?: number; version?: number; threadCount?: number }

// Writes a frame the way view_frame.cc does.
function encode(p: Parts): ArrayBuffer {
  const thread = p.thread ?? [];
  const tissue = p.tissue ?? [];
  const overlay = p.overlay ?? [];
  const bytes = HEADER_BYTES + SCALAR_COUNT * 8 + thread.length * 4 + tissue.length * 4 +
                overlay.length * 4 + (p.extraBytes ?? 0);
  const buf = new ArrayBuffer(bytes);
  const v = new DataView(buf);
  v.setUint32(0, p.magic ?? FRAME_MAGIC, true);
  v.setUint16(4, p.version ?? FRAME_VERSION, true);
  v.setUint16(6, p.flags, true);
  v.setUint32(8, p.slot ?? 0, true);
  v.setUint32(12, p.threadCount ?? thread.length / 3, true);
  for (const [k, val] of Object.entries(p.scalars)) v.setFloat64(HEADER_BYTES + Number(k) * 8, val, true);
  let o = HEADER_BYTES + SCALAR_COUNT * 8;
  for (const x of thread) { v.setFloat32(o, x, true); o += 4; }
  for (const x of tissue) { v.setFloat32(o, x, true); o += 4; }
  for (const x of overlay) { v.setFloat32(o, x, true); o += 4; }
  return buf;
}

// An overlay section as view_frame.cc writes it: one polyline of two points and one label
// (its text packed into the 32 bytes that follow its 8 numbers, little-endian floats reused
// as bytes).
function overlaySection(text: string): number[] {
  const out = [1, 1, /* polyline */ 2, 1, 0.5, 0, 0.8, 0, 2, 0.001, 0.002, 0.003, 0.004, 0.005, 0.006,
               /* label */ 4, 0, 1, 1, 1, 0.01, 0.02, 0.03];
  const bytes = new Uint8Array(32);
  bytes.set(new TextEncoder().encode(text));
  const asFloats = new Float32Array(bytes.buffer);
  return out.concat(Array.from(asFloats));
}

test('the cue overlay: polylines and labels after the tissue field', () => {
  const f = decodeFrame(encode({ flags: HAS_TISSUE | HAS_OVERLAY, tissue: [0, 0, 0, 0],
    scalars: { [S.tissueNodesX]: 2, [S.tissueNodesY]: 2 }, overlay: overlaySection('0.42 mm') }));
  assert.ok(f.overlay);
  assert.equal(f.overlay.polylines.length, 1);
  const pl = f.overlay.polylines[0];
  assert.equal(pl.role, 2);
  assert.equal(pl.points.length, 6);
  assert.ok(Math.abs(pl.points[5] - 0.006) < 1e-7);
  assert.ok(Math.abs(pl.rgba[1] - 0.5) < 1e-7);
  assert.equal(f.overlay.labels.length, 1);
  assert.equal(f.overlay.labels[0].text, '0.42 mm');
  assert.ok(Math.abs(f.overlay.labels[0].p[2] - 0.03) < 1e-7);
});

test('an overlay out of its bounds or short is refused', () => {
  const tooMany = overlaySection('x');
  tooMany[0] = 9; // polylines: at most 8
  assert.throws(() => decodeFrame(encode({ flags: HAS_OVERLAY, scalars: {}, overlay: tooMany })),
                /polyline count 9/);
  const cut = overlaySection('x').slice(0, 12);
  assert.throws(() => decodeFrame(encode({ flags: HAS_OVERLAY, scalars: {}, overlay: cut })), /overruns/);
  const points = overlaySection('x');
  points[8] = 65; // points: at most 64
  assert.throws(() => decodeFrame(encode({ flags: HAS_OVERLAY, scalars: {}, overlay: points })),
                /point count 65/);
  assert.throws(() => decodeFrame(encode({ flags: HAS_OVERLAY, scalars: {}, overlay: overlaySection('x'),
                                           extraBytes: 4 })), /expected/);
});

test('the magic is "MDXF" as little-endian bytes', () => {
  const b = new Uint8Array(encode({ flags: 0, scalars: {} }));
  assert.equal(String.fromCharCode(b[0], b[1], b[2], b[3]), 'MDXF');
});

test('a needle frame: scalars at their indices', () => {
  const f = decodeFrame(encode({ flags: HAS_NEEDLE, slot: 5, scalars: {
    [S.stampMs]: 1.7e12 + 0.25, [S.step]: 4242, [S.toolP]: 1e-3, [S.toolP + 2]: -2e-3,
    [S.needleQ]: 0.5, [S.clearance]: 1.25e-4, [S.contact]: 1 } }));
  assert.equal(f.slot, 5);
  assert.equal(f.flags, HAS_NEEDLE);
  assert.equal(f.scalars[S.step], 4242);
  assert.equal(f.scalars[S.stampMs], 1.7e12 + 0.25);
  assert.equal(f.scalars[S.toolP + 2], -2e-3);
  assert.equal(f.scalars[S.clearance], 1.25e-4);
  assert.equal(f.threadNodes.length, 0);
  assert.equal(f.tissue.length, 0);
});

test('thread nodes and a tissue grid follow the scalars', () => {
  const thread = [0, 1, 2, 3, 4, 5, 6, 7, 8].map((x) => x * 1e-3);
  const tissue = Array.from({ length: 12 }, (_, i) => -i * 1e-5);
  const f = decodeFrame(encode({ flags: HAS_THREAD | HAS_TISSUE, thread, tissue,
    scalars: { [S.tissueNodesX]: 4, [S.tissueNodesY]: 3 } }));
  assert.equal(f.threadNodes.length, 9);
  assert.ok(Math.abs(f.threadNodes[8] - 8e-3) < 1e-9);
  assert.equal(f.tissueNodesX, 4);
  assert.equal(f.tissueNodesY, 3);
  assert.equal(f.tissue.length, 12);
  assert.ok(Math.abs(f.tissue[11] + 11e-5) < 1e-9);
});

test('bad frames are refused with a reason', () => {
  assert.throws(() => decodeFrame(new ArrayBuffer(20)), FrameError);
  assert.throws(() => decodeFrame(encode({ flags: 0, scalars: {}, magic: 0x12345678 })), /magic/);
  assert.throws(() => decodeFrame(encode({ flags: 0, scalars: {}, version: 9 })), /version 9/);
  // A node count that runs past the end of the message.
  assert.throws(() => decodeFrame(encode({ flags: HAS_THREAD, scalars: {}, threadCount: 1000 })),
                /overrun/);
  assert.throws(() => decodeFrame(encode({ flags: 0, scalars: {}, thread: [1, 2, 3] })),
                /without the thread flag/);
  // A tissue grid whose size does not match the bytes.
  assert.throws(() => decodeFrame(encode({ flags: HAS_TISSUE, tissue: [1, 2, 3],
    scalars: { [S.tissueNodesX]: 2, [S.tissueNodesY]: 2 } })), /bytes, expected/);
  assert.throws(() => decodeFrame(encode({ flags: HAS_TISSUE, tissue: [1, 2],
    scalars: { [S.tissueNodesX]: 1.5, [S.tissueNodesY]: 2 } })), /tissue grid/);
  assert.throws(() => decodeFrame(encode({ flags: 0, scalars: {}, extraBytes: 4 })), /expected/);
});

test('active cue names from the bit mask', () => {
  assert.deepEqual(activeCueNames(0), []);
  assert.deepEqual(activeCueNames((1 << 1) | (1 << 3)), ['convergent', 'amplified_tremor']);
  assert.deepEqual(activeCueNames(1 << 13), ['predictive']);
  assert.deepEqual(activeCueNames(1 << 0), []); // "clear" is a command, never in force
});
