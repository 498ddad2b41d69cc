// The instructor's live console: one tile per mirrored station (up to 8 drawn; click to
// enlarge), drawn with the shared scene objects (common/view/src) at the tiles' level of
// detail, each into a canvas of its own; a cue panel per station with the station's
// acknowledgements, and one for all stations; a score table and a plot of the live scores.
//
// A canvas per tile, not one canvas under the whole page: with software compositing (no GPU)
// the browser reads every WebGL canvas it presents back from the renderer, and recomposites
// what changed, so a page-wide canvas cost a full-page read-back and composite per animation
// frame however few tiles were drawn; a tile's canvas costs only when that tile is drawn.
//
// Update budget: a canvas shows its last picture until it is drawn again, so a tile is drawn
// only when it has a new state (or its size changed); the enlarged tile whenever it has one,
// the others oldest first, at most `budget` of them per animation frame.
// The budget adapts to the frame time (more tiles while frames take under 1/25 s, fewer
// above 1/18 s; `?budget=N` fixes it). A frame is applied to its tile only when the tile is
// drawn (newer frames replace a waiting one), and its latency is taken then.

import * as THREE from 'three';
import { Frame, S, activeCueNames, decodeFrame } from '../../common/view/src/frame';
import { LOW_DETAIL, SceneJson, SceneView } from '../../common/view/src/scene_objects';
import { fitCamera, microscopeCamera } from '../../common/view/src/microscope';
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
  cues: CueJson[]; scene_error?: string;
  cues_invalid?: number; device_samples_invalid?: number; // the station's own counts
}
// The samples the instructor refused (invalid, a station beyond the registry, a station_id
// not its writer's partition's), by topic.
interface RejectedJson { total: number; by_topic: Record<string, number>; latest: string }

class Tile {
  readonly el: HTMLDivElement;
  readonly viewport: HTMLDivElement;
  readonly canvas: HTMLCanvasElement;
  renderer: THREE.WebGLRenderer | null = null; // made with the scene
  size = ''; // the canvas's size in pixels, as last set
  readonly label: HTMLDivElement; // the caption bar above the picture
  readonly note: HTMLDivElement; // why there is no scene, over the empty picture
  drawn = false; // its canvas shows its picture at the canvas's current size
  drawnAt = 0; // performance.now() of its last drawing
  framedVersion = -1; // the thread extent the camera was last fitted to
  private acksHtml = '';
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
    this.label = document.createElement('div');
    this.label.className = 'label';
    this.el.appendChild(this.label);
    this.viewport = document.createElement('div');
    this.viewport.className = 'viewport';
    this.canvas = document.createElement('canvas');
    this.viewport.appendChild(this.canvas);
    this.note = document.createElement('div');
    this.note.className = 'note';
    this.viewport.appendChild(this.note);
    this.viewport.addEventListener('click', () => this.el.classList.toggle('big'));
    this.el.appendChild(this.viewport);
    const panel = document.createElement('div');
    panel.className = 'panel';
    const more = document.createElement('details');
    more.innerHTML = '<summary>more cues</summary>';
    for (const c of kinds) {
      const row = cueRow(c);
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
    this.fetchScene(0);
  }

  // The scene as the station sent it (SceneDescription); while it has not arrived the server
  // says so with retry: true, and the tile asks again.
  private fetchScene(attempt: number): void {
    fetch(`/scene/${encodeURIComponent(this.station.id)}.json`).then((r) => r.json()).then((j) => {
      if (!j.error) {
        this.setScene(j as SceneJson, '');
      } else if (j.retry) {
        // Asked again, less often as it takes longer (a station may start long after).
        this.note.textContent = j.error;
        setTimeout(() => this.fetchScene(attempt + 1), Math.min(500 + 250 * attempt, 5000));
      } else {
        this.setScene(null, j.error);
      }
    }).catch((e) => this.setScene(null, String(e)));
  }

  private setScene(scene: SceneJson | null, why: string): void {
    const s: SceneJson = scene ?? {
      name: '(no scene)', task: '', modules: [], tolerance: 0, path: [],
      microscope: { magnification: 10, look_at: [0, 0, 0], view_dir: [0, 0, -1] },
      tool_start: { p: [0, 0, 0], q: [1, 0, 0, 0] },
    };
    this.note.textContent = scene ? '' : `no scene: ${why}`;
    this.view = new SceneView(s, LOW_DETAIL);
    this.world.add(this.view.root);
    this.world.background = new THREE.Color(0x101418);
    this.camera = microscopeCamera(s, 16 / 9);
    if (!this.renderer) {
      this.renderer = new THREE.WebGLRenderer({ canvas: this.canvas, antialias: false });
      this.renderer.setPixelRatio(1);
    }
    this.drawn = false;
  }

