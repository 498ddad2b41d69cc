// From a scene (the JSON of common/view/scene_view.cc) and the state frames to three.js
// objects, shared by the station's page and the console's tiles. The objects are built once
// per scene; apply() updates their poses and buffers in place (no geometry rebuilt per frame).

import * as THREE from 'three';
import {
  Frame, HAS_NEEDLE, HAS_SCORE, HAS_THREAD, HAS_TISSUE, MAX_OVERLAY_LABELS, MAX_OVERLAY_POINTS,
  MAX_OVERLAY_POLYLINES, MAX_STITCHES, HAS_SECOND_TOOL, Overlay, S,
} from './frame';

export type V3 = [number, number, number];
export type Q4 = [number, number, number, number]; // w, x, y, z
export interface Pose { p: V3; q: Q4 }

export interface SceneJson {
  name: string;
  task: string;
  modules: string[];
  microscope: { magnification: number; look_at: V3; view_dir: V3 };
  tolerance: number;
  path: V3[];
  tool_start: Pose;
  // Bimanual scenes: the second tool (forceps) at the task's start.
  second_tool_start?: Pose;
  vessel?: { core_radius: number; tube_radius: number; segment_angle: number; pose: Pose };
  needle?: { radius: number; sweep: number; X_TN: Pose };
  target?: { p: V3; radius: number };
  thread?: { anchor: V3; radius: number };
  tissue?: { lx: number; ly: number; pose: Pose; bar: number };
  wire?: { radius: number; points: V3[] };
  loop?: { radius: number; wire_radius: number };
  grasp?: {
    shape: string; size: V3; radius: number; length: number; p: V3; yaw: number;
    jaw_width: number; jaw_length: number; jaw_thickness: number; open_gap: number;
  };
  placement?: { vessel_radius: number; end_height: number; stitches: number; bite: number };
  // The knot-topology quiz: each item's thread, x y z per point (m, the tissue at z = 0).
  // radius: the largest item's; radii: each item's tube (the knots are drawn at their own scale).
  knots?: { radius: number; radii?: number[]; items: number[][] };
  // Knot tying: the stitch's rods (the bite and the two punctures) and the tissue surface, the
  // plane y = surface_y (that scene's frame has y up).
  stitch?: { rods: { a: V3; b: V3; radius: number }[]; surface_y: number };
}

// Colours the tests look for (tests/web): the needle is drawn unlit in NEEDLE_COLOR, red in
// contact with the wall.
export const NEEDLE_COLOR = 0x00e5ff;
export const CONTACT_COLOR = 0xff2020;
export const TOOL_COLOR = 0xc8c8d0;
export const TOOL2_COLOR = 0xa8b4c8; // the second tool (forceps), a cooler steel
export const THREAD_COLOR = 0x3050ff;
export const PATH_COLOR = 0xd0d080; // the task's ideal path, faint
export const KNOT_COLOR = 0x2040ff; // the quiz's knot (a blue suture)
export const STITCH_TARGET_COLOR = 0x40ff60; // where the placement task's stitches go

// Level of detail: the station's full view or a console tile.
export interface Detail {
  radial: number; // segments around tubes
  along: number; // segments along curves
  tissueStride: number; // every n-th node of the tissue grid
  thinFraction: number; // thin things (the thread) drawn at least this fraction of the field thick
}
export const HIGH_DETAIL: Detail = { radial: 16, along: 96, tissueStride: 1, thinFraction: 1 / 300 };
export const LOW_DETAIL: Detail = { radial: 6, along: 32, tissueStride: 2, thinFraction: 1 / 90 };

export function quat(q: ArrayLike<number>, at = 0): THREE.Quaternion {
  // Frames and the scene JSON store (w, x, y, z); three.js takes (x, y, z, w).
  return new THREE.Quaternion(q[at + 1], q[at + 2], q[at + 3], q[at]);
}

export function setPose(o: THREE.Object3D, p: ArrayLike<number>, pAt: number,
                        q: ArrayLike<number>, qAt: number): void {
  o.position.set(p[pAt], p[pAt + 1], p[pAt + 2]);
  o.quaternion.set(q[qAt + 1], q[qAt + 2], q[qAt + 3], q[qAt]);
}

// The needle: the arc (ρ cos s, ρ sin s, 0), s in [0, sweep], as a tube in its frame N.
export function needleCurve(radius: number, sweep: number): THREE.Curve<THREE.Vector3> {
  return new (class extends THREE.Curve<THREE.Vector3> {
    getPoint(t: number, target = new THREE.Vector3()): THREE.Vector3 {
      const s = t * sweep;
      return target.set(radius * Math.cos(s), radius * Math.sin(s), 0);
    }
  })();
}

// A polyline (m, world) as a curve for TubeGeometry.
export function polylineCurve(points: V3[]): THREE.CurvePath<THREE.Vector3> {
  const path = new THREE.CurvePath<THREE.Vector3>();
  for (let i = 1; i < points.length; ++i) {
    path.add(new THREE.LineCurve3(new THREE.Vector3(...points[i - 1]),
                                  new THREE.Vector3(...points[i])));
  }
  return path;
}

