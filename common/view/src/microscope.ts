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
