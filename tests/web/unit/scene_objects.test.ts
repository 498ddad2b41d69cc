// Building three.js objects from a scene (common/view/src/scene_objects.ts) and updating them
// from frames: geometry where the scene says, poses from the frame, the tissue grid in place.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import * as THREE from 'three';
import { HAS_NEEDLE, HAS_SCORE, HAS_SECOND_TOOL, HAS_TISSUE, HAS_THREAD, S, SCALAR_COUNT, Frame, Overlay } from '../../../common/view/src/frame';
import {
  SceneJson, SceneView, HIGH_DETAIL, LOW_DETAIL, NEEDLE_COLOR, CONTACT_COLOR, gridIndices,
  needleCurve, polylineCurve, sampleTissue, sampleField, fieldOfView, TISSUE_REST, KNOT_SMOOTHING,
  smoothKnot,
} from '../../../common/view/src/scene_objects';
import { fitCamera, microscopeCamera } from '../../../common/view/src/microscope';

const base: SceneJson = {
  name: 't', task: 'follow_path', modules: ['needle'], tolerance: 1e-4, path: [],
  microscope: { magnification: 10, look_at: [0, 0, 0], view_dir: [0, 0, -1] },
  tool_start: { p: [0.001, 0, 0], q: [1, 0, 0, 0] },
  vessel: { core_radius: 5e-3, tube_radius: 0.5e-3, segment_angle: Math.PI, pose: { p: [0, 0, 0], q: [1, 0, 0, 0] } },
  needle: { radius: 5e-3, sweep: Math.PI / 3, X_TN: { p: [0, 0, 0], q: [1, 0, 0, 0] } },
};

function frame(flags: number, set: Record<number, number>, thread: number[] = [],
               tissue: number[] = [], nx = 0, ny = 0): Frame {
  const scalars = new Float64Array(SCALAR_COUNT);
  scalars[S.toolQ] = 1;
  scalars[S.needleQ] = 1;
  scalars[S.tissueQ] = 1;
  scalars[S.tool2Q] = 1;
  for (const [k, v] of Object.entries(set)) scalars[Number(k)] = v;
  return { flags, slot: 0, scalars, threadNodes: new Float32Array(thread),
           tissue: new Float32Array(tissue), tissueNodesX: nx, tissueNodesY: ny, overlay: null };
}

test('a quiz knot is drawn smooth through every one of its nodes', () => {
  const nodes = [0, 0, 0, 1e-4, 0, 0, 1e-4, 1e-4, 0, 0, 1e-4, 5e-5];
  const s = smoothKnot(nodes);
  assert.equal(s.length / 3, 3 * KNOT_SMOOTHING + 1);
  for (let i = 0; i < 4; ++i) {
    for (let c = 0; c < 3; ++c) assert.ok(Math.abs(s[3 * KNOT_SMOOTHING * i + c] - nodes[3 * i + c]) < 1e-10);
  }
  // Between the corner nodes the curve bulges out of the polygon's corner (rounded, not cut).
  const mid = (k: number) => new THREE.Vector3(s[3 * k], s[3 * k + 1], s[3 * k + 2]);
  const half = mid(KNOT_SMOOTHING + KNOT_SMOOTHING / 2);  // between nodes 1 and 2, x = 1e-4 on the polygon
  assert.ok(half.x > 1e-4, `the curve is rounded out past the corner: x ${half.x}`);
  assert.deepEqual(Array.from(smoothKnot([0, 0, 0, 1, 0, 0])), [0, 0, 0, 1, 0, 0]);
});

test('the knot quiz shows the item its progress points at, none once done', () => {
  const knots = { radius: 90e-6, radii: [60e-6, 90e-6],
                  items: [[0, 0, 0, 1e-4, 0, 0, 2e-4, 1e-4, 0], [0, 0, 0, 0, 3e-4, 0]] };
  const v = new SceneView({ ...base, modules: ['knots'], vessel: undefined, needle: undefined, knots }, LOW_DETAIL);
  assert.ok(v.knot);
  assert.equal(v.knot!.mesh.visible, true);
  assert.equal(v.tool.visible, false, 'the quiz is answered with the buttons: no tool over the knot');
  assert.equal(new SceneView(base, LOW_DETAIL).tool.visible, true);
  assert.equal(v.knotItem, 0);
  const drawn = () => v.knot!.mesh.geometry.drawRange.count;
  const first = drawn();
  assert.ok(first > 0);
  assert.equal(v.knot!.radius, 60e-6, 'each item its own tube');
  v.apply(frame(HAS_SCORE, { [S.progress]: 0.5 }));
  assert.equal(v.knotItem, 1);
  assert.equal(v.knot!.radius, 90e-6);
  assert.ok(drawn() < first, 'the second knot has fewer points');
  assert.ok(v.knot!.mesh.visible);
  v.apply(frame(HAS_SCORE, { [S.progress]: 1 }));
  assert.equal(v.knot!.mesh.visible, false);
});

