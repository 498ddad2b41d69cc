// Decoding the station's audio cue blocks (common/view/view_audio.h has the layout; the two
// must agree, kAudioVersion changes with it): PCM the station rendered with its own synthesis,
// stamped with the step and tick stamp of the first sample and of the most recent audio cause.

export const AUDIO_MAGIC = 0x4158444d; // "MDXA"
export const AUDIO_VERSION = 1;
export const AUDIO_HEADER_BYTES = 88;
export const MAX_AUDIO_BLOCK_SAMPLES = 1024;

export const AUDIO_START = 1; // the first block after silence
export const AUDIO_END = 2; // the last block: no audio cue on any more

export const CAUSE_CLICK = 1;
export const CAUSE_ERROR = 2;
export const CAUSE_WARNING = 4;
export const CAUSE_PROXIMITY = 8;
export const CAUSE_GEIGER = 16;
export const CAUSE_CUE_ON = 32;
export const CAUSE_BEFORE = 0xffffffff; // causeOffset: the cause came before this block

export interface AudioBlockMeta {
  flags: number;
  sampleRate: number;
  samples: number;
  seq: number;
  firstStep: number;
  firstStampMs: number; // CLOCK_REALTIME of the first sample's tick
  causeStep: number;
  causeStampMs: number;
  cause: number;
  activeCues: number;
  toneHz: number; // the proximity tone's pitch at the block's last step (0: silent)
  clearanceM: number;
  geigerRateHz: number;
  causeOffset: number; // index of the cause step's first sample here, or CAUSE_BEFORE
  sentMs: number; // when the station's view server sent it (CLOCK_REALTIME)
  receivedMs: number; // when the page received it (performance.timeOrigin + now)
}

export interface AudioBlock { meta: AudioBlockMeta; pcm: Float32Array }

export class AudioBlockError extends Error {}

// True when the message is an audio block (by its magic), whatever else it holds.
export function isAudioBlock(buf: ArrayBuffer): boolean {
  return buf.byteLength >= 4 && new DataView(buf).getUint32(0, true) === AUDIO_MAGIC;
}

function u64(v: DataView, at: number): number {
  return v.getUint32(at, true) + v.getUint32(at + 4, true) * 4294967296;
}

// The block's header and a view of its samples (no copy); throws AudioBlockError for a
// message that is not a well-formed block of this version.
export function decodeAudioBlock(buf: ArrayBuffer, receivedMs = 0): AudioBlock {
  if (buf.byteLength < AUDIO_HEADER_BYTES) {
    throw new AudioBlockError(`audio block: ${buf.byteLength} bytes, shorter than its header`);
  }
  const v = new DataView(buf);
  if (v.getUint32(0, true) !== AUDIO_MAGIC) throw new AudioBlockError('audio block: bad magic');
  const version = v.getUint16(4, true);
  if (version !== AUDIO_VERSION) {
    throw new AudioBlockError(`audio block: version ${version}, expected ${AUDIO_VERSION}`);
  }
  const sampleRate = v.getUint32(8, true);
  const n = v.getUint32(12, true);
  if (n > MAX_AUDIO_BLOCK_SAMPLES || buf.byteLength !== AUDIO_HEADER_BYTES + 4 * n) {
    throw new AudioBlockError(`audio block: ${n} samples in ${buf.byteLength} bytes`);
  }
  if (sampleRate < 8000 || sampleRate > 192000) {
    throw new AudioBlockError(`audio block: sample rate ${sampleRate} Hz outside 8000..192000`);
  }
  const causeOffset = v.getUint32(76, true);
  if (causeOffset !== CAUSE_BEFORE && causeOffset >= n) {
    throw new AudioBlockError(`audio block: cause at sample ${causeOffset} of ${n}`);
  }
  const pcm = new Float32Array(buf, AUDIO_HEADER_BYTES, n);
  for (let i = 0; i < n; ++i) {
    if (!(Math.abs(pcm[i]) <= 1)) throw new AudioBlockError(`audio block: sample ${i} is not in [-1, 1]`);
  }
  return {
    meta: {
      flags: v.getUint16(6, true),
      sampleRate,
      samples: n,
      seq: u64(v, 16),
      firstStep: u64(v, 24),
      firstStampMs: v.getFloat64(32, true),
      causeStep: u64(v, 40),
      causeStampMs: v.getFloat64(48, true),
      cause: v.getUint32(56, true),
      activeCues: v.getUint32(60, true),
      toneHz: v.getFloat32(64, true),
      clearanceM: v.getFloat32(68, true),
      geigerRateHz: v.getFloat32(72, true),
      causeOffset,
      sentMs: v.getFloat64(80, true),
      receivedMs,
    },
    pcm,
  };
}