  // A thread tile frames the thread (its extent so far, and the anchor) rather than the
  // microscope's whole field: a suture is a few pixels of a small tile otherwise.
  frameThread(): void {
    const v = this.view;
    if (!v || !this.camera || !v.scene.thread || v.threadBox.isEmpty()) return;
    if (v.threadBoxVersion === this.framedVersion) return;
    this.framedVersion = v.threadBoxVersion;
    const box = v.threadBox.clone().expandByPoint(new THREE.Vector3(...v.scene.thread.anchor));
    v.setThreadField(fitCamera(this.camera, v.scene, box));
  }

  update(station: StationJson): void {
    this.station = station;
    const lost = station.presence !== 'alive';
    const f = this.view?.lastFrame;
    const invalid = (station.cues_invalid ?? 0) + (station.device_samples_invalid ?? 0);
    const health = station.period_p99_ms !== undefined
        ? `loop p99 ${station.period_p99_ms.toFixed(2)} ms · ${station.overruns} overruns` +
          (invalid > 0 ? ` · <span class="lost">invalid rx ${station.cues_invalid} cues, ${station.device_samples_invalid} device</span>` : '')
        : '';
    const score = station.score !== undefined
        ? `score ${station.score.toFixed(1)} · ${((station.progress ?? 0) * 100).toFixed(0)} % · ${OUTCOMES[station.outcome ?? 0]}` : 'score –';
    const age = f ? `${f.scalars[S.toolAgeMs].toFixed(0)} ms` : '–';
    const html =
        `<div><span class="name">${esc(station.trainee)}</span> <span style="opacity:.7">${esc(station.id)}</span>` +
        ` · <span class="${lost ? 'lost' : 'ok'}">${lost ? `${station.presence.toUpperCase()} (${station.lost_by})` : 'alive'}</span></div>` +
        `<div><span class="scene">${esc(sceneName(station.scene))}</span> · ${score}</div>` +
        `<div>${health} · state age ${age}</div>` +
        (station.scene_error ? `<div class="lost">scene refused: ${esc(station.scene_error)}</div>` : '');
    if (html !== this.label.innerHTML) this.label.innerHTML = html;
    // Rewritten only when changed: a new layout costs a software renderer a repaint.
    const acks = station.cues.slice().reverse().map((c) => {
      const ack = c.ack === null ? 'waiting for the station…'
          : c.ack.applied ? `applied at step ${c.ack.step}` : `rejected: ${esc(c.ack.text)}`;
      return `<div class="ack" data-cue-id="${c.cue_id}">#${c.cue_id} ${c.kind} ${c.off ? 'off' : c.param} → ${ack}</div>`;
    }).join('');
    if (acks !== this.acksHtml) {
      this.acksHtml = acks;
      this.acks.innerHTML = acks;
    }
  }

  // Off the page, its WebGL context given back (a page has a limited number of them).
  dispose(): void {
    this.el.remove();
    this.renderer?.dispose();
    this.renderer?.forceContextLoss();
    this.renderer = null;
  }

  applyPending(): void {
    if (!this.pending || !this.view) return;
    this.view.apply(this.pending);
    this.frameThread();
    const mask = this.pending.scalars[S.activeCues];
    for (const [bit, el] of this.inForce) {
      const on = (mask & (1 << bit)) !== 0;
      if (el.classList.contains('on') === on) continue; // a DOM change costs a style pass
      el.classList.toggle('on', on);
      // Until the instructor touches a kind, its switch shows the station's own state (a
      // scene may start with cues on).
      const box = el.parentElement!.querySelector('input[data-cue]') as HTMLInputElement;
      if (!this.touched.has(box.dataset.cue!)) box.checked = on;
    }
    this.pending = null;
  }
}