test('the cue overlay draws the frame\'s polylines in their colours, hides the rest', () => {
  const v = new SceneView(base, LOW_DETAIL);
  const f = frame(0, {});
  const o: Overlay = { polylines: [{ role: 2, rgba: new Float32Array([1, 0, 0, 0.5]), widthM: 0,
                                     points: new Float32Array([0, 0, 0, 1e-3, 0, 0, 1e-3, 1e-3, 0]) }],
                       labels: [{ role: 3, rgba: new Float32Array([1, 1, 0, 1]), p: new Float32Array([1e-3, 2e-3, 3e-3]), text: '0.3 mm' }] };
  f.overlay = o;
  v.apply(f);
  const line = v.overlay.lines[0];
  assert.ok(line.visible);
  assert.equal(line.geometry.drawRange.count, 3);
  assert.ok(Math.abs((line.material as THREE.LineBasicMaterial).opacity - 0.5) < 1e-6);
  assert.equal(v.overlay.lines[1].visible, false);
  assert.ok(v.overlay.labels[0].sprite.visible);
  assert.ok(Math.abs(v.overlay.labels[0].sprite.position.z - 3e-3) < 1e-9);
  // An empty overlay clears what was drawn; a frame without one keeps it.
  const g = frame(0, {});
  g.overlay = { polylines: [], labels: [] };
  v.apply(g);
  assert.equal(line.visible, false);
  assert.equal(v.overlay.labels[0].sprite.visible, false);
});

test('a thread tile frames the thread: the camera sees every node, closer than the field', () => {
  const s: SceneJson = { ...base, modules: ['thread'], vessel: undefined, needle: undefined,
                         thread: { anchor: [0, 0, 0], radius: 15e-6 } };
  const v = new SceneView(s, LOW_DETAIL);
  const nodes = [0, 0, 0, 2e-3, 1e-3, 0, 4e-3, 0, 0];
  v.apply(frame(HAS_THREAD, {}, nodes));
  assert.ok(!v.threadBox.isEmpty());
  const cam = microscopeCamera(s, 16 / 9);
  const before = cam.position.distanceTo(new THREE.Vector3(0, 0, 0));
  fitCamera(cam, s, v.threadBox);
  cam.updateMatrixWorld();
  for (let i = 0; i < nodes.length; i += 3) {
    const p = new THREE.Vector3(nodes[i], nodes[i + 1], nodes[i + 2]).project(cam);
    assert.ok(Math.abs(p.x) <= 1 && Math.abs(p.y) <= 1, `node ${i / 3} in view`);
  }
  assert.ok(cam.position.distanceTo(new THREE.Vector3(2e-3, 0.5e-3, 0)) < before);
});

test('the needle curve is the arc (rho cos s, rho sin s, 0)', () => {
  const c = needleCurve(2, Math.PI / 2);
  const end = c.getPoint(1);
  assert.ok(Math.abs(end.x) < 1e-12 && Math.abs(end.y - 2) < 1e-12);
  const mid = c.getPoint(0.5);
  assert.ok(Math.abs(mid.length() - 2) < 1e-12);
});

