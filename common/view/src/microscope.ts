// The microscope's camera: looking along the scene's view_dir at look_at, the field of view
// set by the magnification (fieldOfView); the eyepieces' two views for stereo.

import * as THREE from 'three';
import { SceneJson, fieldOfView } from './scene_objects';

export const VERTICAL_FOV_DEG = 20;

// A camera for `scene` with the given aspect (width / height).
export function microscopeCamera(scene: SceneJson, aspect: number): THREE.PerspectiveCamera {
  const field = fieldOfView(scene);
  const distance = field / 2 / Math.tan(THREE.MathUtils.degToRad(VERTICAL_FOV_DEG / 2));
  const camera = new THREE.PerspectiveCamera(VERTICAL_FOV_DEG, aspect, distance / 50, distance * 20);
  aimCamera(camera, scene, distance);
  return camera;
}

// Places the camera at `distance` from look_at against view_dir; "up" on the screen is world
// +y turned into the image plane (or +x when looking along y).
export function aimCamera(camera: THREE.PerspectiveCamera, scene: SceneJson,
                          distance: number, orbit = new THREE.Quaternion()): void {
  const look = new THREE.Vector3(...scene.microscope.look_at);
  const dir = new THREE.Vector3(...scene.microscope.view_dir).normalize().applyQuaternion(orbit);
  camera.position.copy(look).addScaledVector(dir, -distance);
  const up = Math.abs(dir.y) > 0.9 ? new THREE.Vector3(1, 0, 0) : new THREE.Vector3(0, 1, 0);
  if (Math.abs(dir.z) < 0.95) up.set(0, 0, 1);
  camera.up.copy(up);
  camera.lookAt(look);
  camera.updateMatrixWorld();
}

export function cameraDistance(scene: SceneJson): number {
  return fieldOfView(scene) / 2 / Math.tan(THREE.MathUtils.degToRad(VERTICAL_FOV_DEG / 2));
}

// The image-plane axes of a camera in world (for turning keys into world moves).
export function screenAxes(camera: THREE.Camera): { right: THREE.Vector3; up: THREE.Vector3;
                                                    forward: THREE.Vector3 } {
  const m = camera.matrixWorld.elements;
  return {
    right: new THREE.Vector3(m[0], m[1], m[2]).normalize(),
    up: new THREE.Vector3(m[4], m[5], m[6]).normalize(),
    forward: new THREE.Vector3(-m[8], -m[9], -m[10]).normalize(),
  };
}

// True when WebGL is drawn in software (SwiftShader, llvmpipe): the pages then spare
// multisampling.
export function softwareGl(): boolean {
  const gl = document.createElement('canvas').getContext('webgl2');
  if (!gl) return true;
  const info = gl.getExtension('WEBGL_debug_renderer_info');
  const name = String(info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER));
  gl.getExtension('WEBGL_lose_context')?.loseContext();
  return /swiftshader|llvmpipe|software/i.test(name);
}

// Aims `camera` along the scene's view direction at the centre of `box` (world), from the
// distance at which the box, with `margin` around it, just fits the view (its extent across
// and up the image plane against the horizontal and vertical angles of view): the console's
// thread tiles show the thread wherever it lies, as large as fits. Returns the height of the
// field shown at the box's centre (m).
export function fitCamera(camera: THREE.PerspectiveCamera, scene: SceneJson, box: THREE.Box3,
                          margin = 1.15): number {
  if (box.isEmpty()) return fieldOfView(scene);
  const centre = box.getCenter(new THREE.Vector3());
  const framed: SceneJson = { ...scene, microscope: { ...scene.microscope,
                                                      look_at: centre.toArray() as [number, number, number] } };
  // The image-plane axes for this view direction (aimCamera's), then the box's half extents
  // along them and along the view.
  aimCamera(camera, framed, 1);
  const { right, up, forward } = screenAxes(camera);
  let halfW = 0;
  let halfH = 0;
  let halfD = 0;
  const corner = new THREE.Vector3();
  for (let k = 0; k < 8; ++k) {
    corner.set(k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y,
               k & 4 ? box.max.z : box.min.z).sub(centre);
    halfW = Math.max(halfW, Math.abs(corner.dot(right)));
    halfH = Math.max(halfH, Math.abs(corner.dot(up)));
    halfD = Math.max(halfD, Math.abs(corner.dot(forward)));
  }
  const minHalf = fieldOfView(scene) / 80; // a point-like thread: not closer than this
  const tanV = Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
  const tanH = tanV * camera.aspect;
  const distance = halfD + margin * Math.max(halfW / tanH, halfH / tanV, minHalf / tanV);
  camera.near = distance / 50;
  camera.far = distance * 20;
  camera.updateProjectionMatrix();
  aimCamera(camera, framed, distance);
  return 2 * (distance - halfD) * tanV;
}