// One cue kind's switch and strength (its in-force dot lit by the tile from the station's state).
function cueRow(c: CueKindJson): HTMLDivElement {
  const row = document.createElement('div');
  row.className = 'cue';
  const value = PARAM_DEFAULTS[c.kind] ?? c.default;
  const unit = c.param.split('_').slice(1).join(' ') || c.param;
  row.innerHTML = `<span class="inforce" title="in force at the station"></span>` +
      `<label><input type="checkbox" data-cue="${c.kind}"> ${c.kind.replace(/_/g, ' ')}</label>` +
      `<input type="number" data-strength="${c.kind}" value="${value}" min="${c.min}" max="${c.max}" step="any" title="${c.param}">` +
      `<span>${unit}</span>`;
  return row;
}

// The panel for every station: each kind's switch sends one command addressed to all ("cue all
// KIND PARAM|off"); every station acknowledges it in its own tile. Built once the cue kinds
// are known.
function buildAllPanel(section: HTMLElement, kinds: CueKindJson[], send: (m: string) => boolean): void {
  const rows = section.querySelector('.rows') as HTMLElement;
  const more = document.createElement('details');
  more.innerHTML = '<summary>more cues</summary>';
  const moreRows = document.createElement('div');
  moreRows.className = 'rows';
  more.appendChild(moreRows);
  for (const c of kinds) {
    const row = cueRow(c);
    row.querySelector('.inforce')!.remove();
    (SHOWN.includes(c.kind) ? rows : moreRows).appendChild(row);
  }
  section.appendChild(more);
  section.addEventListener('change', (e) => {
    const t = e.target as HTMLInputElement;
    if (t.dataset.cue) {
      const strength = section.querySelector(`input[data-strength="${t.dataset.cue}"]`) as HTMLInputElement;
      send(`cue all ${t.dataset.cue} ${t.checked ? Number(strength.value) : 'off'}`);
    } else if (t.dataset.strength) {
      const box = section.querySelector(`input[data-cue="${t.dataset.strength}"]`) as HTMLInputElement;
      if (box.checked) send(`cue all ${t.dataset.strength} ${Number(t.value)}`);
    }
  });
}

// Each trainee's live score over the session (seconds since this page first heard of the
// station): a line per station, 0-100, redrawn at most once a second. At most kPlotPoints
// points per station; beyond, every other one is dropped (the oldest thinned first).
const kPlotPoints = 2000;
const PALETTE = ['#4fc3f7', '#ffb74d', '#81c784', '#e57373', '#ba68c8', '#fff176', '#4db6ac', '#f06292'];
class ScorePlot {
  readonly series = new Map<string, { trainee: string; t0: number; points: [number, number][] }>();
  private drawnAt = 0;
  constructor(private readonly el: HTMLElement) {}

  add(list: StationJson[], nowMs: number): void {
    for (const s of list) {
      if (s.score === undefined) continue;
      let line = this.series.get(s.id);
      if (!line) {
        line = { trainee: s.trainee, t0: nowMs, points: [] };
        this.series.set(s.id, line);
      }
      line.trainee = s.trainee;
      line.points.push([(nowMs - line.t0) / 1000, s.score]);
      if (line.points.length > kPlotPoints) line.points = line.points.filter((_, i) => i % 2 === 0);
    }
    if (nowMs - this.drawnAt >= 1000) {
      this.drawnAt = nowMs;
      this.draw();
    }
  }

  draw(): void {
    const W = 640, H = 170, L = 34, R = 10, T = 8, B = 22;
    let tMax = 10;
    for (const l of this.series.values()) tMax = Math.max(tMax, l.points.at(-1)?.[0] ?? 0);
    const x = (t: number) => L + (W - L - R) * t / tMax;
    const y = (v: number) => T + (H - T - B) * (1 - Math.min(Math.max(v, 0), 100) / 100);
    let svg = `<svg width="${W}" height="${H}" viewBox="0 0 ${W} ${H}" font-size="10" fill="#9aa">`;
    for (const v of [0, 50, 100]) {
      svg += `<line x1="${L}" x2="${W - R}" y1="${y(v)}" y2="${y(v)}" stroke="#333"/>` +
          `<text x="${L - 4}" y="${y(v) + 3}" text-anchor="end">${v}</text>`;
    }
    svg += `<text x="${W - R}" y="${H - 6}" text-anchor="end">${tMax.toFixed(0)} s</text>` +
        `<text x="${L}" y="${H - 6}">0 s</text>`;
    let legend = '';
    let k = 0;
    for (const [id, l] of this.series) {
      const colour = PALETTE[k++ % PALETTE.length];
      const pts = l.points.map(([t, v]) => `${x(t).toFixed(1)},${y(v).toFixed(1)}`).join(' ');
      svg += `<polyline data-station="${esc(id)}" points="${pts}" fill="none" stroke="${colour}" stroke-width="1.5"/>`;
      legend += `<span style="color:${colour}">— ${esc(l.trainee)} (${esc(id)}) ${l.points.at(-1)?.[1].toFixed(1) ?? ''}</span>`;
    }
    this.el.innerHTML = `<div>score over the session</div>${svg}</svg><div class="legend">${legend}</div>`;
  }
}