test('the vessel is the torus segment of the scene, the needle follows the frame', () => {
  const v = new SceneView(base, HIGH_DETAIL);
  v.root.updateMatrixWorld(true);
  const box = new THREE.Box3().setFromObject(v.root.children.find((o) =>
      (o as THREE.Mesh).geometry instanceof THREE.TorusGeometry)!);
  // Half a torus (segment π): x from −(R + r) to R + r, y from about 0 to R + r.
  assert.ok(Math.abs(box.max.x - 5.5e-3) < 1e-5, `max x ${box.max.x}`);
  assert.ok(Math.abs(box.max.y - 5.5e-3) < 2e-4, `max y ${box.max.y}`);
  assert.ok(box.min.y > -0.6e-3, `min y ${box.min.y}`);
  // A frame places the needle at its pose and colours it by contact.
  const q = new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(0, 0, 1), Math.PI / 2);
  v.apply(frame(HAS_NEEDLE, { [S.needleP]: 1e-3, [S.needleP + 1]: 2e-3, [S.needleQ]: q.w,
                              [S.needleQ + 3]: q.z, [S.contact]: 1 }));
  assert.equal(v.needleMaterial!.color.getHex(), CONTACT_COLOR);
  const mid = v.needleMidpointWorld()!;
  // Midpoint of the arc at s = π/6 turned by 90° about z, then moved by (1, 2, 0) mm.
  const m = new THREE.Vector3(5e-3 * Math.cos(Math.PI / 6), 5e-3 * Math.sin(Math.PI / 6), 0)
      .applyQuaternion(q).add(new THREE.Vector3(1e-3, 2e-3, 0));
  assert.ok(mid.distanceTo(m) < 1e-12, `${mid.toArray()} vs ${m.toArray()}`);
  v.apply(frame(HAS_NEEDLE, { [S.contact]: 0 }));
  assert.equal(v.needleMaterial!.color.getHex(), NEEDLE_COLOR);
});

test('knot placement: the stitches placed appear on the vessel wall at their azimuth and bite', () => {
  const placement = { vessel_radius: 1e-3, end_height: 4e-3, stitches: 8, bite: 0.3e-3 };
  const v = new SceneView({ ...base, modules: ['placement'], vessel: undefined, needle: undefined, placement },
                          LOW_DETAIL);
  assert.equal(v.stitches.length, 16);
  assert.ok(v.stitches.every((b) => !b.visible), 'none placed yet');
  v.apply(frame(0, { [S.stitchCount]: 2, [S.stitchAzimuth]: 0, [S.stitchBite]: 0.3e-3,
                     [S.stitchAzimuth + 1]: Math.PI / 2, [S.stitchBite + 1]: 0.5e-3 }));
  assert.deepEqual(v.stitches.map((b) => b.visible).slice(0, 3), [true, true, false]);
  const near = (a: number[], b: number[]) => a.every((x, i) => Math.abs(x - b[i]) < 1e-12);
  assert.ok(near(v.stitches[0].position.toArray(), [1.04e-3, 0, 3.7e-3]));
  assert.ok(near(v.stitches[1].position.toArray(), [0, 1.04e-3, 3.5e-3]));
  // A count beyond the slots is cut; a later frame with fewer hides the rest (a new run).
  v.apply(frame(0, { [S.stitchCount]: 99 }));
  assert.ok(v.stitches.every((b) => b.visible));
  v.apply(frame(0, { [S.stitchCount]: 0 }));
  assert.ok(v.stitches.every((b) => !b.visible));
});

test('the tool takes the frame pose', () => {
  const v = new SceneView(base, LOW_DETAIL);
  assert.deepEqual(v.tool.position.toArray(), [0.001, 0, 0]);
  v.apply(frame(0, { [S.toolP]: 3e-3, [S.toolP + 1]: -1e-3, [S.toolP + 2]: 2e-3 }));
  assert.deepEqual(v.tool.position.toArray(), [3e-3, -1e-3, 2e-3]);
});

test('a bimanual scene draws the second tool at its start, then where its frames put it', () => {
  assert.equal(new SceneView(base, LOW_DETAIL).tool2, null, 'one hand: no second tool');
  const v = new SceneView({ ...base, second_tool_start: { p: [-0.002, 0, 0], q: [1, 0, 0, 0] } },
                         LOW_DETAIL);
  assert.ok(v.tool2);
  assert.deepEqual(v.tool2!.position.toArray(), [-0.002, 0, 0]);
  // A frame without the section leaves it; one with it moves it (and not the first tool).
  v.apply(frame(0, { [S.tool2P]: 5e-3 }));
  assert.deepEqual(v.tool2!.position.toArray(), [-0.002, 0, 0]);
  const h = Math.SQRT1_2;
  v.apply(frame(HAS_SECOND_TOOL, { [S.tool2P]: -4e-3, [S.tool2P + 1]: 1e-3, [S.tool2P + 2]: 2e-3,
                                   [S.tool2Q]: h, [S.tool2Q + 3]: h }));
  assert.deepEqual(v.tool2!.position.toArray(), [-4e-3, 1e-3, 2e-3]);
  assert.ok(Math.abs(v.tool2!.quaternion.z - h) < 1e-12);
  assert.deepEqual(v.tool.position.toArray(), [0, 0, 0]);
});