// Index buffer of an nx × ny grid of vertices (x fastest), two triangles per cell.
export function gridIndices(nx: number, ny: number): Uint32Array {
  const out = new Uint32Array((nx - 1) * (ny - 1) * 6);
  let k = 0;
  for (let j = 0; j + 1 < ny; ++j) {
    for (let i = 0; i + 1 < nx; ++i) {
      const a = j * nx + i;
      out[k++] = a; out[k++] = a + 1; out[k++] = a + nx;
      out[k++] = a + 1; out[k++] = a + nx + 1; out[k++] = a + nx;
    }
  }
  return out;
}

// The tissue grid's vertex heights from the field, sub-sampled by `stride`: writes z of every
// kept node into `positions` (x, y, z per vertex). Returns the kept grid's size.
export function sampleTissue(w: Float32Array, nx: number, ny: number, stride: number,
                             lx: number, ly: number, positions: Float32Array | null):
    { nx: number; ny: number } {
  const kx = Math.floor((nx - 1) / stride) + 1;
  const ky = Math.floor((ny - 1) / stride) + 1;
  if (positions) {
    let v = 0;
    for (let j = 0; j < ky; ++j) {
      for (let i = 0; i < kx; ++i) {
        const gi = i * stride;
        const gj = j * stride;
        positions[v++] = (gi / (nx - 1)) * lx;
        positions[v++] = (gj / (ny - 1)) * ly;
        positions[v++] = w[gj * nx + gi];
      }
    }
  }
  return { nx: kx, ny: ky };
}

// The field's value at (x, y) of a patch lx × ly (m) sampled on nx × ny nodes (x fastest):
// bilinear between its nodes, the point clamped to the patch.
export function sampleField(w: Float32Array, nx: number, ny: number, lx: number, ly: number,
                            x: number, y: number): number {
  if (nx < 2 || ny < 2 || w.length < nx * ny) return 0;
  const u = Math.min(Math.max((x / lx) * (nx - 1), 0), nx - 1);
  const v = Math.min(Math.max((y / ly) * (ny - 1), 0), ny - 1);
  const i = Math.min(Math.floor(u), nx - 2);
  const j = Math.min(Math.floor(v), ny - 2);
  const a = u - i;
  const b = v - j;
  const at = (ii: number, jj: number) => w[jj * nx + ii];
  return (1 - a) * (1 - b) * at(i, j) + a * (1 - b) * at(i + 1, j) +
         (1 - a) * b * at(i, j + 1) + a * b * at(i + 1, j + 1);
}

// Lambert shading: cheap per pixel (software WebGL draws every pixel on the CPU); metal
// parts get a little emissive sheen instead of a PBR highlight.
interface Look { transparent?: boolean; opacity?: number; side?: THREE.Side; depthWrite?: boolean;
                 metal?: boolean }
function material(color: number, look: Look = {}): THREE.MeshLambertMaterial {
  const { metal, ...rest } = look;
  const m = new THREE.MeshLambertMaterial({ color, ...rest });
  if (metal) m.emissive.setHex(color).multiplyScalar(0.25);
  // One pass for double-sided transparent surfaces (three draws back and front apart).
  if (rest.transparent) m.forceSinglePass = true;
  return m;
}

// A tube along a polyline of up to maxNodes nodes whose vertices are rewritten in place
// (the thread: its nodes move every frame). Rings are carried along by parallel transport.
// The quiz's knots are drawn as a smooth centreline through their nodes (a centripetal
// Catmull-Rom curve, KNOT_SMOOTHING points per link, through every node): a tied knot's links
// are about four thread diameters long, so that a wrap is only two or three of them.
export const KNOT_SMOOTHING = 4;
export function smoothKnot(points: number[]): Float32Array {
  const n = Math.floor(points.length / 3);
  if (n < 3) return new Float32Array(points);
  const nodes: THREE.Vector3[] = [];
  for (let i = 0; i < n; ++i) nodes.push(new THREE.Vector3(points[3 * i], points[3 * i + 1], points[3 * i + 2]));
  const curve = new THREE.CatmullRomCurve3(nodes, false, 'centripetal');
  const m = (n - 1) * KNOT_SMOOTHING + 1;
  const out = new Float32Array(m * 3);
  const p = new THREE.Vector3();
  for (let k = 0; k < m; ++k) {
    curve.getPoint(k / (m - 1), p);  // uniform in the curve's parameter: node i at k = 4 i
    out[3 * k] = p.x; out[3 * k + 1] = p.y; out[3 * k + 2] = p.z;
  }
  return out;
}

export class PolylineTube {
  readonly mesh: THREE.Mesh;
  private readonly positions: Float32Array;
  private readonly normals: Float32Array;

