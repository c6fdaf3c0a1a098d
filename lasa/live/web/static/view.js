// The robot drawn in this page (--frames browser): MuJoCo's official WebAssembly bindings place the
// geoms at the joint positions the server sends, three.js draws them. No control code here: the
// step runs on the server only (lasa.live.web.conversation); this module only draws its state.
import * as THREE from "/npm/three/three.module.js";
import loadMujoco from "/npm/mujoco/mujoco.js";

const DIR = "/scene"; // the scene's folder in the module's in-memory file system (MEMFS)
const GEOM = { PLANE: 0, SPHERE: 2, CAPSULE: 3, ELLIPSOID: 4, CYLINDER: 5, BOX: 6, MESH: 7 };

// What the tests and the load benchmark read: load times [ms] and frames drawn.
export const stats = { moduleMs: null, modelMs: null, frames: 0, geoms: 0 };
window.lasaView = stats;

let mujocoReady = null; // the module, loaded once per page
let view = null; // { mujoco, model, data, xml, meshes, camera, scene, renderer, adr }
let pending = null; // the newest joint positions not drawn yet
let scheduled = false; // a draw is waiting for the next animation frame

function rgba(model, g) {
  const mat = model.geom_matid[g];
  const src = mat >= 0 ? model.mat_rgba : model.geom_rgba;
  const k = 4 * (mat >= 0 ? mat : g);
  return [src[k], src[k + 1], src[k + 2], src[k + 3]];
}

function geometry(model, g) {
  const s = model.geom_size.slice(3 * g, 3 * g + 3);
  switch (model.geom_type[g]) {
    case GEOM.PLANE: return new THREE.PlaneGeometry(2 * (s[0] || 2.5), 2 * (s[1] || 2.5));
    case GEOM.SPHERE: return new THREE.SphereGeometry(s[0], 24, 16);
    case GEOM.ELLIPSOID: return new THREE.SphereGeometry(1, 24, 16).scale(s[0], s[1], s[2]);
    // three.js builds capsules and cylinders along y; MuJoCo's run along the geom's z
    case GEOM.CAPSULE: return new THREE.CapsuleGeometry(s[0], 2 * s[1], 8, 16).rotateX(Math.PI / 2);
    case GEOM.CYLINDER: return new THREE.CylinderGeometry(s[0], s[0], 2 * s[1], 24).rotateX(Math.PI / 2);
    case GEOM.BOX: return new THREE.BoxGeometry(2 * s[0], 2 * s[1], 2 * s[2]);
    case GEOM.MESH: {
      const m = model.geom_dataid[g];
      const v0 = model.mesh_vertadr[m], nv = model.mesh_vertnum[m];
      const f0 = model.mesh_faceadr[m], nf = model.mesh_facenum[m];
      const geo = new THREE.BufferGeometry();
      geo.setAttribute("position", new THREE.BufferAttribute(Float32Array.from(model.mesh_vert.slice(3 * v0, 3 * (v0 + nv))), 3));
      geo.setIndex(new THREE.BufferAttribute(Uint32Array.from(model.mesh_face.slice(3 * f0, 3 * (f0 + nf))), 1));
      geo.computeVertexNormals();
      return geo;
    }
    default: return null; // height fields, SDFs: not in the study's scene
  }
}