test('the thread tube is rebuilt in place around the frame\'s nodes', () => {
  const v = new SceneView({ ...base, thread: { anchor: [0, 0, 0], radius: 1e-3 } });
  const tube = v.thread!;
  const geom = tube.mesh.geometry;
  const attr = geom.getAttribute('position');
  const nodes = [0, 0, 0, 1e-2, 0, 0, 2e-2, 1e-2, 0];
  v.apply(frame(HAS_THREAD, {}, nodes));
  assert.equal(geom.drawRange.count, 2 * tube.sides * 6);
  // Every ring vertex lies one radius from its node, its normal along the offset.
  for (let i = 0; i < 3; ++i) {
    for (let j = 0; j < tube.sides; ++j) {
      const k = i * tube.sides + j;
      const off = new THREE.Vector3(attr.getX(k) - nodes[i * 3], attr.getY(k) - nodes[i * 3 + 1],
                                    attr.getZ(k) - nodes[i * 3 + 2]);
      assert.ok(Math.abs(off.length() - 1e-3) < 1e-8, `ring ${i} vertex ${j}: ${off.length()}`);
      const nrm = geom.getAttribute('normal');
      assert.ok(off.normalize().distanceTo(new THREE.Vector3(nrm.getX(k), nrm.getY(k), nrm.getZ(k))) < 1e-5);
    }
  }
  // The rings are across the thread: node 0's ring is perpendicular to the first link.
  const k0 = new THREE.Vector3(attr.getX(0), attr.getY(0), attr.getZ(0));
  assert.ok(Math.abs(k0.x) < 1e-9);
  v.apply(frame(HAS_THREAD, {}, [0, 0, 0, 5e-3, 0, 0]));
  assert.equal(geom.drawRange.count, 1 * tube.sides * 6);
  assert.equal(geom.getAttribute('position'), attr, 'the same buffer, updated');
});

test('tissue grid: indices, sub-sampling, heights from the field', () => {
  const idx = gridIndices(3, 2);
  assert.deepEqual(Array.from(idx), [0, 1, 3, 1, 4, 3, 1, 2, 4, 2, 5, 4]);
  const w = new Float32Array(25).map((_, i) => -i);
  const out = new Float32Array(9 * 3);
  const size = sampleTissue(w, 5, 5, 2, 0.02, 0.01, out);
  assert.deepEqual(size, { nx: 3, ny: 3 });
  // Node (i, j) = (2, 1) of the kept grid is (4, 2) of the field: w = -(2 * 5 + 4).
  const k = (1 * 3 + 2) * 3;
  assert.ok(Math.abs(out[k] - 0.02) < 1e-9 && Math.abs(out[k + 1] - 0.005) < 1e-9);
  assert.equal(out[k + 2], -14);

  const v = new SceneView({ ...base, tissue: { lx: 0.02, ly: 0.02, pose: { p: [0, 0, 0], q: [1, 0, 0, 0] }, bar: 0 } });
  const field = Array.from({ length: 9 }, (_, i) => (i === 4 ? -1e-3 : 0));
  v.apply(frame(HAS_TISSUE, { [S.tissueLx]: 0.02, [S.tissueLy]: 0.02 }, [], field, 3, 3));
  const pos = v.tissue!.geometry.getAttribute('position');
  assert.equal(pos.count, 9);
  assert.equal(pos.getZ(4), Math.fround(-1e-3)); // float32, as in the frame
  assert.ok(Math.abs(pos.getX(4) - 0.01) < 1e-9);
  const colour = v.tissue!.geometry.getAttribute('color');
  assert.ok(colour.getX(4) < colour.getX(0) - 0.3, 'the pressed node is drawn darker');
  assert.ok(Math.abs(colour.getX(0) - TISSUE_REST[0]) < 1e-6);
  const mesh = v.tissue;
  v.apply(frame(HAS_TISSUE, { [S.tissueLx]: 0.02, [S.tissueLy]: 0.02 }, [], field.map(() => 0), 3, 3));
  assert.equal(v.tissue, mesh, 'same grid size: the mesh is updated, not rebuilt');
  assert.equal(v.tissue!.geometry.getAttribute('position').getZ(4), 0);
});

