// The instructor's live console: one tile per mirrored station (up to 8 drawn; click to
// enlarge), drawn with the shared scene objects (common/view/src) at the tiles' level of
// detail by one renderer into scissored viewports; a cue panel per station with the
// station's acknowledgements; a score table.

import * as THREE from 'three';
import { Frame, S, activeCueNames, decodeFrame } from '../../common/view/src/frame';
import { LOW_DETAIL, SceneJson, SceneView } from '../../common/view/src/scene_objects';
import { microscopeCamera } from '../../common/view/src/microscope';
import { socketUrl } from '../../common/view/src/socket';
import { FrameLink, MAX_SLOTS } from '../../common/view/src/frame_link';

const MAX_TILES = 8;
const OUTCOMES = ['running', 'completed', 'time limit'];
// The cue kinds as the console server lists them (every kind of common/cues/cue_kind.h but
// clear, with its parameter's name and limits). The haptic ones are shown, the visual and
// audio ones under "more cues".
interface CueKindJson { kind: string; bit: number; param: string; min: number; max: number; default: number }
const SHOWN = ['convergent', 'divergent', 'amplified_tremor', 'wall'];
const PARAM_DEFAULTS: Record<string, number> = { convergent: 300, divergent: 300 };

interface CueJson {
  cue_id: number; kind: string; param: number; off: boolean; sent_ms: number;
  ack: null | { applied: boolean; step: number; text: string };
}
interface StationJson {
  slot: number; id: string; trainee: string; scene: string; device: string; presence: string;
  lost_by: string; heard_ms_ago: number; modules: string[]; period_p99_ms?: number;
  overruns?: number; score?: number; progress?: number; outcome?: number; task?: string;
  cues: CueJson[];
}

class Tile {
  readonly el: HTMLDivElement;
  readonly viewport: HTMLDivElement;
  readonly label: HTMLDivElement;
  readonly acks: HTMLDivElement;
  readonly inForce = new Map<number, HTMLElement>(); // by cue bit
  readonly touched = new Set<string>(); // kinds this console has switched
  world = new THREE.Scene();
  view: SceneView | null = null;
  camera: THREE.PerspectiveCamera | null = null;
  pending: Frame | null = null;
  frames = 0;
  station: StationJson;

  constructor(station: StationJson, kinds: CueKindJson[], send: (m: string) => boolean) {
    this.station = station;
    this.el = document.createElement('div');
    this.el.className = 'tile';
    this.el.dataset.station = station.id;
    this.viewport = document.createElement('div');
    this.viewport.className = 'viewport';
    this.label = document.createElement('div');
    this.label.className = 'label';
    this.viewport.appendChild(this.label);
    this.viewport.addEventListener('click', () => this.el.classList.toggle('big'));
    this.el.appendChild(this.viewport);
    const panel = document.createElement('div');
    panel.className = 'panel';
    const more = document.createElement('details');
    more.innerHTML = '<summary>more cues</summary>';
    for (const c of kinds) {
      const row = document.createElement('div');
      row.className = 'cue';
      const value = PARAM_DEFAULTS[c.kind] ?? c.default;
      const unit = c.param.split('_').slice(1).join(' ') || c.param;
      row.innerHTML = `<span class="inforce" title="in force at the station"></span>` +
          `<label><input type="checkbox" data-cue="${c.kind}"> ${c.kind.replace(/_/g, ' ')}</label>` +
          `<input type="number" data-strength="${c.kind}" value="${value}" min="${c.min}" max="${c.max}" step="any" title="${c.param}">` +
          `<span>${unit}</span>`;
      this.inForce.set(c.bit, row.querySelector('.inforce') as HTMLElement);
      (SHOWN.includes(c.kind) ? panel : more).appendChild(row);
    }
    panel.appendChild(more);
    this.acks = document.createElement('div');
    this.acks.className = 'acks';
    panel.appendChild(this.acks);
    this.el.appendChild(panel);
    // A toggle sends the kind with its strength, or switches that kind off; a new strength of
    // a kind that is on is sent at once.
    panel.addEventListener('change', (e) => {
      const t = e.target as HTMLInputElement;
      if (t.dataset.cue) {
        this.touched.add(t.dataset.cue);
        const strength = panel.querySelector(`input[data-strength="${t.dataset.cue}"]`) as HTMLInputElement;
        send(`cue ${this.station.id} ${t.dataset.cue} ${t.checked ? Number(strength.value) : 'off'}`);
      } else if (t.dataset.strength) {
        const box = panel.querySelector(`input[data-cue="${t.dataset.strength}"]`) as HTMLInputElement;
        if (box.checked) send(`cue ${this.station.id} ${t.dataset.strength} ${Number(t.value)}`);
      }
    });
    fetch(`/scene/${encodeURIComponent(station.id)}.json`).then((r) => r.json()).then((j) => {
      this.setScene(j.error ? null : j as SceneJson);
    }).catch(() => this.setScene(null));
  }