  constructor(readonly maxNodes: number, public radius: number, readonly sides: number,
              mat: THREE.Material) {
    this.positions = new Float32Array(maxNodes * sides * 3);
    this.normals = new Float32Array(maxNodes * sides * 3);
    const index = new Uint32Array((maxNodes - 1) * sides * 6);
    let k = 0;
    for (let i = 0; i + 1 < maxNodes; ++i) {
      for (let j = 0; j < sides; ++j) {
        const a = i * sides + j;
        const b = i * sides + ((j + 1) % sides);
        index[k++] = a; index[k++] = b; index[k++] = a + sides;
        index[k++] = b; index[k++] = b + sides; index[k++] = a + sides;
      }
    }
    const geom = new THREE.BufferGeometry();
    geom.setAttribute('position', new THREE.BufferAttribute(this.positions, 3));
    geom.setAttribute('normal', new THREE.BufferAttribute(this.normals, 3));
    geom.setIndex(new THREE.BufferAttribute(index, 1));
    geom.setDrawRange(0, 0);
    this.mesh = new THREE.Mesh(geom, mat);
    this.mesh.frustumCulled = false;
  }

  // nodes: x, y, z per node. Returns the number of nodes drawn.
  update(nodes: Float32Array): number {
    const n = Math.min(nodes.length / 3, this.maxNodes);
    const t = new THREE.Vector3();
    const nrm = new THREE.Vector3();
    const bin = new THREE.Vector3();
    const p = new THREE.Vector3();
    const q = new THREE.Vector3();
    for (let i = 0; i < n; ++i) {
      const a = Math.max(i - 1, 0);
      const b = Math.min(i + 1, n - 1);
      p.set(nodes[a * 3], nodes[a * 3 + 1], nodes[a * 3 + 2]);
      q.set(nodes[b * 3], nodes[b * 3 + 1], nodes[b * 3 + 2]);
      t.subVectors(q, p);
      if (t.lengthSq() === 0) t.set(1, 0, 0);
      t.normalize();
      if (i === 0) {
        nrm.set(Math.abs(t.x) < 0.9 ? 1 : 0, Math.abs(t.x) < 0.9 ? 0 : 1, 0);
      }
      // Parallel transport: the previous normal made perpendicular to this tangent.
      nrm.addScaledVector(t, -nrm.dot(t));
      if (nrm.lengthSq() < 1e-12) nrm.set(-t.y, t.x, 0);
      nrm.normalize();
      bin.crossVectors(t, nrm);
      for (let j = 0; j < this.sides; ++j) {
        const ang = (2 * Math.PI * j) / this.sides;
        const c = Math.cos(ang);
        const s = Math.sin(ang);
        const v = (i * this.sides + j) * 3;
        const nx = c * nrm.x + s * bin.x;
        const ny = c * nrm.y + s * bin.y;
        const nz = c * nrm.z + s * bin.z;
        this.normals[v] = nx; this.normals[v + 1] = ny; this.normals[v + 2] = nz;
        this.positions[v] = nodes[i * 3] + this.radius * nx;
        this.positions[v + 1] = nodes[i * 3 + 1] + this.radius * ny;
        this.positions[v + 2] = nodes[i * 3 + 2] + this.radius * nz;
      }
    }
    const g = this.mesh.geometry;
    g.getAttribute('position').needsUpdate = true;
    g.getAttribute('normal').needsUpdate = true;
    g.setDrawRange(0, Math.max(n - 1, 0) * this.sides * 6);
    return n;
  }
}

// The tissue's colour by how deep it is pressed (seen from above, the microscope's light shows
// a dimple poorly): skin tone at rest, darkening to deep red at TISSUE_DEPTH_SCALE_M.
// sRGB colours, turned into the linear values vertex colours are read as.
function linear(hex: number): V3 {
  const c = new THREE.Color(hex); // hex is sRGB; three keeps it linear
  return [c.r, c.g, c.b];
}
export const TISSUE_REST: V3 = linear(0xe8a890);
export const TISSUE_PRESSED: V3 = linear(0x8c1f1f);
export const TISSUE_DEPTH_SCALE_M = 0.5e-3;
export function tissueColours(positions: Float32Array, colours: Float32Array): void {
  for (let v = 0; v < positions.length; v += 3) {
    const t = Math.min(Math.max(-positions[v + 2] / TISSUE_DEPTH_SCALE_M, 0), 1);
    for (let k = 0; k < 3; ++k) colours[v + k] = TISSUE_REST[k] + (TISSUE_PRESSED[k] - TISSUE_REST[k]) * t;
  }
}

// One station's scene as three.js objects.
export class SceneView {
  readonly root = new THREE.Group();
  readonly tool = new THREE.Group();
  // Bimanual scenes: the second tool (forceps: a shaft and two closed jaws); null with one hand.
  readonly tool2: THREE.Group | null = null;
  needle: THREE.Mesh | null = null;
  needleMaterial: THREE.MeshBasicMaterial | null = null;
  thread: PolylineTube | null = null;
  tissue: THREE.Mesh | null = null;
  private tissueKey = '';
  // Knot tying: the stitch's rods, which move with the patch (applyTissue), and their centres
  // at rest.
  readonly stitchRods: THREE.Mesh[] = [];
  private readonly stitchRodCentres: THREE.Vector3[] = [];
  knot: PolylineTube | null = null;
  knotItem = -1; // the quiz item drawn (-1 none; items.length: the quiz is done)
  private knotMinRadius = 0;
  // Knot placement: the stitches placed so far (hidden until placed), from the frames.
  readonly stitches: THREE.Mesh[] = [];
  readonly overlay: CueOverlayView;
  // The thread's extent so far (grows only): the console frames a thread tile on it.
  readonly threadBox = new THREE.Box3();
  threadBoxVersion = 0;
  private shadowDot: THREE.Mesh;
  private floorZ: number;
  lastFrame: Frame | null = null;