function build(mujoco, model, data, canvas, cameraId) {
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  scene.add(new THREE.AmbientLight(0xffffff, 1.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(0.6, -1.0, 2.0); // MuJoCo's world: z up
  scene.add(sun);
  const meshes = [];
  for (let g = 0; g < model.ngeom; g++) {
    const color = rgba(model, g);
    if (model.geom_group[g] >= 3 || color[3] === 0) continue; // MuJoCo's viewer hides these too
    const geo = geometry(model, g);
    if (!geo) continue;
    const material = new THREE.MeshLambertMaterial({
      color: new THREE.Color().setRGB(color[0], color[1], color[2], THREE.SRGBColorSpace),
      transparent: color[3] < 1, opacity: color[3], side: THREE.DoubleSide,
    });
    const mesh = new THREE.Mesh(geo, material);
    mesh.matrixAutoUpdate = false;
    scene.add(mesh);
    meshes.push([g, mesh]);
  }
  mujoco.mj_forward(model, data); // once, for the (fixed) camera's pose
  const fovy = cameraId >= 0 ? model.cam_fovy[cameraId] : 45;
  const camera = new THREE.PerspectiveCamera(fovy, canvas.width / canvas.height, 0.01, 20);
  camera.matrixAutoUpdate = false;
  if (cameraId >= 0) place(camera, data.cam_xpos, data.cam_xmat, cameraId);
  else { camera.position.set(1.6, -1.2, 1.2); camera.up.set(0, 0, 1); camera.lookAt(0.4, 0, 0.2); camera.updateMatrix(); }
  // no antialiasing: software WebGL (no GPU) stays cheap; the buffer is kept so a test can read it
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setSize(canvas.width, canvas.height, false);
  return { meshes, camera, scene, renderer };
}

// An object's matrix from MuJoCo's position (3 a row) and row-major rotation (9 a row) of row k.
function place(object, xpos, xmat, k) {
  const p = xpos.slice(3 * k, 3 * k + 3), r = xmat.slice(9 * k, 9 * k + 9);
  object.matrix.set(r[0], r[1], r[2], p[0], r[3], r[4], r[5], p[1], r[6], r[7], r[8], p[2], 0, 0, 0, 1);
  object.matrixWorldNeedsUpdate = true;
}

function draw() {
  scheduled = false;
  if (!view || !pending) return;
  const { mujoco, model, data, adr } = view;
  const qpos = data.qpos;
  pending.forEach((v, i) => { qpos[adr[i]] = v; });
  pending = null;
  mujoco.mj_kinematics(model, data);
  const xpos = data.geom_xpos, xmat = data.geom_xmat;
  for (const [g, mesh] of view.meshes) place(mesh, xpos, xmat, g);
  view.renderer.render(view.scene, view.camera);
  stats.frames += 1;
}

/** Load the current trial's scene (GET /scene) into MuJoCo, once per distinct scene, and draw on `canvas`. */
export async function load(key, msg, canvas) {
  const t0 = performance.now();
  mujocoReady ??= loadMujoco();
  const mujoco = await mujocoReady;
  if (stats.moduleMs === null) stats.moduleMs = performance.now() - t0;
  const t1 = performance.now();
  const auth = { headers: { "X-Scene-Key": key } }; // the trial's key, from its scene message
  const reply = await fetch("/scene", auth);
  if (!reply.ok) throw new Error(`the scene is not available (${reply.status})`);
  const spec = await reply.json();
  if (view && view.xml === spec.xml) { // the same scene as the last trial: keep it
    view.adr = msg.qpos_adr;
    return stats;
  }
  const files = await Promise.all(spec.assets.map(async (name) => {
    const r = await fetch(`/scene/${encodeURIComponent(name)}`, auth);
    if (!r.ok) throw new Error(`the scene's file ${name} is not available (${r.status})`);
    return [name, new Uint8Array(await r.arrayBuffer())];
  }));
  if (!mujoco.FS.analyzePath(DIR).exists) mujoco.FS.mkdir(DIR);
  for (const [name, bytes] of files) mujoco.FS.writeFile(`${DIR}/${name}`, bytes);
  mujoco.FS.writeFile(`${DIR}/scene.xml`, spec.xml);
  const model = mujoco.MjModel.from_xml_path(`${DIR}/scene.xml`);
  const data = new mujoco.MjData(model);
  if (view) { view.renderer.dispose(); view.data.delete(); view.model.delete(); }
  view = { mujoco, model, data, xml: spec.xml, adr: msg.qpos_adr, ...build(mujoco, model, data, canvas, msg.camera) };
  stats.geoms = view.meshes.length;
  stats.modelMs = performance.now() - t1;
  schedule();
  return stats;
}

// At most one draw per animation frame, of the newest state: a slow machine skips states, never queues them.
function schedule() {
  if (!scheduled) { scheduled = true; requestAnimationFrame(draw); }
}

/** Draw the robot at joint positions `q` (the server's tick), or as soon as the scene is loaded. */
export function show(q) {
  pending = q;
  if (view) schedule();
}