// The recording and replay controls (microdex-instructor --record-dir DIR; the server's
// console_session.h): start and stop a recording into DIR, DIR's recordings with a play button
// each, and the replay playing (progress, pause, speed, stop). The server refuses what cannot
// be done (a replay while recording, a replay of a station that is live here, ...) and the
// reason shows under the controls.
interface RecordingJson { file: string; bytes: number; seconds: number; stations: string[]; recording: boolean; error: string }
interface SessionJson {
  record_dir: string; ready: boolean; can_replay: boolean;
  recording: null | { file: string; seconds: number; written: number; dropped: number; error: string };
  last_recording: null | { file: string; written: number; dropped: number };
  replay: null | { file: string; files: string[]; stations: string[]; length_s: number; position_s: number; speed: number;
    paused: boolean; seeks: number; done: boolean; published?: number; stopped?: boolean; error?: string; scenes_missing?: string[] };
  recordings: RecordingJson[];
}
const SPEEDS = [0.25, 0.5, 1, 2, 4, 8];
class SessionPanel {
  private built = false;
  private busy = false; // a replay is playing
  private seeking = false; // the position slider is held: the updates leave it alone
  private listHtml = '';
  private statusHtml = '';
  private replayHtml = '';
  messages: string[] = []; // the server's replies and refusals, latest last
  constructor(private readonly el: HTMLElement, private readonly send: (m: string) => boolean) {}

  update(session: SessionJson | null): void {
    const body = this.el.querySelector('.body') as HTMLElement;
    if (!session) {
      const text = 'not available: start the console with --record-dir DIR to record and replay from here';
      if (body.textContent !== text) body.textContent = text;
      return;
    }
    if (!this.built) this.build(body);
    const rec = session.recording;
    const busy = session.replay !== null && !session.replay.done;
    (body.querySelector('#rec-start') as HTMLButtonElement).disabled = rec !== null || busy;
    (body.querySelector('#rec-stop') as HTMLButtonElement).disabled = rec === null;
    const status = rec
        ? `<span class="rec-on">● recording ${esc(rec.file)}</span> · ${rec.seconds.toFixed(1)} s · ${rec.written} samples written` +
          (rec.dropped ? ` · <span class="lost">${rec.dropped} dropped</span>` : '') + (rec.error ? ` · <span class="lost">${esc(rec.error)}</span>` : '')
        : session.last_recording
            ? `not recording · last: ${esc(session.last_recording.file)}, ${session.last_recording.written} samples (${session.last_recording.dropped} dropped)`
            : `not recording · into ${esc(session.record_dir)}`;
    if (status !== this.statusHtml) {
      this.statusHtml = status;
      (body.querySelector('#rec-status') as HTMLElement).innerHTML = status;
    }
    const r = session.replay;
    const replay = !r ? 'no replay'
        : r.done
            ? `${esc(r.files.join(' + '))}: ${r.error ? `<span class="lost">failed: ${esc(r.error)}</span>` : r.stopped ? 'stopped' : 'played to the end'}` +
              ` · ${r.published ?? 0} samples` +
              ((r.scenes_missing ?? []).length ? ` · <span class="lost">scene not found: ${esc((r.scenes_missing ?? []).join('; '))}</span>` : '')
            : `▶ ${esc(r.files.join(' + '))} (${esc(r.stations.join(', '))}) · ${r.position_s.toFixed(1)} / ${r.length_s.toFixed(1)} s · ×${r.speed}${r.paused ? ' · paused' : ''}`;
    if (replay !== this.replayHtml) {
      this.replayHtml = replay;
      (body.querySelector('#rp-status') as HTMLElement).innerHTML = replay;
    }
    // The position, and the slider that seeks the replay playing.
    const seek = body.querySelector('#rp-seek') as HTMLInputElement;
    seek.disabled = !busy;
    if (!this.seeking) {
      seek.max = String(r?.length_s || 1);
      seek.value = String(r ? (r.done && !r.stopped && !r.error ? r.length_s : r.position_s) : 0);
    }
    this.busy = busy;
    for (const id of ['#rp-pause', '#rp-stop']) {
      (body.querySelector(id) as HTMLInputElement).disabled = !busy;
    }
    (body.querySelector('#rp-pause') as HTMLButtonElement).textContent = r?.paused ? 'resume' : 'pause';
    const rows = session.recordings.map((f) => `<tr data-file="${esc(f.file)}"><td>${esc(f.file)}</td>` +
        `<td>${f.recording ? '<span class="rec-on">recording…</span>' : f.error ? `<span class="lost">${esc(f.error)}</span>` : esc(f.stations.join(', '))}</td>` +
        `<td class="num">${f.recording ? '' : f.seconds.toFixed(1) + ' s'}</td><td class="num">${(f.bytes / 1e6).toFixed(2)} MB</td>` +
        // While a replay plays, another file joins it ("+ alongside": from its position, on its
        // transport) instead of starting one of its own.
        `<td>${f.recording || f.error || !session.can_replay ? ''
            : busy ? (r!.files.includes(f.file) ? '<span class="rec-on">playing</span>' : `<button data-add="${esc(f.file)}">+ alongside</button>`)
            : `<button data-play="${esc(f.file)}"${rec ? ' disabled' : ''}>▶ play</button>`}` +
        `${f.recording ? '' : ` <button data-rename="${esc(f.file)}"${busy && r!.files.includes(f.file) ? ' disabled' : ''}>✎ rename</button>` +
            `<button data-delete="${esc(f.file)}"${busy && r!.files.includes(f.file) ? ' disabled' : ''}>✕ delete</button>`}</td></tr>`).join('');
    if (rows !== this.listHtml) {
      this.listHtml = rows;
      (body.querySelector('#recordings tbody') as HTMLElement).innerHTML =
          rows || '<tr><td colspan="5">no recordings yet</td></tr>';
    }
  }