  constructor(readonly scene: SceneJson, readonly detail: Detail = HIGH_DETAIL) {
    const d = detail;
    const scale = sceneScale(scene);
    this.floorZ = floorHeight(scene);
    // No table plane: the background is the renderer's clear colour (a full-screen plane
    // costs a software renderer a shaded pixel everywhere); the tool tip's shadow dot on the
    // floor height keeps the depth cue.
    if (scene.vessel) {
      const v = scene.vessel;
      const torus = new THREE.Mesh(
          new THREE.TorusGeometry(v.core_radius, v.tube_radius, d.radial, d.along, v.segment_angle),
          material(0xd0606a, { transparent: true, opacity: 0.45, side: THREE.DoubleSide,
                               depthWrite: false }));
      setPose(torus, v.pose.p, 0, v.pose.q, 0);
      this.root.add(torus);
    }
    if (scene.needle) {
      const n = scene.needle;
      const tube = Math.max(n.radius * 0.03, 40e-6);
      this.needleMaterial = new THREE.MeshBasicMaterial({ color: NEEDLE_COLOR });
      this.needle = new THREE.Mesh(
          new THREE.TubeGeometry(needleCurve(n.radius, n.sweep), d.along, tube, d.radial / 2),
          this.needleMaterial);
      this.root.add(this.needle);
    }
    if (scene.target) {
      const t = scene.target;
      const ring = new THREE.Mesh(new THREE.TorusGeometry(t.radius, t.radius * 0.08, 8, d.along),
                                  new THREE.MeshBasicMaterial({ color: 0x40ff60 }));
      ring.position.set(...t.p);
      this.root.add(ring);
      const dot = new THREE.Mesh(new THREE.SphereGeometry(t.radius * 0.12, 12, 8),
                                 new THREE.MeshBasicMaterial({ color: 0x40ff60 }));
      dot.position.set(...t.p);
      this.root.add(dot);
    }
    if (scene.wire && scene.wire.points.length >= 2) {
      const w = scene.wire;
      const wire = new THREE.Mesh(
          new THREE.TubeGeometry(polylineCurve(w.points), d.along * 2, w.radius, d.radial),
          material(0xd8b040, { metal: true }));
      this.root.add(wire);
    }
    if (scene.stitch) {
      // The rods the suture passes over and under, and the tissue as a translucent slab
      // below the surface, so the bite under it shows through (when the scene has no FEM
      // tissue; with one, that patch is drawn translucent instead: applyTissue).
      for (const r of scene.stitch.rods) {
        const rod = new THREE.Mesh(
            new THREE.TubeGeometry(polylineCurve([r.a, r.b]), 4, r.radius, d.radial),
            material(0xd88080));
        this.stitchRods.push(rod);
        this.stitchRodCentres.push(new THREE.Vector3(
            (r.a[0] + r.b[0]) / 2, (r.a[1] + r.b[1]) / 2, (r.a[2] + r.b[2]) / 2));
        this.root.add(rod);
      }
      if (!scene.tissue) {
      const xs = scene.stitch.rods.flatMap((r) => [r.a[0], r.b[0]]);
      const x0 = Math.min(...xs) - 12e-3;
      const x1 = Math.max(...xs) + 10e-3;
      const depth = 2e-3;
      const slab = new THREE.Mesh(new THREE.BoxGeometry(x1 - x0, depth, 8e-3),
                                  new THREE.MeshStandardMaterial({
                                    color: 0xe0a0a0, transparent: true, opacity: 0.35,
                                    depthWrite: false }));
      slab.position.set((x0 + x1) / 2, scene.stitch.surface_y - depth / 2, 0);
      this.root.add(slab);
      }
    }
    if (scene.grasp) {
      const g = scene.grasp;
      let geom: THREE.BufferGeometry;
      if (g.shape === 'sphere') geom = new THREE.SphereGeometry(g.radius, d.radial, d.radial);
      else if (g.shape === 'cylinder') {
        geom = new THREE.CylinderGeometry(g.radius, g.radius, g.length, d.radial);
        geom.rotateX(Math.PI / 2); // its axis along z
      } else geom = new THREE.BoxGeometry(...g.size);
      const obj = new THREE.Mesh(geom, material(0x6080e0));
      obj.position.set(...g.p);
      obj.rotation.z = g.yaw;
      this.root.add(obj);
    }
    if (scene.placement) {
      const p = scene.placement;
      const geom = new THREE.CylinderGeometry(p.vessel_radius, p.vessel_radius, p.end_height,
                                              d.radial * 2, 1, true);
      geom.rotateX(Math.PI / 2);
      geom.translate(0, 0, p.end_height / 2);
      this.root.add(new THREE.Mesh(geom, material(0xd0606a, { side: THREE.DoubleSide })));
    }
    if (scene.placement) {
      // Where the stitches go: evenly around the vessel, bite below the cut edge (a guide);
      // the stitches placed are drawn as they arrive in the frames (stitch_* of the tool
      // state), a suture-blue bead through the wall at each.
      const p = scene.placement;
      const beadGeom = new THREE.SphereGeometry(p.vessel_radius * 0.11, d.radial, d.radial / 2);
      const beadMat = new THREE.MeshBasicMaterial({ color: KNOT_COLOR });
      for (let k = 0; k < MAX_STITCHES; ++k) {
        const bead = new THREE.Mesh(beadGeom, beadMat);
        bead.visible = false;
        this.stitches.push(bead);
        this.root.add(bead);
      }
      const z = p.end_height - p.bite;
      const r = p.vessel_radius * 1.04;
      const dotGeom = new THREE.SphereGeometry(p.vessel_radius * 0.09, d.radial, d.radial / 2);
      const dotMat = new THREE.MeshBasicMaterial({ color: STITCH_TARGET_COLOR });
      for (let k = 0; k < p.stitches; ++k) {
        const a = (2 * Math.PI * k) / p.stitches;
        const dot = new THREE.Mesh(dotGeom, dotMat);
        dot.position.set(r * Math.cos(a), r * Math.sin(a), z);
        this.root.add(dot);
      }
      // The cut edge, a ring.
      const edge = new THREE.Mesh(new THREE.TorusGeometry(p.vessel_radius, p.vessel_radius * 0.03,
                                                          4, d.along * 2),
                                  new THREE.MeshBasicMaterial({ color: 0xffe0e0 }));
      edge.position.z = p.end_height;
      this.root.add(edge);
    }
    if (scene.knots && scene.knots.items.length > 0) {
      const maxPoints = Math.max(...scene.knots.items.map((k) => k.length / 3));
      // Thin: the strands of a tight knot lie a diameter apart; drawn at least a pixel or two.
      this.knotMinRadius = (fieldOfView(scene) * d.thinFraction) / 6;
      const radius = Math.max(scene.knots.radius, this.knotMinRadius);
      this.knot = new PolylineTube(Math.max((maxPoints - 1) * KNOT_SMOOTHING + 1, 2), radius,
                                   Math.max(4, d.radial / 2),
                                   material(KNOT_COLOR));
      this.root.add(this.knot.mesh);
      this.showKnot(0);
    }
    if (scene.path.length >= 2) {
      const line = new THREE.Line(
          new THREE.BufferGeometry().setFromPoints(scene.path.map((p) => new THREE.Vector3(...p))),
          new THREE.LineBasicMaterial({ color: PATH_COLOR, transparent: true, opacity: 0.6 }));
      this.root.add(line);
    }
    if (scene.thread) {
      // Drawn a few pixels wide: a 10-0 suture (25 µm) is thinner than a pixel of the field.
      const radius = Math.max(scene.thread.radius, (fieldOfView(scene) * d.thinFraction) / 2);
      this.thread = new PolylineTube(512, radius, Math.max(4, d.radial / 2),
                                     material(THREAD_COLOR));
      this.root.add(this.thread.mesh);
    }

    // The tool: a shaft along +z_T from the tip, a tip ball; a loop in T's xy plane.
    const shaftLength = scale * 1.5;
    const shaftRadius = scale * 0.025;
    const shaft = new THREE.Mesh(
        new THREE.CylinderGeometry(shaftRadius, shaftRadius * 0.4, shaftLength, d.radial),
        material(TOOL_COLOR, { metal: true }));
    shaft.rotateX(Math.PI / 2);
    shaft.position.z = shaftLength / 2;
    this.tool.add(shaft);
    const tip = new THREE.Mesh(new THREE.SphereGeometry(shaftRadius * 0.6, d.radial, d.radial / 2),
                               material(0xffd040));
    this.tool.add(tip);
    if (scene.tissue && scene.tissue.bar > 0) {
      // The bar tool pressing the tissue: along the tool's x axis, centred at the tip.
      const bar = new THREE.Mesh(
          new THREE.CylinderGeometry(shaftRadius * 0.5, shaftRadius * 0.5, scene.tissue.bar, d.radial),
          material(TOOL_COLOR, { metal: true }));
      bar.rotateZ(Math.PI / 2);
      this.tool.add(bar);
    }
    if (scene.loop) {
      const loop = new THREE.Mesh(
          new THREE.TorusGeometry(scene.loop.radius, scene.loop.wire_radius, d.radial / 2, d.along),
          material(0xe0e0e8, { metal: true }));
      this.tool.add(loop);
    }
    if (scene.grasp) {
      const g = scene.grasp;
      for (const side of [1, -1]) {
        const jaw = new THREE.Mesh(new THREE.BoxGeometry(g.jaw_width, g.jaw_thickness, g.jaw_length),
                                   material(TOOL_COLOR, { metal: true }));
        jaw.position.set(0, side * (g.open_gap / 2 + g.jaw_thickness / 2), 0);
        this.tool.add(jaw);
      }
    }
    setPose(this.tool, scene.tool_start.p, 0, scene.tool_start.q, 0);
    this.root.add(this.tool);
    if (scene.second_tool_start) {
      const tool2 = new THREE.Group();
      const shaft2 = new THREE.Mesh(
          new THREE.CylinderGeometry(shaftRadius, shaftRadius * 0.4, shaftLength, d.radial),
          material(TOOL2_COLOR, { metal: true }));
      shaft2.rotateX(Math.PI / 2);
      shaft2.position.z = shaftLength / 2;
      tool2.add(shaft2);
      for (const side of [1, -1]) {  // the forceps' closed jaws, tips at the tool point
        const jaw = new THREE.Mesh(
            new THREE.BoxGeometry(shaftRadius * 0.5, shaftRadius * 0.4, shaftLength * 0.2),
            material(TOOL2_COLOR, { metal: true }));
        jaw.position.set(0, side * shaftRadius * 0.25, shaftLength * 0.1);
        tool2.add(jaw);
      }
      setPose(tool2, scene.second_tool_start.p, 0, scene.second_tool_start.q, 0);
      this.root.add(tool2);
      this.tool2 = tool2;
    }
    this.overlay = new CueOverlayView(fieldOfView(scene));
    this.root.add(this.overlay.root);
    // The tool tip's shadow on the table (a depth cue under a microscope's vertical light).
    this.shadowDot = new THREE.Mesh(new THREE.CircleGeometry(shaftRadius * 1.5, 16),
                                    new THREE.MeshBasicMaterial({ color: 0x000000,
                                                                  transparent: true,
                                                                  opacity: 0.45 }));
    this.root.add(this.shadowDot);
    this.placeShadow();
    // The knot quiz is answered with the buttons: its tool would only hide the knot.
    if (scene.knots) this.tool.visible = this.shadowDot.visible = false;

    // Lighting: the microscope's coaxial light plus a hemisphere fill.
    this.root.add(new THREE.HemisphereLight(0xffffff, 0x303040, 0.8));
    const key = new THREE.DirectionalLight(0xffffff, 1.4);
    const dir = scene.microscope.view_dir;
    // Oblique enough to shade a dimple in the tissue.
    key.position.set(-dir[0] + 0.7, -dir[1] + 0.4, -dir[2]);
    this.root.add(key);
  }

