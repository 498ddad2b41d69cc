// The station's microscope view: the shared scene objects (common/view/src) drawn through the
// scene's microscope, the live score and task state, stereo, and the keyboard and mouse as the
// station's device when it runs with --device page.

import * as THREE from 'three';
import { AnaglyphEffect } from 'three/examples/jsm/effects/AnaglyphEffect.js';
import { StereoEffect } from 'three/examples/jsm/effects/StereoEffect.js';
import { VRButton } from 'three/examples/jsm/webxr/VRButton.js';
import { Frame, S, activeCueNames, decodeFrame, HAS_NEEDLE, HAS_SCORE, HAS_THREAD, HAS_TISSUE } from '../../common/view/src/frame';
import { SceneJson, SceneView, HIGH_DETAIL, fieldOfView } from '../../common/view/src/scene_objects';
import { microscopeCamera, screenAxes, softwareGl } from '../../common/view/src/microscope';
import { socketUrl } from '../../common/view/src/socket';
import { FrameLink } from '../../common/view/src/frame_link';
import { AudioPlayer } from '../../common/view/src/audio_player';

const OUTCOMES = ['running', 'completed', 'time limit'];
type StereoMode = 'mono' | 'anaglyph' | 'side-by-side';
const STEREO_MODES: StereoMode[] = ['mono', 'anaglyph', 'side-by-side'];

// What the tests and the measurement script read (window.microdexView).
interface ViewProbe {
  ready: boolean;
  framesReceived: number;
  framesDrawn: number;
  badFrames: number;
  lastFrame: Frame | null;
  latencyMs: number[]; // tick stamp → the frame drawn (page clock, CLOCK_REALTIME)
  receivedMs: number[]; // tick stamp → the frame received by the page
  encodedMs: number[]; // tick stamp → the frame encoded by the station's publisher thread
  fps: number;
  stereo: StereoMode;
  sharedFrames: boolean; // frames through the worker's shared buffer (frame_link.ts)
  freeze: boolean; // keep drawing the last frame applied (tests: a still image to compare)
  project(p: [number, number, number]): [number, number];
  needleScreen(): [number, number] | null;
  toolPosition(): [number, number, number];
  screenAxes(): { right: number[]; up: number[]; forward: number[] };
}