  // A reply or refusal of the server to a session command.
  note(text: string, bad: boolean): void {
    this.messages.push(text);
    const msg = this.el.querySelector('.msg') as HTMLElement | null;
    if (!msg) return;
    msg.textContent = text;
    msg.className = bad ? 'msg lost' : 'msg';
  }

  private build(body: HTMLElement): void {
    this.built = true;
    body.innerHTML =
        `<div class="row">record <input id="rec-name" size="24" placeholder="name (default: session-DATE-TIME)">` +
        `<button id="rec-start">● record</button><button id="rec-stop">■ stop</button><span id="rec-status"></span></div>` +
        `<div class="row">replay from <input id="rp-from" type="number" min="0" step="any" value="0" style="width:56px"> s ` +
        `<button id="rp-pause">pause</button><select id="rp-speed">` +
        SPEEDS.map((v) => `<option value="${v}"${v === 1 ? ' selected' : ''}>×${v}</option>`).join('') +
        `</select><button id="rp-stop">■ stop</button><input id="rp-seek" type="range" min="0" max="1" step="0.1" value="0" title="position: drag to seek"><span id="rp-status"></span></div>` +
        `<div class="msg"></div>` +
        `<table id="recordings"><thead><tr><th>recording</th><th>stations</th><th>length</th><th>size</th><th></th></tr></thead><tbody></tbody></table>`;
    const name = body.querySelector('#rec-name') as HTMLInputElement;
    const speed = body.querySelector('#rp-speed') as HTMLSelectElement;
    body.querySelector('#rec-start')!.addEventListener('click', () => {
      this.send(`record start ${name.value.trim()}`.trim());
    });
    body.querySelector('#rec-stop')!.addEventListener('click', () => this.send('record stop'));
    body.querySelector('#rp-pause')!.addEventListener('click', () => this.send('replay pause'));
    body.querySelector('#rp-stop')!.addEventListener('click', () => this.send('replay stop'));
    // The speed of the replay playing, or of the next one.
    speed.addEventListener('change', () => {
      if (this.busy) this.send(`replay speed ${speed.value}`);
    });
    // Seek: while the slider is held its value is the user's; on release the replay goes on
    // from there.
    const seek = body.querySelector('#rp-seek') as HTMLInputElement;
    seek.addEventListener('input', () => { this.seeking = true; });
    seek.addEventListener('change', () => {
      this.seeking = false;
      if (this.busy) this.send(`replay seek ${Number(seek.value)}`);
    });
    body.addEventListener('click', (e) => {
      const data = (e.target as HTMLElement).dataset ?? {};
      const from = Math.max(0, Number((body.querySelector('#rp-from') as HTMLInputElement).value) || 0);
      if (data.play) this.send(`replay play ${data.play} ${speed.value} ${from}`);
      if (data.add) this.send(`replay add ${data.add}`);
      if (data.rename) {
        const to = window.prompt(`Rename the recording ${data.rename} to:`, data.rename.replace(/\.db$/, ''));
        if (to && to.trim()) this.send(`record rename ${data.rename} ${to.trim()}`);
      }
      if (data.delete && window.confirm(`Delete the recording ${data.delete}? This cannot be undone.`)) {
        this.send(`record delete ${data.delete}`);
      }
    });
  }
}