  // Updates the objects from a frame (poses, thread nodes, tissue field, contact colour).
  apply(f: Frame): void {
    this.lastFrame = f;
    const s = f.scalars;
    setPose(this.tool, s, S.toolP, s, S.toolQ);
    if (this.tool2 && (f.flags & HAS_SECOND_TOOL)) setPose(this.tool2, s, S.tool2P, s, S.tool2Q);
    this.placeShadow();
    if (this.needle && (f.flags & HAS_NEEDLE)) {
      setPose(this.needle, s, S.needleP, s, S.needleQ);
      this.needleMaterial!.color.setHex(s[S.contact] ? CONTACT_COLOR : NEEDLE_COLOR);
    }
    if (this.thread && (f.flags & HAS_THREAD)) {
      this.thread.update(f.threadNodes);
      this.growThreadBox(f.threadNodes);
    }
    if (f.flags & HAS_TISSUE) this.applyTissue(f);
    if (this.knot && this.scene.knots && (f.flags & HAS_SCORE)) {
      // The quiz's progress is the share of its items answered: the item shown is the next.
      this.showKnot(Math.round(s[S.progress] * this.scene.knots.items.length));
    }
    if (f.overlay) this.overlay.apply(f.overlay);
    this.applyStitches(s);
  }

  // The knot placement's stitches placed so far, on the vessel wall at their azimuth and bite.
  applyStitches(s: Float64Array): void {
    const p = this.scene.placement;
    if (!p || this.stitches.length === 0) return;
    const n = Math.max(0, Math.min(MAX_STITCHES, Math.round(s[S.stitchCount])));
    for (let k = 0; k < this.stitches.length; ++k) {
      const bead = this.stitches[k];
      bead.visible = k < n;
      if (k >= n) continue;
      const a = s[S.stitchAzimuth + k];
      // Just outside the wall (as the targets), so that the wall does not hide half of it.
      const r = p.vessel_radius * 1.04;
      bead.position.set(r * Math.cos(a), r * Math.sin(a), p.end_height - s[S.stitchBite + k]);
    }
  }