test('the wire polyline becomes a curve through its points', () => {
  const c = polylineCurve([[0, 0, 0], [1, 0, 0], [1, 1, 0]]);
  assert.ok(Math.abs(c.getLength() - 2) < 1e-9);
  assert.ok(c.getPoint(1).distanceTo(new THREE.Vector3(1, 1, 0)) < 1e-9);
});

test('the microscope camera looks at look_at and shows the field of its magnification', () => {
  const scene = { ...base, microscope: { magnification: 20, look_at: [0.01, 0, 0.002] as [number, number, number], view_dir: [0, -1, -1] as [number, number, number] } };
  const cam = microscopeCamera(scene, 16 / 9);
  const centre = new THREE.Vector3(...scene.microscope.look_at).project(cam);
  assert.ok(Math.abs(centre.x) < 1e-9 && Math.abs(centre.y) < 1e-9);
  const dir = new THREE.Vector3();
  cam.getWorldDirection(dir);
  assert.ok(dir.distanceTo(new THREE.Vector3(0, -1, -1).normalize()) < 1e-9);
  // A segment of the field's length across the view at look_at spans the image height.
  const field = fieldOfView(scene);
  const up = new THREE.Vector3().setFromMatrixColumn(cam.matrixWorld, 1);
  const top = new THREE.Vector3(...scene.microscope.look_at).addScaledVector(up, field / 2).project(cam);
  assert.ok(Math.abs(top.y - 1) < 1e-6, `top at ${top.y}`);
});

test('knot tying: the stitch rods move with the patch along its normal', () => {
  // The field: bilinear between the nodes, clamped to the patch.
  const w = new Float32Array([0, 1, 2, 3]);  // 2 x 2 nodes over 0.02 x 0.01 m: w = 50 x + 200 y
  assert.ok(Math.abs(sampleField(w, 2, 2, 0.02, 0.01, 0.01, 0.005) - 1.5) < 1e-9);
  assert.ok(Math.abs(sampleField(w, 2, 2, 0.02, 0.01, 0.015, 0.0025) - 1.25) < 1e-9);
  assert.equal(sampleField(w, 2, 2, 0.02, 0.01, -1, 5), 2);
  // The knot-tying scene's frame: the patch's normal along +y (rotated -90 deg about x), its
  // corner at (-1, -0.35, 10) mm; the rods along z at x = 6.5, 9, 11.5 mm.
  const q = [Math.SQRT1_2, -Math.SQRT1_2, 0, 0];
  const p = [-1e-3, -0.35e-3, 10e-3];
  const rod = (x: number, y: number) => ({ a: [x, y, -4e-3] as [number, number, number],
                                          b: [x, y, 4e-3] as [number, number, number],
                                          radius: 1e-4 });
  const v = new SceneView({
    ...base, modules: ['thread', 'tissue'],
    tissue: { lx: 0.02, ly: 0.02, pose: { p, q }, bar: 0 },
    stitch: { rods: [rod(6.5e-3, -0.1e-3), rod(9e-3, -1e-3), rod(11.5e-3, -0.1e-3)],
              surface_y: -0.35e-3 },
  });
  assert.equal(v.stitchRods.length, 3);
  // 21 x 21 nodes (1 mm apart); the patch lifted 0.1 mm at the bite (its centre: patch x 10,
  // y 10 mm), 0 elsewhere.
  const field = Array.from({ length: 21 * 21 }, (_, i) => (i === 10 * 21 + 10 ? 1e-4 : 0));
  v.apply(frame(HAS_TISSUE, {
    [S.tissueLx]: 0.02, [S.tissueLy]: 0.02, [S.tissueP]: p[0], [S.tissueP + 1]: p[1],
    [S.tissueP + 2]: p[2], [S.tissueQ]: q[0], [S.tissueQ + 1]: q[1], [S.tissueQ + 2]: q[2],
    [S.tissueQ + 3]: q[3],
  }, [], field, 21, 21));
  const bite = v.stitchRods[1].position;
  assert.ok(Math.abs(bite.y - 1e-4) < 1e-9, `the bite lifted along +y: ${bite.y}`);
  assert.ok(Math.abs(bite.x) < 1e-12 && Math.abs(bite.z) < 1e-12);
  // The punctures, 2.5 mm away, between nodes with w = 0: still.
  assert.ok(v.stitchRods[0].position.length() < 1e-12);
  assert.ok(v.stitchRods[2].position.length() < 1e-12);
});