async function main(): Promise<void> {
  const [scene, info] = await Promise.all([
    fetch('/scene.json').then((r) => r.json()) as Promise<SceneJson>,
    fetch('/info.json').then((r) => r.json()) as Promise<{ station_id: string; device: string }>,
  ]);
  const params = new URLSearchParams(location.search);
  const container = document.getElementById('view')!;
  // Multisampling costs a software renderer more than the rest of the frame: off there
  // unless ?aa=1.
  const aa = params.get('aa');
  const renderer = new THREE.WebGLRenderer({ antialias: aa !== null ? aa !== '0' : !softwareGl() });
  renderer.setPixelRatio(1);
  renderer.setSize(window.innerWidth, window.innerHeight);
  renderer.setClearColor(0x101418);
  container.appendChild(renderer.domElement);

  const world = new THREE.Scene();
  world.fog = new THREE.Fog(0x101418, 0, 1); // set from the camera below
  const view = new SceneView(scene, HIGH_DETAIL);
  world.add(view.root);
  const camera = microscopeCamera(scene, window.innerWidth / window.innerHeight);
  const dist = camera.position.distanceTo(new THREE.Vector3(...scene.microscope.look_at));
  (world.fog as THREE.Fog).near = dist * 0.9;
  (world.fog as THREE.Fog).far = dist * 3;

  const anaglyph = new AnaglyphEffect(renderer, window.innerWidth, window.innerHeight);
  const sbs = new StereoEffect(renderer);
  // three's stereo cameras have a human eye separation (64 mm); the microscope's scene is
  // millimetres across, so the stereo views draw a scaled copy of it: eyes 1/20 of the
  // working distance apart (about 3°, a surgical microscope's stereo angle), converging at
  // look_at.
  const stereoCamera = new THREE.PerspectiveCamera();
  const renderStereo = (effect: { render(s: THREE.Scene, c: THREE.Camera): void }) => {
    const k = (0.064 * 20) / dist;
    stereoCamera.copy(camera);
    stereoCamera.position.multiplyScalar(k);
    stereoCamera.near *= k;
    stereoCamera.far *= k;
    stereoCamera.focus = dist * k;
    stereoCamera.updateProjectionMatrix();
    stereoCamera.updateMatrixWorld();
    const fog = world.fog as THREE.Fog;
    world.scale.setScalar(k);
    fog.near *= k;
    fog.far *= k;
    effect.render(world, stereoCamera);
    world.scale.setScalar(1);
    fog.near /= k;
    fog.far /= k;
  };
  let stereo: StereoMode = (STEREO_MODES as string[]).includes(params.get('stereo') ?? '')
      ? params.get('stereo') as StereoMode : 'mono';
  const stereoButton = document.getElementById('stereo') as HTMLButtonElement;
  const setStereo = (m: StereoMode) => {
    stereo = m;
    probe.stereo = m;
    stereoButton.textContent = `stereo: ${m}`;
    renderer.setSize(window.innerWidth, window.innerHeight);
  };
  stereoButton.onclick = () => setStereo(STEREO_MODES[(STEREO_MODES.indexOf(stereo) + 1) % 3]);
  if ('xr' in navigator) {
    (navigator as any).xr?.isSessionSupported('immersive-vr').then((ok: boolean) => {
      if (!ok) return;
      renderer.xr.enabled = true;
      document.getElementById('controls')!.appendChild(VRButton.createButton(renderer));
    }).catch(() => undefined);
  }

  const probe: ViewProbe = {
    ready: false, framesReceived: 0, framesDrawn: 0, badFrames: 0, lastFrame: null,
    latencyMs: [], receivedMs: [], encodedMs: [], fps: 0, stereo, freeze: false, sharedFrames: false,
    project(p) {
      const v = new THREE.Vector3(...p).project(camera);
      return [(v.x + 1) / 2 * window.innerWidth, (1 - v.y) / 2 * window.innerHeight];
    },
    needleScreen() {
      const m = view.needleMidpointWorld();
      return m ? probe.project([m.x, m.y, m.z]) : null;
    },
    toolPosition() {
      return [view.tool.position.x, view.tool.position.y, view.tool.position.z];
    },
    screenAxes() {
      const a = screenAxes(camera);
      return { right: a.right.toArray(), up: a.up.toArray(), forward: a.forward.toArray() };
    },
  };
  (window as any).microdexView = probe;
  setStereo(stereo);

  const link = new FrameLink(socketUrl(), 'frame_worker.js', {
    onText(m) { if (m.type === 'error') console.warn(`station: ${m.error}`); },
    onStatus(open) {
      document.getElementById('link')!.innerHTML = open ? '' : '<span class="warn">disconnected</span>';
      if (open) audio.relink();
    },
  });
  probe.sharedFrames = link.shared;

  // The station's audio cues (the toggle: browsers start audio on a user gesture; ?audio=1
  // tries at once). ?audio_buffer=MS: the jitter buffer's target (30), ?audio_adapt=0 keeps it
  // fixed, ?audio_rate=HZ asks the AudioContext for that rate.
  const num = (k: string) => (params.get(k) !== null ? Number(params.get(k)) : undefined);
  const audio = new AudioPlayer(link, {
    targetMs: num('audio_buffer'), adaptive: params.get('audio_adapt') !== '0', sampleRate: num('audio_rate'),
  });
  (window as any).__audioStats = audio;
  const audioButton = document.getElementById('audio') as HTMLButtonElement;
  const hudAudio = document.getElementById('audio-status')!;
  const setAudio = async (on: boolean) => {
    try {
      if (on) await audio.start();
      else await audio.stop();
    } catch (e) {
      hudAudio.innerHTML = `<span class="warn">audio: ${String(e)}</span>`;
    }
    audioButton.textContent = `audio: ${audio.stats.on ? 'on' : 'off'}`;
  };
  audioButton.onclick = () => { void setAudio(!audio.stats.on); };
  if (params.get('audio') === '1') void setAudio(true);
  const showAudio = () => {
    const a = audio.stats;
    if (!a.on) { hudAudio.textContent = ''; return; }
    const j = a.jitter;
    const f = (x: number) => (Number.isFinite(x) ? x.toFixed(1) : '–');
    hudAudio.textContent = `audio: cause → sound p50 ${f(a.p50)} ms · p99 ${f(a.p99)} ms · ` +
        `buffer ${j ? j.targetMs.toFixed(0) : '–'} ms · underruns ${j ? j.underruns : 0}` +
        (a.lastMeta && a.lastMeta.toneHz > 0 ? ` · tone ${a.lastMeta.toneHz.toFixed(0)} Hz` : '');
  };
  setInterval(showAudio, 500);
  // The newest frame, decoded (null: none new, or a bad one, counted).
  const takeFrame = (): Frame | null => {
    const t = link.take(0);
    if (!t) return null;
    try {
      const f = decodeFrame(t.buffer);
      ++probe.framesReceived;
      if (probe.receivedMs.length < 100000) {
        probe.receivedMs.push(t.receivedMs - f.scalars[S.stampMs]);
        probe.encodedMs.push(f.scalars[S.sentMs] - f.scalars[S.stampMs]);
      }
      return f;
    } catch (e) {
      ++probe.badFrames;
      console.warn(String(e));
      return null;
    }
  };

  // Keyboard and mouse as the device.
  const device = info.device === 'page' ? new PageInput(camera, scene, (m) => link.send(m)) : null;
  document.getElementById('help')!.textContent = device
      ? 'arrows/WASD move · R/F depth · Q/E roll · space grip · 1–5 buttons · drag: move · V stereo'
      : 'watching (the station\'s device is not this page) · V stereo';
  window.addEventListener('keydown', (e) => {
    if (e.key === 'v' || e.key === 'V') stereoButton.click();
  });

  window.addEventListener('resize', () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    anaglyph.setSize(window.innerWidth, window.innerHeight);
  });

  const hudScore = document.getElementById('score')!;
  const hudTask = document.getElementById('task')!;
  const hudState = document.getElementById('state')!;
  const hudCues = document.getElementById('cues')!;
  const drawing = params.get('draw') !== '0';
  let fpsCount = 0;
  let fpsStart = performance.now();
  let lastT = performance.now();
  renderer.setAnimationLoop(() => {
    const t = performance.now();
    device?.tick((t - lastT) / 1000);
    lastT = t;
    const f = probe.freeze ? null : takeFrame();
    if (f) {
      view.apply(f);
      probe.lastFrame = f;
      ++probe.framesDrawn;
      const s = f.scalars;
      if (probe.latencyMs.length < 100000) {
        probe.latencyMs.push(performance.timeOrigin + performance.now() - s[S.stampMs]);
      }
      hudScore.textContent = f.flags & HAS_SCORE
          ? `score ${s[S.score].toFixed(1)} · ${(s[S.progress] * 100).toFixed(0)} %` : 'score –';
      hudTask.textContent = `${scene.name} · ${scene.task} · ${OUTCOMES[s[S.outcome]] ?? '?'} · step ${s[S.step]}`;
      const parts: string[] = [];
      if (f.flags & HAS_NEEDLE) {
        parts.push(s[S.contact] ? '<span class="warn">needle touching</span>'
                                : `clearance ${(s[S.clearance] * 1e3).toFixed(3)} mm`);
      }
      if (f.flags & HAS_THREAD) parts.push(`strain ${(s[S.threadStrain] * 100).toFixed(2)} %`);
      if (f.flags & HAS_TISSUE) parts.push(`depth ${(s[S.tissueDepth] * 1e3).toFixed(3)} mm`);
      parts.push(`tremor ${(s[S.tremorRms] * 1e6).toFixed(0)} µm`);
      hudState.innerHTML = parts.join(' · ');
      const cues = activeCueNames(s[S.activeCues]);
      hudCues.textContent = cues.length ? `cues: ${cues.join(', ')}` : '';
    }
    if (!drawing) { /* ?draw=0: measurements of the page without its rendering */ }
    else if (stereo === 'anaglyph') renderStereo(anaglyph);
    else if (stereo === 'side-by-side') renderStereo(sbs);
    else renderer.render(world, camera);
    ++fpsCount;
    if (t - fpsStart >= 1000) {
      probe.fps = (fpsCount * 1000) / (t - fpsStart);
      fpsCount = 0;
      fpsStart = t;
    }
    link.drew();
    probe.ready = true;
  });
}