  // The thread drawn at least a few pixels wide for a view showing `field` (m) high (a tile
  // framed on the thread shows less than the microscope's field).
  setThreadField(field: number): void {
    if (!this.thread || !this.scene.thread) return;
    this.thread.radius = Math.max(this.scene.thread.radius, (field * this.detail.thinFraction) / 2);
    if (this.lastFrame && (this.lastFrame.flags & HAS_THREAD)) this.thread.update(this.lastFrame.threadNodes);
  }

  // The quiz item i's knot (none once every item is answered).
  showKnot(i: number): void {
    if (!this.knot || !this.scene.knots || i === this.knotItem) return;
    this.knotItem = i;
    const items = this.scene.knots.items;
    if (i >= 0 && i < items.length) {
      this.knot.radius =
          Math.max(this.scene.knots.radii?.[i] ?? this.scene.knots.radius, this.knotMinRadius);
      this.knot.update(smoothKnot(items[i]));
      this.knot.mesh.visible = true;
    } else {
      this.knot.mesh.visible = false;
    }
  }

  private growThreadBox(nodes: Float32Array): void {
    const before = this.threadBox.clone();
    const p = new THREE.Vector3();
    for (let i = 0; i + 2 < nodes.length; i += 3) {
      this.threadBox.expandByPoint(p.set(nodes[i], nodes[i + 1], nodes[i + 2]));
    }
    if (!before.equals(this.threadBox)) ++this.threadBoxVersion;
  }

