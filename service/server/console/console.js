// The graspd console: plan on a cloud file and look at the plan in 3D. The scene is graspd's own
// (POST /v1/plan?format=glb, service/core/src/plan_scene.rs); the figures come from the JSON
// plan of the same request. Everything is served by graspd itself (no CDN): three.js is in
// vendor/three (MIT, see its LICENSE).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

const $ = (id) => document.getElementById(id);
const state = { cloud: null, cloudName: '' };

// The view: z up, as graspd's frames are.
const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xfafafa);
const camera = new THREE.PerspectiveCamera(45, 1, 0.005, 20);
camera.up.set(0, 0, 1);
camera.position.set(0.45, -0.45, 0.4);
const controls = new OrbitControls(camera, renderer.domElement);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8888aa, 2.0));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(1, -1, 2);
scene.add(sun);
let planRoot = null;

function resize() {
  const w = view.clientWidth, h = view.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();
renderer.setAnimationLoop(() => { controls.update(); renderer.render(scene, camera); });

function status(text, error = false) {
  $('status').textContent = text;
  $('status').classList.toggle('error', error);
}

function headers() {
  const token = $('token').value.trim();
  return token ? { authorization: `Bearer ${token}` } : {};
}

async function errorText(response) {
  try {
    const e = (await response.json()).error;
    return `${response.status}: ${e.field ? e.field + ': ' : ''}${e.message}`;
  } catch {
    return `${response.status} ${response.statusText}`;
  }
}

async function loadHands() {
  const response = await fetch('/v1/hands', { headers: headers() });
  if (!response.ok) {
    status(`hands: ${await errorText(response)}`, true);
    return;
  }
  const { hands } = await response.json();
  const select = $('hand');
  const chosen = select.value;
  select.replaceChildren(...hands.map((h) => new Option(h.name, h.name)));
  if (hands.some((h) => h.name === chosen)) select.value = chosen;
  status(state.cloud ? 'Pick a hand and plan.' : 'Pick a cloud.');
}

function setCloud(bytes, name) {
  state.cloud = bytes;
  state.cloudName = name;
  $('plan').disabled = false;
  status(`${name}: ${bytes.byteLength} bytes. Pick a hand and plan.`);
}

$('cloud').addEventListener('change', async (e) => {
  const file = e.target.files[0];
  if (file) setCloud(await file.arrayBuffer(), file.name);
});
const drop = $('drop');
drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('over'); });
drop.addEventListener('dragleave', () => drop.classList.remove('over'));
drop.addEventListener('drop', async (e) => {
  e.preventDefault();
  drop.classList.remove('over');
  const file = e.dataTransfer.files[0];
  if (file) setCloud(await file.arrayBuffer(), file.name);
});
$('example').addEventListener('click', async () => {
  const response = await fetch('/console/example.ply');
  setCloud(await response.arrayBuffer(), 'tomato_soup_can.ply');
});
$('token').addEventListener('change', loadHands);

/// The RGB-D pair, when both images are chosen.
function rgbdFiles() {
  const color = $('color').files[0], depth = $('depth').files[0];
  return color && depth ? { color, depth } : null;
}

function form() {
  const body = new FormData();
  const request = {
    hand_name: $('hand').value,
    options: { seed: Number($('seed').value) || 0 },
  };
  const frame = rgbdFiles();
  if (frame) {
    const [fx, fy, cx, cy] = $('intrinsics').value.split(/[ ,]+/).filter(Boolean).map(Number);
    request.rgbd = { intrinsics: { fx, fy, cx, cy } };
    body.append('color', frame.color, frame.color.name);
    body.append('depth', frame.depth, frame.depth.name);
  } else {
    body.append('cloud', new Blob([state.cloud]), state.cloudName);
    if ($('table').checked) request.hints = { support_plane: { normal: [0, 0, 1], offset: 0 } };
  }
  body.append('request', new Blob([JSON.stringify(request)], { type: 'application/json' }));
  return body;
}

for (const id of ['color', 'depth']) {
  $(id).addEventListener('change', () => {
    if (rgbdFiles()) {
      $('plan').disabled = false;
      status('RGB-D frame chosen. Pick a hand and plan.');
    }
  });
}

