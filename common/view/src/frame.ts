// Decoding the binary state frames (common/view/view_frame.h has the layout; the two must
// agree, kFrameVersion changes with it). Decoding only makes typed-array views over the
// message: no copies, nothing drawn here.

export const FRAME_MAGIC = 0x4658444d; // "MDXF"
export const FRAME_VERSION = 4;
export const HEADER_BYTES = 16;
export const SCALAR_COUNT = 91;
export const MAX_STITCHES = 16;

export const HAS_NEEDLE = 1;
export const HAS_THREAD = 2;
export const HAS_TISSUE = 4;
export const HAS_SCORE = 8;
export const HAS_TELEMETRY = 16;
export const HAS_OVERLAY = 32;
export const HAS_SECOND_TOOL = 64;

// The cue overlay's bounds (common/cues/cue_overlay.h).
export const MAX_OVERLAY_POLYLINES = 8;
export const MAX_OVERLAY_POINTS = 64;
export const MAX_OVERLAY_LABELS = 4;
const LABEL_TEXT_BYTES = 32;

// Scalar indices (float64), as in view_frame.h.
export const S = {
  stampMs: 0,
  step: 1,
  sentMs: 2,
  toolP: 3,
  toolQ: 6,
  toolForce: 10,
  activeCues: 13,
  tremorRms: 14,
  needleP: 15,
  needleQ: 18,
  clearance: 22,
  contact: 23,
  threadStrain: 24,
  graspedNode: 25,
  tissueNodesX: 26,
  tissueNodesY: 27,
  tissueDepth: 28,
  tissueP: 29,
  tissueQ: 32,
  tissueLx: 36,
  tissueLy: 37,
  score: 38,
  progress: 39,
  outcome: 40,
  periodP99Ms: 41,
  overruns: 42,
  presence: 43,
  toolAgeMs: 44,
  tool2P: 48,
  tool2Q: 51,
  tool2Force: 55,
  stitchCount: 58, // knot placement: the stitches placed so far
  stitchAzimuth: 59, // MAX_STITCHES slots, rad about the vessel axis
  stitchBite: 75, // MAX_STITCHES slots, m below the cut edge
} as const;

// The visual cues as drawing data (common/cues/cue_overlay.h): world points, colours 0..1.
export interface OverlayPolyline { role: number; rgba: Float32Array; widthM: number; points: Float32Array }
export interface OverlayLabel { role: number; rgba: Float32Array; p: Float32Array; text: string }
export interface Overlay { polylines: OverlayPolyline[]; labels: OverlayLabel[] }

export interface Frame {
  flags: number;
  slot: number;
  scalars: Float64Array; // SCALAR_COUNT values
  threadNodes: Float32Array; // x, y, z per node (world, m)
  tissue: Float32Array; // nodesX * nodesY displacements (x fastest, m)
  tissueNodesX: number;
  tissueNodesY: number;
  overlay: Overlay | null; // null: the frame carries none (the view keeps what it drew)
}

export class FrameError extends Error {}