  private applyTissue(f: Frame): void {
    const s = f.scalars;
    const lx = s[S.tissueLx];
    const ly = s[S.tissueLy];
    const stride = this.detail.tissueStride;
    const key = `${f.tissueNodesX}x${f.tissueNodesY}`;
    if (!this.tissue || key !== this.tissueKey) {
      if (this.tissue) {
        this.root.remove(this.tissue);
        this.tissue.geometry.dispose();
      }
      const size = sampleTissue(f.tissue, f.tissueNodesX, f.tissueNodesY, stride, lx, ly, null);
      const geom = new THREE.BufferGeometry();
      geom.setAttribute('position',
                        new THREE.BufferAttribute(new Float32Array(size.nx * size.ny * 3), 3));
      geom.setAttribute('color',
                        new THREE.BufferAttribute(new Float32Array(size.nx * size.ny * 3), 3));
      geom.setIndex(new THREE.BufferAttribute(gridIndices(size.nx, size.ny), 1));
      // Over a stitch the patch is translucent: the suture's bite under it shows through.
      const m = this.scene.stitch
        ? material(0xffffff, { side: THREE.DoubleSide, transparent: true, opacity: 0.55,
                               depthWrite: false })
        : material(0xffffff, { side: THREE.DoubleSide });
      m.vertexColors = true;
      this.tissue = new THREE.Mesh(geom, m);
      this.tissue.frustumCulled = false;
      this.tissueKey = key;
      this.root.add(this.tissue);
    }
    setPose(this.tissue, s, S.tissueP, s, S.tissueQ);
    const attr = this.tissue.geometry.getAttribute('position') as THREE.BufferAttribute;
    sampleTissue(f.tissue, f.tissueNodesX, f.tissueNodesY, stride, lx, ly,
                 attr.array as Float32Array);
    attr.needsUpdate = true;
    const colour = this.tissue.geometry.getAttribute('color') as THREE.BufferAttribute;
    tissueColours(attr.array as Float32Array, colour.array as Float32Array);
    colour.needsUpdate = true;
    this.tissue.geometry.computeVertexNormals();
    // The stitch moves with the patch (the suture's pull on it is in the field): each rod by
    // the field at its centre, along the patch's normal.
    if (this.stitchRods.length > 0) {
      this.tissue.updateMatrix();
      const toPatch = this.tissue.matrix.clone().invert();
      const normal = new THREE.Vector3(0, 0, 1).applyQuaternion(this.tissue.quaternion);
      for (let k = 0; k < this.stitchRods.length; ++k) {
        const p = this.stitchRodCentres[k].clone().applyMatrix4(toPatch);
        const w = sampleField(f.tissue, f.tissueNodesX, f.tissueNodesY, lx, ly, p.x, p.y);
        this.stitchRods[k].position.copy(normal).multiplyScalar(Number.isFinite(w) ? w : 0);
      }
    }
  }

  private placeShadow(): void {
    this.shadowDot.position.set(this.tool.position.x, this.tool.position.y, this.floorZ + 1e-6);
  }

  // The needle's midpoint in world (the tests look for its colour there).
  needleMidpointWorld(): THREE.Vector3 | null {
    if (!this.needle || !this.scene.needle) return null;
    const n = this.scene.needle;
    const p = needleCurve(n.radius, n.sweep).getPoint(0.5);
    this.needle.updateMatrixWorld();
    return p.applyMatrix4(this.needle.matrixWorld);
  }
}

// The visual cues (CueOverlay topic, in the frames): each polyline a line strip of its colour,
// each label a text sprite at its point, drawn over the scene (no depth test) so that a cue is
// never hidden behind the object it is about. Buffers are allocated once; a label's texture
// is redrawn only when its text or colour changes.
export class CueOverlayView {
  readonly root = new THREE.Group();
  readonly lines: THREE.Line[] = [];
  readonly labels: { sprite: THREE.Sprite; key: string; canvas: HTMLCanvasElement | null }[] = [];
  drawnPolylines = 0;
  drawnLabels = 0;