// A hand from a folder: its MJCF or URDF document at the top, the meshes with their paths
// relative to it, as POST /v1/hands takes them.
$('hand-upload').addEventListener('click', async () => {
  const files = [...$('hand-folder').files];
  const relative = (f) => (f.webkitRelativePath || f.name).split('/').slice(1).join('/') || f.name;
  // The document at the folder's top; MuJoCo Menagerie's scene.xml (which includes the hand)
  // comes last.
  const documents = files
    .filter((f) => !relative(f).includes('/') && /\.(xml|urdf)$/i.test(f.name))
    .sort((a, b) => (a.name === 'scene.xml') - (b.name === 'scene.xml'));
  const model = documents[0];
  if (!model) {
    status('hand: the folder needs an .xml (MJCF) or .urdf document at its top', true);
    return;
  }
  const body = new FormData();
  body.append('name', $('hand-name').value.trim());
  body.append('format', /\.urdf$/i.test(model.name) ? 'urdf' : 'mjcf');
  body.append('model', model, model.name);
  // The meshes (and textures) the document may name; README and LICENSE files stay behind.
  for (const f of files) {
    if (f !== model && /\.(stl|obj|msh|png)$/i.test(f.name)) body.append('asset', f, relative(f));
  }
  status('Registering the hand…');
  const response = await fetch('/v1/hands', { method: 'POST', body, headers: headers() });
  if (!response.ok) {
    status(`hand: ${await errorText(response)}`, true);
    return;
  }
  const registered = await response.json();
  const name = registered.hand?.name || $('hand-name').value.trim();
  await loadHands();
  $('hand').value = name;
  status(`Hand ${name} registered.`);
});

function figures(plan) {
  const q = plan.quality || {};
  const rows = [
    ['hand', plan.hand],
    ['grasp type', plan.grasp_type],
    ['feasible', plan.feasible ? 'yes' : `no: ${plan.infeasible_reason}`],
    ['robustness', (q.robustness ?? 0).toFixed(3)],
    ['GII', (q.gii ?? 0).toFixed(3)],
    ['contacts', plan.contacts.map((c) => c.finger).join(', ')],
    ['points used', plan.points_used],
    ['planner', `${(plan.timings.total * 1000).toFixed(1)} ms`],
  ];
  $('figures').replaceChildren(...rows.map(([k, v]) => {
    const tr = document.createElement('tr');
    tr.append(Object.assign(document.createElement('td'), { textContent: k }),
              Object.assign(document.createElement('td'), { textContent: String(v) }));
    return tr;
  }));
}

function frame(object) {
  const box = new THREE.Box3().setFromObject(object);
  const centre = box.getCenter(new THREE.Vector3());
  const size = Math.max(box.getSize(new THREE.Vector3()).length(), 0.05);
  controls.target.copy(centre);
  camera.position.copy(centre).add(new THREE.Vector3(0.8, -0.8, 0.7).multiplyScalar(size));
  camera.near = size / 100;
  camera.far = size * 50;
  camera.updateProjectionMatrix();
}

async function plan() {
  $('plan').disabled = true;
  status('Planning…');
  try {
    const [json, glb] = await Promise.all([
      fetch('/v1/plan', { method: 'POST', body: form(), headers: headers() }),
      fetch('/v1/plan?format=glb', { method: 'POST', body: form(), headers: headers() }),
    ]);
    if (!json.ok) throw new Error(await errorText(json));
    if (!glb.ok) throw new Error(await errorText(glb));
    const plan = await json.json();
    const gltf = await new GLTFLoader().parseAsync(await glb.arrayBuffer(), '');
    if (planRoot) scene.remove(planRoot);
    planRoot = gltf.scene;
    planRoot.traverse((o) => {
      if (o.isPoints) o.material.size = 3, o.material.sizeAttenuation = false;
    });
    scene.add(planRoot);
    frame(planRoot);
    figures(plan);
    // What the scene holds, for tests and the curious: the node names of the plan's scene.
    // (three.js strips '/' from names; the glTF's own name is kept in userData.)
    window.graspdScene = {
      nodes: gltf.scene.children.map((o) => o.userData.name || o.name),
      plan,
    };
    status(`Planned: ${plan.grasp_type}, ${plan.feasible ? 'feasible' : 'infeasible'}.`);
  } catch (e) {
    status(String(e.message || e), true);
  } finally {
    $('plan').disabled = false;
  }
}
$('plan').addEventListener('click', plan);

loadHands();