// Keys and mouse drags → small world moves of the tool (in the image plane, and along the
// view axis for depth), sent at most once per animation frame.
class PageInput {
  private keys = new Set<string>();
  private drag: { x: number; y: number } | null = null;
  private dragMove = new THREE.Vector3();
  private grip = 0;
  private readonly speed: number; // m/s at full key press

  constructor(private readonly camera: THREE.Camera, scene: SceneJson,
              private readonly send: (m: string) => void) {
    this.speed = fieldOfView(scene) / 4;
    window.addEventListener('keydown', (e) => {
      this.keys.add(e.key.toLowerCase());
      if (e.key === ' ') {
        this.grip = this.grip > 0.5 ? 0 : 1;
        this.send(`grip ${this.grip}`);
      }
      if (e.key >= '1' && e.key <= '5') this.send(`buttons ${Number(e.key)}`);
    });
    window.addEventListener('keyup', (e) => {
      this.keys.delete(e.key.toLowerCase());
      if (e.key >= '1' && e.key <= '5') this.send('buttons 0');
    });
    window.addEventListener('blur', () => this.keys.clear());
    const el = document.body;
    el.addEventListener('mousedown', (e) => { this.drag = { x: e.clientX, y: e.clientY }; });
    window.addEventListener('mouseup', () => { this.drag = null; });
    window.addEventListener('mousemove', (e) => {
      if (!this.drag) return;
      const perPixel = this.speed * 4 / window.innerHeight;
      const { right, up } = screenAxes(this.camera);
      this.dragMove.addScaledVector(right, (e.clientX - this.drag.x) * perPixel)
          .addScaledVector(up, -(e.clientY - this.drag.y) * perPixel);
      this.drag = { x: e.clientX, y: e.clientY };
    });
  }