// The final score of each trainee's past sessions (the scores database of microdex-instructor
// --db, course by course): a line per trainee and scene, session by session in start order
// (the latest ConsoleServer::kPastPerLine), with a dot per session. Shown once the console has
// any.
interface PastLineJson { trainee: string; scene: string; sessions: { id: string; started_ms: number; score: number }[] }
class PastPlot {
  lines: PastLineJson[] = [];
  private json = '';
  constructor(private readonly el: HTMLElement) {}

  set(course: string, lines: PastLineJson[]): void {
    const json = JSON.stringify(lines);
    if (json === this.json) return;
    this.json = json;
    this.lines = lines;
    const W = 640, H = 170, L = 34, R = 10, T = 8, B = 22;
    let n = 2;
    for (const l of lines) n = Math.max(n, l.sessions.length);
    const x = (i: number) => L + (W - L - R) * i / (n - 1);
    const y = (v: number) => T + (H - T - B) * (1 - Math.min(Math.max(v, 0), 100) / 100);
    let svg = `<svg width="${W}" height="${H}" viewBox="0 0 ${W} ${H}" font-size="10" fill="#9aa">`;
    for (const v of [0, 50, 100]) {
      svg += `<line x1="${L}" x2="${W - R}" y1="${y(v)}" y2="${y(v)}" stroke="#333"/>` +
          `<text x="${L - 4}" y="${y(v) + 3}" text-anchor="end">${v}</text>`;
    }
    svg += `<text x="${L}" y="${H - 6}">session 1</text><text x="${W - R}" y="${H - 6}" text-anchor="end">${n}</text>`;
    let legend = '';
    lines.forEach((l, k) => {
      const colour = PALETTE[k % PALETTE.length];
      const pts = l.sessions.map((s, i) => [x(i), y(s.score)]);
      svg += `<polyline data-trainee="${esc(l.trainee)}" data-scene="${esc(l.scene)}" points="${pts.map(([a, b]) => `${a.toFixed(1)},${b.toFixed(1)}`).join(' ')}" fill="none" stroke="${colour}" stroke-width="1.5"/>`;
      for (const [a, b] of pts) svg += `<circle cx="${a.toFixed(1)}" cy="${b.toFixed(1)}" r="2.5" fill="${colour}"/>`;
      const last = l.sessions.at(-1)?.score;
      legend += `<span style="color:${colour}">— ${esc(l.trainee)} · ${esc(sceneName(l.scene))}: ${l.sessions.length} session(s), last ${last?.toFixed(1) ?? '–'}</span>`;
    });
    this.el.innerHTML = lines.length === 0 ? ''
        : `<div>final scores over past sessions (scores database, course ${esc(course)})</div>${svg}</svg><div class="legend">${legend}</div>`;
  }
}

// A scene's name for a caption: its file name without the folder and the .yaml extension.
function sceneName(path: string): string {
  return (path.split('/').pop() ?? '').replace(/\.ya?ml$/, '');
}

function esc(s: string): string {
  return s.replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]!));
}

