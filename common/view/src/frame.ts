// Decoding the binary state frames (common/view/view_frame.h has the layout; the two must
// agree, kFrameVersion changes with it). Decoding only makes typed-array views over the
// message: no copies, nothing drawn here.

export const FRAME_MAGIC = 0x4658444d; // "MDXF"
export const FRAME_VERSION = 1;
export const HEADER_BYTES = 16;
export const SCALAR_COUNT = 48;

export const HAS_NEEDLE = 1;
export const HAS_THREAD = 2;
export const HAS_TISSUE = 4;
export const HAS_SCORE = 8;
export const HAS_TELEMETRY = 16;

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
} as const;

export interface Frame {
  flags: number;
  slot: number;
  scalars: Float64Array; // SCALAR_COUNT values
  threadNodes: Float32Array; // x, y, z per node (world, m)
  tissue: Float32Array; // nodesX * nodesY displacements (x fastest, m)
  tissueNodesX: number;
  tissueNodesY: number;
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
  if (offset + tissueCount * 4 !== buffer.byteLength) {
    throw new FrameError(
        `frame: ${buffer.byteLength} bytes, expected ${offset + tissueCount * 4}`);
  }
  const tissue = new Float32Array(buffer, offset, tissueCount);
  return { flags, slot, scalars, threadNodes, tissue, tissueNodesX, tissueNodesY };
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