  constructor(private readonly field: number) {
    this.root.renderOrder = 10;
    for (let i = 0; i < MAX_OVERLAY_POLYLINES; ++i) {
      const geom = new THREE.BufferGeometry();
      geom.setAttribute('position', new THREE.BufferAttribute(new Float32Array(MAX_OVERLAY_POINTS * 3), 3));
      geom.setDrawRange(0, 0);
      const line = new THREE.Line(geom, new THREE.LineBasicMaterial({
        color: 0xffffff, transparent: true, depthTest: false, depthWrite: false }));
      line.frustumCulled = false;
      line.renderOrder = 10;
      line.visible = false;
      this.lines.push(line);
      this.root.add(line);
    }
    for (let i = 0; i < MAX_OVERLAY_LABELS; ++i) {
      const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ depthTest: false, depthWrite: false,
                                                                 transparent: true }));
      sprite.renderOrder = 11;
      sprite.visible = false;
      this.labels.push({ sprite, key: '', canvas: null });
      this.root.add(sprite);
    }
  }

  apply(o: Overlay): void {
    for (let i = 0; i < this.lines.length; ++i) {
      const line = this.lines[i];
      const pl = o.polylines[i];
      if (!pl || pl.points.length < 6) { line.visible = false; continue; }
      const attr = line.geometry.getAttribute('position') as THREE.BufferAttribute;
      (attr.array as Float32Array).set(pl.points);
      attr.needsUpdate = true;
      line.geometry.setDrawRange(0, pl.points.length / 3);
      const m = line.material as THREE.LineBasicMaterial;
      m.color.setRGB(pl.rgba[0], pl.rgba[1], pl.rgba[2], THREE.SRGBColorSpace);
      m.opacity = pl.rgba[3];
      line.visible = true;
    }
    this.drawnPolylines = Math.min(o.polylines.length, this.lines.length);
    for (let i = 0; i < this.labels.length; ++i) {
      const l = this.labels[i];
      const lab = o.labels[i];
      if (!lab || !lab.text) { l.sprite.visible = false; continue; }
      l.sprite.position.set(lab.p[0], lab.p[1], lab.p[2]);
      const key = `${lab.text}|${Array.from(lab.rgba).map((v) => v.toFixed(2)).join(',')}`;
      if (key !== l.key) {
        l.key = key;
        this.drawLabel(l, lab.text, lab.rgba);
        // Labels anchored at nearly the same point (the tool's) stack downwards, not overlap.
        l.sprite.center.set(0, 0.5 + 1.1 * i);
      }
      l.sprite.visible = true;
    }
    this.drawnLabels = Math.min(o.labels.length, this.labels.length);
  }

  private drawLabel(l: { sprite: THREE.Sprite; canvas: HTMLCanvasElement | null }, text: string,
                    rgba: Float32Array): void {
    if (typeof document === 'undefined') return; // no DOM (unit tests): positions only
    if (!l.canvas) {
      l.canvas = document.createElement('canvas');
      l.canvas.width = 256;
      l.canvas.height = 48;
    }
    const ctx = l.canvas.getContext('2d');
    if (!ctx) return;
    ctx.clearRect(0, 0, 256, 48);
    ctx.font = 'bold 30px sans-serif';
    ctx.textBaseline = 'middle';
    ctx.lineWidth = 6;
    ctx.strokeStyle = 'rgba(0,0,0,0.8)';
    ctx.strokeText(text, 6, 24);
    const c = (v: number) => Math.round(Math.min(Math.max(v, 0), 1) * 255);
    ctx.fillStyle = `rgb(${c(rgba[0])},${c(rgba[1])},${c(rgba[2])})`;
    ctx.fillText(text, 6, 24);
    const m = l.sprite.material as THREE.SpriteMaterial;
    if (m.map) m.map.dispose();
    m.map = new THREE.CanvasTexture(l.canvas);
    m.map.colorSpace = THREE.SRGBColorSpace;
    m.needsUpdate = true;
    // About a twentieth of the field high, anchored at its left end.
    const h = this.field / 20;
    l.sprite.scale.set(h * (256 / 48), h, 1);
    l.sprite.center.set(0, 0.5);
  }
}

// The scene's size: what the microscope shows at its magnification (m).
export function fieldOfView(scene: SceneJson): number {
  // A surgical microscope's field is about 200 mm / magnification across.
  return 0.2 / scene.microscope.magnification;
}

export function sceneScale(scene: SceneJson): number { return fieldOfView(scene) / 2; }

// The table below the scene's objects.
export function floorHeight(scene: SceneJson): number {
  let z = scene.microscope.look_at[2];
  const lower = (v: number) => { z = Math.min(z, v); };
  if (scene.vessel) lower(scene.vessel.pose.p[2] - scene.vessel.core_radius * 0.5);
  if (scene.tissue) lower(scene.tissue.pose.p[2] - 0.5e-3);
  if (scene.wire) for (const p of scene.wire.points) lower(p[2] - scene.wire.radius * 4);
  if (scene.target) lower(scene.target.p[2] - 1e-3);
  if (scene.thread) lower(scene.thread.anchor[2] - 1e-3);
  if (scene.grasp) return 0;
  if (scene.placement) return 0;
  return z - 1e-3;
}