  tick(dt: number): void {
    const { right, up, forward } = screenAxes(this.camera);
    const k = (a: string, b: string) => (this.keys.has(a) || this.keys.has(b) ? 1 : 0);
    const fine = this.keys.has('shift') ? 0.2 : 1;
    const step = this.speed * Math.min(dt, 0.1) * fine;
    const move = this.dragMove.clone();
    this.dragMove.set(0, 0, 0);
    move.addScaledVector(right, (k('arrowright', 'd') - k('arrowleft', 'a')) * step);
    move.addScaledVector(up, (k('arrowup', 'w') - k('arrowdown', 's')) * step);
    move.addScaledVector(forward, (k('f', 'pagedown') - k('r', 'pageup')) * step);
    const len = move.length();
    if (len > 0) {
      if (len > 1.9e-3) move.multiplyScalar(1.9e-3 / len);
      this.send(`move ${move.x.toExponential(6)} ${move.y.toExponential(6)} ${move.z.toExponential(6)}`);
    }
    const roll = (k('e', 'e') - k('q', 'q')) * Math.min(dt, 0.1) * 1.0;
    if (roll !== 0) {
      const axis = forward.clone().multiplyScalar(roll);
      this.send(`turn ${axis.x.toExponential(6)} ${axis.y.toExponential(6)} ${axis.z.toExponential(6)}`);
    }
  }
}

main().catch((e) => {
  document.body.insertAdjacentHTML('beforeend', `<pre class="warn" style="position:fixed;bottom:0">${String(e)}</pre>`);
});