// Decodes one frame; throws FrameError naming what is wrong (a short or foreign message).
export function decodeFrame(buffer: ArrayBuffer): Frame {
  if (buffer.byteLength < HEADER_BYTES + SCALAR_COUNT * 8) {
    throw new FrameError(`frame: ${buffer.byteLength} bytes, shorter than its header`);
  }
  const view = new DataView(buffer);
  const magic = view.getUint32(0, true);
  if (magic !== FRAME_MAGIC) throw new FrameError(`frame: bad magic 0x${magic.toString(16)}`);
  const version = view.getUint16(4, true);
  if (version !== FRAME_VERSION) {
    throw new FrameError(`frame: version ${version}, this page reads ${FRAME_VERSION}`);
  }
  const flags = view.getUint16(6, true);
  const slot = view.getUint32(8, true);
  const threadCount = view.getUint32(12, true);
  const scalars = new Float64Array(buffer, HEADER_BYTES, SCALAR_COUNT);
  let offset = HEADER_BYTES + SCALAR_COUNT * 8;
  const threadBytes = threadCount * 12;
  if ((flags & HAS_THREAD) === 0 && threadCount !== 0) {
    throw new FrameError('frame: thread nodes without the thread flag');
  }
  if (offset + threadBytes > buffer.byteLength) {
    throw new FrameError(`frame: ${threadCount} thread nodes overrun the message`);
  }
  const threadNodes = new Float32Array(buffer, offset, threadCount * 3);
  offset += threadBytes;
  let tissueNodesX = 0;
  let tissueNodesY = 0;
  if (flags & HAS_TISSUE) {
    tissueNodesX = scalars[S.tissueNodesX];
    tissueNodesY = scalars[S.tissueNodesY];
    if (!Number.isInteger(tissueNodesX) || !Number.isInteger(tissueNodesY) ||
        tissueNodesX < 2 || tissueNodesY < 2) {
      throw new FrameError(`frame: tissue grid ${tissueNodesX} x ${tissueNodesY}`);
    }
  }
  const tissueCount = tissueNodesX * tissueNodesY;
  const tissueEnd = offset + tissueCount * 4;
  if (tissueEnd > buffer.byteLength || ((flags & HAS_OVERLAY) === 0 && tissueEnd !== buffer.byteLength)) {
    throw new FrameError(`frame: ${buffer.byteLength} bytes, expected ${tissueEnd}`);
  }
  const tissue = new Float32Array(buffer, offset, tissueCount);
  offset = tissueEnd;
  let overlay: Overlay | null = null;
  if (flags & HAS_OVERLAY) {
    overlay = decodeOverlay(buffer, offset);
  }
  return { flags, slot, scalars, threadNodes, tissue, tissueNodesX, tissueNodesY, overlay };
}

// The overlay section, which must end the message exactly.
function decodeOverlay(buffer: ArrayBuffer, start: number): Overlay {
  let at = start;
  const need = (bytes: number, what: string) => {
    if (at + bytes > buffer.byteLength) throw new FrameError(`frame: overlay ${what} overruns the message`);
  };
  const count = (v: number, max: number, what: string) => {
    if (!Number.isInteger(v) || v < 0 || v > max) throw new FrameError(`frame: overlay ${what} ${v} (0..${max})`);
    return v;
  };
  need(8, 'counts');
  const head = new Float32Array(buffer, at, 2);
  const lines = count(head[0], MAX_OVERLAY_POLYLINES, 'polyline count');
  const labels = count(head[1], MAX_OVERLAY_LABELS, 'label count');
  at += 8;
  const out: Overlay = { polylines: [], labels: [] };
  for (let i = 0; i < lines; ++i) {
    need(28, 'polyline');
    const h = new Float32Array(buffer, at, 7);
    const n = count(h[6], MAX_OVERLAY_POINTS, 'point count');
    at += 28;
    need(n * 12, 'points');
    out.polylines.push({ role: h[0], rgba: h.subarray(1, 5), widthM: h[5],
                         points: new Float32Array(buffer, at, n * 3) });
    at += n * 12;
  }
  for (let i = 0; i < labels; ++i) {
    need(32 + LABEL_TEXT_BYTES, 'label');
    const h = new Float32Array(buffer, at, 8);
    const bytes = new Uint8Array(buffer, at + 32, LABEL_TEXT_BYTES);
    const end = bytes.indexOf(0);
    const text = new TextDecoder().decode(bytes.subarray(0, end < 0 ? LABEL_TEXT_BYTES : end));
    out.labels.push({ role: h[0], rgba: h.subarray(1, 5), p: h.subarray(5, 8), text });
    at += 32 + LABEL_TEXT_BYTES;
  }
  if (at !== buffer.byteLength) {
    throw new FrameError(`frame: ${buffer.byteLength} bytes, expected ${at}`);
  }
  return out;
}

// Bits of the active cues: bit k is cues::CueKind k (common/cues/cue_kind.h, same order).
export const CUE_KINDS = [
  'clear', 'convergent', 'divergent', 'amplified_tremor', 'visual_path', 'visual_limits',
  'visual_deviation', 'visual_clearance', 'audio_click', 'audio_error', 'audio_proximity',
  'audio_geiger', 'wall', 'predictive',
] as const;
export function activeCueNames(mask: number): string[] {
  return CUE_KINDS.filter((_, i) => i > 0 && (mask & (1 << i)) !== 0);
}