  private setScene(scene: SceneJson | null): void {
    const s: SceneJson = scene ?? {
      name: '(scene not on this machine)', task: '', modules: [], tolerance: 0, path: [],
      microscope: { magnification: 10, look_at: [0, 0, 0], view_dir: [0, 0, -1] },
      tool_start: { p: [0, 0, 0], q: [1, 0, 0, 0] },
    };
    this.view = new SceneView(s, LOW_DETAIL);
    this.world.add(this.view.root);
    this.world.background = new THREE.Color(0x101418);
    this.camera = microscopeCamera(s, 16 / 9);
  }

  update(station: StationJson): void {
    this.station = station;
    const lost = station.presence !== 'alive';
    const f = this.view?.lastFrame;
    const health = station.period_p99_ms !== undefined
        ? `loop p99 ${station.period_p99_ms.toFixed(2)} ms · ${station.overruns} overruns` : '';
    const score = station.score !== undefined
        ? `score ${station.score.toFixed(1)} · ${((station.progress ?? 0) * 100).toFixed(0)} % · ${OUTCOMES[station.outcome ?? 0]}` : 'score –';
    const age = f ? `${f.scalars[S.toolAgeMs].toFixed(0)} ms` : '–';
    this.label.innerHTML =
        `<div class="name">${esc(station.trainee)} <span style="opacity:.7">${esc(station.id)}</span></div>` +
        `<div>${esc(station.scene.split('/').pop() ?? '')} · ${score}</div>` +
        `<div class="${lost ? 'lost' : 'ok'}">${lost ? `${station.presence.toUpperCase()} (${station.lost_by})` : 'alive'}</div>` +
        `<div>${health} · state age ${age}</div>`;
    this.acks.innerHTML = station.cues.slice().reverse().map((c) => {
      const ack = c.ack === null ? 'waiting for the station…'
          : c.ack.applied ? `applied at step ${c.ack.step}` : `rejected: ${esc(c.ack.text)}`;
      return `<div class="ack" data-cue-id="${c.cue_id}">#${c.cue_id} ${c.kind} ${c.off ? 'off' : c.param} → ${ack}</div>`;
    }).join('');
  }

  applyPending(): void {
    if (!this.pending || !this.view) return;
    this.view.apply(this.pending);
    const mask = this.pending.scalars[S.activeCues];
    for (const [bit, el] of this.inForce) {
      const on = (mask & (1 << bit)) !== 0;
      el.classList.toggle('on', on);
      // Until the instructor touches a kind, its switch shows the station's own state (a
      // scene may start with cues on).
      const box = el.parentElement!.querySelector('input[data-cue]') as HTMLInputElement;
      if (!this.touched.has(box.dataset.cue!)) box.checked = on;
    }
    this.pending = null;
  }
}

function esc(s: string): string {
  return s.replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]!));
}