function main(): void {
  const grid = document.getElementById('grid')!;
  const tbody = document.querySelector('#scores tbody')!;
  const tiles = new Map<string, Tile>();
  let slots: string[] = [];
  let tableHtml = '';
  const probe = {
    stations: [] as StationJson[], framesReceived: 0, badFrames: 0, fps: 0, tilesDrawn: 0,
    framesBySlot: [] as number[], errors: [] as string[], latencyMs: [] as number[],
    receivedMs: [] as number[],
    encodedMs: [] as number[], // tick stamp → the frame encoded by the instructor
    waitedMs: [] as number[], // of which the state waited at the instructor
    budget: 0, tileDrawsPerSecond: 0, tileDrawsTotal: 0,
    sceneNames: {} as Record<string, string>, // station → the name of the scene its tile draws
    rejected: { total: 0, by_topic: {}, latest: '' } as RejectedJson,
  };
  let rejectedHtml = '';
  (window as any).microdexConsole = probe;
  const allPanel = document.getElementById('all')!;
  let allBuilt = false;
  const plot = new ScorePlot(document.getElementById('plot')!);
  const past = new PastPlot(document.getElementById('past')!);
  (probe as any).past = past;
  const session = new SessionPanel(document.getElementById('session')!, (text) => link.send(text));
  (probe as any).session = null;
  (probe as any).sessionMessages = session.messages;

  const link = new FrameLink(socketUrl(), 'frame_worker.js', {
    onText(m) {
      if (m.type === 'stations') {
        const list = m.stations as StationJson[];
        probe.stations = list;
        slots = list.map((s) => s.id);
        if (!allBuilt && (m.cue_kinds ?? []).length > 0) {
          allBuilt = true;
          buildAllPanel(allPanel, m.cue_kinds as CueKindJson[], (text) => link.send(text));
        }
        plot.add(list, performance.now());
        (probe as any).session = m.session ?? null;
        session.update((m.session ?? null) as SessionJson | null);
        for (const s of list.slice(0, MAX_TILES)) {
          let tile = tiles.get(s.id);
          if (!tile) {
            tile = new Tile(s, (m.cue_kinds ?? []) as CueKindJson[], (text) => link.send(text));
            tiles.set(s.id, tile);
            grid.appendChild(tile.el);
          }
          tile.update(s);
          probe.sceneNames[s.id] = tile.view?.scene.name ?? '';
        }
        for (const [id, tile] of tiles) {
          if (!slots.includes(id)) { tile.dispose(); tiles.delete(id); }
        }
        document.getElementById('count')!.textContent = `${list.length} station(s)`;
        const rej = m.rejected as RejectedJson | undefined;
        if (rej) {
          probe.rejected = rej;
          const topics = Object.entries(rej.by_topic).map(([t, n]) => `${esc(t)} ${n}`).join(', ');
          const html = rej.total > 0
              ? `<span class="lost">rejected ${rej.total} received samples</span> (${topics}; latest: ${esc(rej.latest)})` : '';
          if (html !== rejectedHtml) {
            rejectedHtml = html;
            document.getElementById('rejected')!.innerHTML = html;
          }
        }
        const rows = list.map((s) => `<tr data-station="${esc(s.id)}"><td>${esc(s.id)}</td><td>${esc(s.trainee)}</td>` +
            `<td>${esc(s.scene.split('/').pop() ?? '')}</td><td>${esc(s.task ?? '')}</td>` +
            `<td class="num">${s.score?.toFixed(1) ?? '–'}</td><td class="num">${s.progress !== undefined ? (s.progress * 100).toFixed(0) + ' %' : '–'}</td>` +
            `<td>${OUTCOMES[s.outcome ?? 0]}</td><td class="${s.presence === 'alive' ? 'ok' : 'lost'}">${s.presence}</td>` +
            `<td class="num">${s.period_p99_ms?.toFixed(3) ?? '–'}</td><td class="num">${s.overruns ?? '–'}</td></tr>`).join('');
        if (rows !== tableHtml) {
          tableHtml = rows;
          tbody.innerHTML = rows;
        }
      } else if (m.type === 'error') {
        probe.errors.push(m.error);
        console.warn(`console: ${m.error}`);
        if (/^(record|replay|session)/.test(m.error)) session.note(m.error, true);
      } else if (m.type === 'past_scores') {
        past.set(String(m.course), m.lines as PastLineJson[]);
      } else if (m.type === 'recording_started') {
        session.note(`recording to ${m.file}`, false);
      } else if (m.type === 'recording_stopped') {
        session.note(`recorded ${m.written} samples to ${m.file} (${m.dropped} dropped)`, false);
      } else if (m.type === 'recording_renamed') {
        session.note(`renamed ${m.file} to ${m.name}`, false);
      } else if (m.type === 'recording_deleted') {
        session.note(`deleted ${m.file} (${(Number(m.bytes) / 1e6).toFixed(2)} MB)`, false);
      } else if (m.type === 'replay_added') {
        session.note(`${m.file} plays alongside from ${Number(m.from_s).toFixed(1)} s: ${(m.stations as string[]).join(', ')}`, false);
      } else if (m.type === 'replay_started') {
        session.note(`replaying ${m.file}: ${(m.stations as string[]).join(', ')}, ${Number(m.length_s).toFixed(1)} s`, false);
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
      if (probe.receivedMs.length < 100000) {
        probe.receivedMs.push(t.receivedMs - f.scalars[S.stampMs]);
        probe.encodedMs.push(f.scalars[S.sentMs] - f.scalars[S.stampMs]);
        probe.waitedMs.push(f.scalars[S.toolAgeMs]);
      }
      probe.framesBySlot[f.slot] = (probe.framesBySlot[f.slot] ?? 0) + 1;
      const tile = tiles.get(slots[f.slot]);
      if (tile) {
        tile.pending = f;
        ++tile.frames;
      }
    }
  };

  const params = new URLSearchParams(location.search);
  const fixedBudget = params.has('budget') ? Math.max(1, Number(params.get('budget'))) : 0;
  let budget = fixedBudget || 2;
  let fpsCount = 0;
  let fpsStart = performance.now();
  let lastFrameAt = performance.now();
  let frameMsAvg = 0;
  let tileDraws = 0;
  const drawTile = (tile: Tile) => {
    const f = tile.pending;
    tile.applyPending();
    if (f && probe.latencyMs.length < 100000) {
      probe.latencyMs.push(performance.timeOrigin + performance.now() - f.scalars[S.stampMs]);
    }
    tile.renderer!.render(tile.world, tile.camera!);
    tile.drawn = true;
    tile.drawnAt = performance.now();
    ++tileDraws;
    ++probe.tileDrawsTotal;
  };
  const loop = () => {
    requestAnimationFrame(loop);
    const now = performance.now();
    frameMsAvg = frameMsAvg === 0 ? now - lastFrameAt : 0.9 * frameMsAvg + 0.1 * (now - lastFrameAt);
    lastFrameAt = now;
    if (!fixedBudget) {
      if (frameMsAvg > 1000 / 18 && budget > 1) budget -= 1;
      else if (frameMsAvg < 1000 / 25 && budget < MAX_TILES) budget += 1;
    }
    const h = window.innerHeight;
    takeFrames();
    // Where each tile is; a canvas whose size changed is cleared, and its tile drawn again.
    const visible: Tile[] = [];
    for (const tile of tiles.values()) {
      if (!tile.view || !tile.camera || !tile.renderer) continue;
      const r = tile.viewport.getBoundingClientRect();
      const w = Math.round(r.width);
      const ht = Math.round(r.height);
      if (r.bottom < 0 || r.top > h || w < 2 || ht < 2) continue;
      const size = `${w}x${ht}`;
      if (size !== tile.size) {
        tile.size = size;
        tile.renderer.setSize(w, ht, false);
        tile.camera.aspect = w / ht;
        tile.camera.updateProjectionMatrix();
        tile.framedVersion = -1;
        tile.frameThread();
        tile.drawn = false;
      }
      visible.push(tile);
    }
    // The enlarged tile and any tile not on the canvas yet, then the others with a new state,
    // oldest picture first, within the budget.
    let small = 0;
    const due = visible.filter((t) => !t.drawn || t.pending).sort((a, b) => a.drawnAt - b.drawnAt);
    for (const tile of due) {
      const big = tile.el.classList.contains('big');
      if (tile.drawn && !big) {
        if (small >= budget) continue;
        ++small;
      }
      drawTile(tile);
    }
    probe.tilesDrawn = visible.filter((t) => t.drawn).length;
    probe.budget = budget;
    link.drew();
    ++fpsCount;
    const t = performance.now();
    if (t - fpsStart >= 1000) {
      probe.fps = (fpsCount * 1000) / (t - fpsStart);
      probe.tileDrawsPerSecond = (tileDraws * 1000) / (t - fpsStart);
      fpsCount = 0;
      tileDraws = 0;
      fpsStart = t;
    }
  };
  requestAnimationFrame(loop);
  void activeCueNames;
}

main();