function main(): void {
  const canvas = document.getElementById('canvas') as HTMLCanvasElement;
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false });
  renderer.setPixelRatio(1);
  renderer.setSize(window.innerWidth, window.innerHeight, false);
  renderer.setScissorTest(true);
  const grid = document.getElementById('grid')!;
  const tbody = document.querySelector('#scores tbody')!;
  const tiles = new Map<string, Tile>();
  let slots: string[] = [];
  const probe = {
    stations: [] as StationJson[], framesReceived: 0, badFrames: 0, fps: 0, tilesDrawn: 0,
    framesBySlot: [] as number[], errors: [] as string[], latencyMs: [] as number[],
    receivedMs: [] as number[],
  };
  (window as any).microdexConsole = probe;

  const link = new FrameLink(socketUrl(), 'frame_worker.js', {
    onText(m) {
      if (m.type === 'stations') {
        const list = m.stations as StationJson[];
        probe.stations = list;
        slots = list.map((s) => s.id);
        for (const s of list.slice(0, MAX_TILES)) {
          let tile = tiles.get(s.id);
          if (!tile) {
            tile = new Tile(s, (m.cue_kinds ?? []) as CueKindJson[], (text) => link.send(text));
            tiles.set(s.id, tile);
            grid.appendChild(tile.el);
          }
          tile.update(s);
        }
        for (const [id, tile] of tiles) {
          if (!slots.includes(id)) { tile.el.remove(); tiles.delete(id); }
        }
        document.getElementById('count')!.textContent = `${list.length} station(s)`;
        tbody.innerHTML = list.map((s) => `<tr data-station="${esc(s.id)}"><td>${esc(s.id)}</td><td>${esc(s.trainee)}</td>` +
            `<td>${esc(s.scene.split('/').pop() ?? '')}</td><td>${esc(s.task ?? '')}</td>` +
            `<td class="num">${s.score?.toFixed(1) ?? '–'}</td><td class="num">${s.progress !== undefined ? (s.progress * 100).toFixed(0) + ' %' : '–'}</td>` +
            `<td>${OUTCOMES[s.outcome ?? 0]}</td><td class="${s.presence === 'alive' ? 'ok' : 'lost'}">${s.presence}</td>` +
            `<td class="num">${s.period_p99_ms?.toFixed(3) ?? '–'}</td><td class="num">${s.overruns ?? '–'}</td></tr>`).join('');
      } else if (m.type === 'error') {
        probe.errors.push(m.error);
        console.warn(`console: ${m.error}`);
      }
    },
    onStatus(open) { document.getElementById('link')!.textContent = open ? 'live' : 'disconnected'; },
  });
  (probe as any).sharedFrames = link.shared;
  // The newest frame of each slot, to its tile.
  const takeFrames = () => {
    for (let slot = 0; slot < Math.min(slots.length, MAX_SLOTS); ++slot) {
      const t = link.take(slot);
      if (!t) continue;
      let f: Frame;
      try {
        f = decodeFrame(t.buffer);
      } catch (e) {
        ++probe.badFrames;
        continue;
      }
      ++probe.framesReceived;
      if (probe.receivedMs.length < 100000) probe.receivedMs.push(t.receivedMs - f.scalars[S.stampMs]);
      probe.framesBySlot[f.slot] = (probe.framesBySlot[f.slot] ?? 0) + 1;
      const tile = tiles.get(slots[f.slot]);
      if (tile) {
        tile.pending = f;
        ++tile.frames;
      }
    }
  };

  window.addEventListener('resize', () => renderer.setSize(window.innerWidth, window.innerHeight, false));
  let fpsCount = 0;
  let fpsStart = performance.now();
  const clear = new THREE.Color(0x15191d);
  renderer.setAnimationLoop(() => {
    const h = window.innerHeight;
    renderer.setScissor(0, 0, window.innerWidth, h);
    renderer.setViewport(0, 0, window.innerWidth, h);
    renderer.setClearColor(clear);
    renderer.clear();
    let drawn = 0;
    takeFrames();
    for (const tile of tiles.values()) {
      const f = tile.pending;
      tile.applyPending();
      if (f && probe.latencyMs.length < 100000) {
        probe.latencyMs.push(performance.timeOrigin + performance.now() - f.scalars[S.stampMs]);
      }
      if (!tile.view || !tile.camera) continue;
      const r = tile.viewport.getBoundingClientRect();
      if (r.bottom < 0 || r.top > h || r.width < 2 || r.height < 2) continue;
      const aspect = r.width / r.height;
      if (Math.abs(tile.camera.aspect - aspect) > 1e-3) {
        tile.camera.aspect = aspect;
        tile.camera.updateProjectionMatrix();
      }
      renderer.setViewport(r.left, h - r.bottom, r.width, r.height);
      renderer.setScissor(r.left, h - r.bottom, r.width, r.height);
      renderer.render(tile.world, tile.camera);
      ++drawn;
    }
    probe.tilesDrawn = drawn;
    link.drew();
    ++fpsCount;
    const t = performance.now();
    if (t - fpsStart >= 1000) {
      probe.fps = (fpsCount * 1000) / (t - fpsStart);
      fpsCount = 0;
      fpsStart = t;
    }
  });
  void activeCueNames;
}

main();
