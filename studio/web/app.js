// panelize studio: the page (docs/studio.md). The 3D garment coloured by panel with its seams (three.js),
// seam strokes and grain strokes drawn on its surface, the options, and the flattened pattern beside it with its
// strain.
// Every edit starts a new run on the server, which cancels the running one.
// SPDX-License-Identifier: GPL-3.0-or-later
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/OrbitControls.js';

const $ = (id) => document.getElementById(id);
const SVG = 'http://www.w3.org/2000/svg';

// What the page knows; the browser test reads it through window.studio.
const state = {
  garment: null,        // the server's garment summary {id, name, faces, mean_edge_mm, ...}
  strokes: [],          // seam strokes: {points: [[x, y, z], ...] on the surface (mm), normals}
  grainStrokes: [],     // grain strokes: the warp runs along each in the piece it lies on (a bias cut)
  run: 0,               // the latest run asked for
  shownRun: 0,          // the run whose result is shown
  result: null,
  mode: 'orbit',
  refining: false,      // the run shown next is the consolidated one of the quick layout shown now
  error: '',
};
window.studio = { state, project };

// ---------------------------------------------------------------- requests

async function api(method, path, body, type = 'application/json') {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers['Content-Type'] = type;
    init.body = type === 'application/json' ? JSON.stringify(body) : body;
  }
  const response = await fetch(path, init);
  const answer = await response.json().catch(() => ({ error: `HTTP ${response.status}` }));
  if (!response.ok) throw new Error(answer.error || `HTTP ${response.status}`);
  return answer;
}

function showError(message) {
  state.error = message;
  $('progress-text').textContent = message;
  $('progress-text').style.color = '#b3261e';
}

// ---------------------------------------------------------------- the 3D view

const canvas = $('canvas3d');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xfafafa);
const camera = new THREE.PerspectiveCamera(35, 1, 1, 100000);
const controls = new OrbitControls(camera, canvas);
scene.add(new THREE.HemisphereLight(0xffffff, 0x666677, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.2);
camera.add(sun);
sun.position.set(0.3, 0.6, 1);
scene.add(camera);
const garmentGroup = new THREE.Group();
scene.add(garmentGroup);
let surface = null;     // the garment's mesh (raycast target)
let seamLines = null;
const strokeGroup = new THREE.Group();
scene.add(strokeGroup);

function resize() {
  const box = canvas.parentElement.getBoundingClientRect();
  renderer.setSize(box.width, box.height, false);
  camera.aspect = box.width / Math.max(1, box.height);
  camera.updateProjectionMatrix();
  drawPatternViewBox();
}
window.addEventListener('resize', resize);

function animate() {
  controls.update();
  renderer.render(scene, camera);
  requestAnimationFrame(animate);
}

// A distinct colour per panel (golden-angle hues).
function panelColour(panel) {
  return new THREE.Color().setHSL(((panel * 0.381966) % 1 + 1) % 1, 0.55, 0.68);
}

// The garment as triangles of its own (a colour per face), its seams as lines.
function showGarment(mesh, facePanel, seams) {
  garmentGroup.clear();
  const faces = mesh.faces, positions = mesh.positions;
  const triangles = faces.length / 3;
  const vertex = new Float32Array(faces.length * 3), colour = new Float32Array(faces.length * 3);
  const grey = new THREE.Color(0xbfc0c0);
  for (let f = 0; f < triangles; ++f) {
    const c = facePanel ? panelColour(facePanel[f]) : grey;
    for (let k = 0; k < 3; ++k) {
      const v = faces[3 * f + k], at = 9 * f + 3 * k;
      vertex[at] = positions[3 * v]; vertex[at + 1] = positions[3 * v + 1]; vertex[at + 2] = positions[3 * v + 2];
      colour[at] = c.r; colour[at + 1] = c.g; colour[at + 2] = c.b;
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(vertex, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(colour, 3));
  geometry.setAttribute('normal', new THREE.BufferAttribute(smoothNormals(mesh, faces.length), 3));
  geometry.computeBoundingBox();
  geometry.computeBoundingSphere();
  const material = new THREE.MeshLambertMaterial({ vertexColors: true, side: THREE.DoubleSide,
    polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
  surface = new THREE.Mesh(geometry, material);
  garmentGroup.add(surface);
  if (seams) {
    const segments = [], dartSegments = [];
    for (const seam of seams) {
      const p = seam.points, into = seam.kind === 'dart' ? dartSegments : segments;
      for (let i = 0; i + 5 < p.length; i += 3) into.push(p[i], p[i + 1], p[i + 2], p[i + 3], p[i + 4], p[i + 5]);
    }
    for (const [list, colourOf] of [[segments, 0x1b2a49], [dartSegments, 0xb5179e]]) {
      const lines = new THREE.BufferGeometry();
      lines.setAttribute('position', new THREE.Float32BufferAttribute(list, 3));
      garmentGroup.add(new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: colourOf })));
    }
  }
}

// Each corner's normal: its vertex's, the area-weighted sum of its faces' (smooth shading, while every
// triangle keeps its own colour).
function smoothNormals(mesh, cornerCount) {
  const positions = mesh.positions, faces = mesh.faces, sum = new Float32Array(positions.length);
  const a = new THREE.Vector3(), b = new THREE.Vector3(), c = new THREE.Vector3();
  for (let f = 0; f < faces.length; f += 3) {
    a.fromArray(positions, 3 * faces[f]); b.fromArray(positions, 3 * faces[f + 1]); c.fromArray(positions, 3 * faces[f + 2]);
    const n = b.sub(a).cross(c.sub(a)); // twice the area, along the normal
    for (let k = 0; k < 3; ++k)
      for (let i = 0; i < 3; ++i) sum[3 * faces[f + k] + i] += n.getComponent(i);
  }
  const normals = new Float32Array(cornerCount * 3), n = new THREE.Vector3();
  for (let corner = 0; corner < cornerCount; ++corner) {
    n.fromArray(sum, 3 * faces[corner]).normalize().toArray(normals, 3 * corner);
  }
  return normals;
}

// Points the camera at the garment, looking at its broad side, its tallest axis up.
function frameGarment() {
  const box = surface.geometry.boundingBox, size = new THREE.Vector3(), centre = new THREE.Vector3();
  box.getSize(size); box.getCenter(centre);
  const zUp = size.z > 1.2 * size.y;
  camera.up.set(0, zUp ? 0 : 1, zUp ? 1 : 0);
  const depthAxis = zUp ? (size.y < size.x ? 'y' : 'x') : (size.z < size.x ? 'z' : 'x');
  const radius = surface.geometry.boundingSphere.radius;
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.05;
  const direction = new THREE.Vector3();
  direction[depthAxis] = -1;
  camera.position.copy(centre).addScaledVector(direction, distance);
  camera.near = distance / 100; camera.far = distance * 10;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
}

// The screen position (CSS pixels in the page) of a 3D point: for the browser test.
function project(point) {
  const v = new THREE.Vector3(...point).project(camera), box = canvas.getBoundingClientRect();
  return [box.left + (v.x + 1) / 2 * box.width, box.top + (1 - v.y) / 2 * box.height];
}

// ---------------------------------------------------------------- strokes

const raycaster = new THREE.Raycaster();
function hitSurface(event) {
  if (!surface) return null;
  const box = canvas.getBoundingClientRect();
  const pointer = new THREE.Vector2(((event.clientX - box.left) / box.width) * 2 - 1,
    -((event.clientY - box.top) / box.height) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  const hits = raycaster.intersectObject(surface, false);
  return hits.length ? hits[0] : null;
}

// Seam strokes in orange; grain strokes in blue, with an arrowhead at their end (the warp's direction).
function drawStrokes() {
  strokeGroup.clear();
  const lift = state.garment ? state.garment.mean_edge_mm * 0.15 : 0.5;
  const kinds = [[state.strokes, 0xef8354], [state.grainStrokes, 0x2f6fd6]];
  for (const [strokes, color] of kinds)
    for (const stroke of strokes) {
      const points = stroke.points.map((p, i) => new THREE.Vector3(...p).addScaledVector(stroke.normals[i], lift));
      const geometry = new THREE.BufferGeometry().setFromPoints(points);
      strokeGroup.add(new THREE.Line(geometry, new THREE.LineBasicMaterial({ color, linewidth: 3 })));
      if (strokes === state.grainStrokes && points.length >= 2) {
        const tip = points[points.length - 1], back = points[Math.max(0, points.length - 3)];
        const direction = tip.clone().sub(back).normalize();
        const length = 2 * (state.garment ? state.garment.mean_edge_mm : 5);
        strokeGroup.add(new THREE.ArrowHelper(direction, tip.clone().addScaledVector(direction, -length), length,
          color, length * 0.8, length * 0.5));
      }
    }
}

// The strokes the current mode draws into.
function strokesOfMode() { return state.mode === 'grain' ? state.grainStrokes : state.strokes; }

let drawing = null;
canvas.addEventListener('pointerdown', (event) => {
  if (state.mode === 'orbit' || event.button !== 0) return;
  const hit = hitSurface(event);
  if (state.mode === 'erase') {
    if (hit) eraseNear(hit.point);
    return;
  }
  if (!hit) return;
  canvas.setPointerCapture(event.pointerId);
  drawing = { points: [hit.point.toArray()], normals: [hit.face.normal.clone()] };
});
canvas.addEventListener('pointermove', (event) => {
  if (!drawing) return;
  const hit = hitSurface(event);
  if (!hit) return;
  const last = new THREE.Vector3(...drawing.points[drawing.points.length - 1]);
  if (last.distanceTo(hit.point) < 0.5 * state.garment.mean_edge_mm) return;
  drawing.points.push(hit.point.toArray());
  drawing.normals.push(hit.face.normal.clone());
  const strokes = strokesOfMode();
  strokes.push(drawing);
  drawStrokes();
  strokes.pop();
});
canvas.addEventListener('pointerup', () => {
  if (!drawing) return;
  const stroke = drawing;
  drawing = null;
  if (stroke.points.length >= 2) {
    strokesOfMode().push(stroke);
    drawStrokes();
    startRun();
  }
});

// Erases the stroke (seam or grain) nearest to `point` when within 3 mean edges of it.
function eraseNear(point) {
  let best = null, bestIndex = -1, bestDistance = 3 * state.garment.mean_edge_mm;
  for (const strokes of [state.strokes, state.grainStrokes])
    strokes.forEach((stroke, index) => {
      for (const p of stroke.points) {
        const d = point.distanceTo(new THREE.Vector3(...p));
        if (d < bestDistance) { bestDistance = d; best = strokes; bestIndex = index; }
      }
    });
  if (!best) return;
  best.splice(bestIndex, 1);
  drawStrokes();
  startRun();
}

function setMode(mode) {
  state.mode = mode;
  for (const name of ['orbit', 'draw', 'grain', 'erase']) $(`mode-${name}`).classList.toggle('active', name === mode);
  controls.enabled = mode === 'orbit';
  $('view3d').classList.toggle('drawing', mode === 'draw' || mode === 'grain');
  $('view3d').classList.toggle('erasing', mode === 'erase');
  $('hint').textContent = { orbit: 'drag: orbit · wheel: zoom · right drag: pan',
    draw: 'drag on the garment: a seam stroke',
    grain: 'drag a short stroke on a piece: its warp runs along it (e.g. 45 degrees: a bias cut)',
    erase: 'click a stroke: erase it' }[mode];
}

// ---------------------------------------------------------------- runs

// consolidate: the run's consolidation (docs/run.md, "Consolidation"); the page asks for a quick layout first
// and, with "fewest pieces" ticked, a consolidated one once it is shown (refine).
function runOptions(consolidate) {
  const options = {
    consolidate,
    max_strain: Number($('max-strain').value),
    max_corners: Number($('max-corners').value),
    max_pieces: Number($('max-pieces').value),
    darts: $('darts').checked,
    symmetry: $('symmetry').value,
    mirror_sketch: $('mirror-sketch').checked,
    strokes: state.strokes.map((stroke) => stroke.points),
    grain_strokes: state.grainStrokes.map((stroke) => stroke.points),
  };
  if ($('fabric').value) options.fabric = $('fabric').value.split(',').map(Number);
  return options;
}

let polling = null;
async function startRun(refine = false) {
  if (!state.garment) return;
  state.refining = refine === true;
  document.body.dataset.refining = state.refining ? '1' : '';
  try {
    const answer = await api('POST', `/api/garments/${state.garment.id}/run`, runOptions(state.refining));
    state.run = answer.run;
    $('cancel').disabled = false;
    $('progress-text').style.color = '';
    if (!polling) poll();
  } catch (error) {
    showError(error.message);
  }
}

async function poll() {
  polling = true;
  try {
    const status = await api('GET', `/api/garments/${state.garment.id}/status`);
    $('progress-bar').style.width = `${Math.round(100 * status.fraction)}%`;
    if (status.run === state.run && status.state !== 'running') {
      polling = null;
      $('cancel').disabled = true;
      if (status.state === 'done') {
        await showResult(status.ms);
        // The quick layout is shown; with "fewest pieces" ticked, its consolidated run follows.
        if (!state.refining && $('consolidate').checked) await startRun(true);
        else state.refining = false, document.body.dataset.refining = '';
      } else if (status.state === 'failed') showError(status.error);
      else $('progress-text').textContent = 'cancelled';
      return;
    }
    $('progress-text').textContent = `run ${status.run}: ${status.stage} ${status.message}`.slice(0, 90);
  } catch (error) {
    showError(error.message);
  }
  setTimeout(poll, 120);
}

async function showResult(ms) {
  const result = await api('GET', `/api/garments/${state.garment.id}/result`);
  state.result = result;
  showGarment(result.garment, result.face_panel, result.seams);
  drawPattern(result);
  const verdict = result.verdict;
  $('verdict').textContent = `${result.panel_count} pieces · worst strain ${(100 * verdict.worst_strain).toFixed(2)}%` +
    ` (S ${(100 * verdict.max_strain).toFixed(1)}%) · ` +
    (verdict.goals_met ? 'goals met' : `goals missed: ${verdict.reasons}`.slice(0, 160));
  $('verdict').className = verdict.goals_met ? 'met' : 'missed';
  $('progress-text').textContent = `run ${result.run}: ${result.panel_count} pieces in ${(ms / 1000).toFixed(2)} s`;
  for (const link of document.querySelectorAll('#downloads a')) {
    link.href = `/api/garments/${state.garment.id}/files/${link.dataset.file}`;
    link.download = `${state.garment.name.replace(/\.[^.]*$/, '')}-${link.dataset.file}`;
    link.classList.remove('disabled');
  }
  state.shownRun = result.run;
  document.body.dataset.run = String(result.run);
  document.body.dataset.pieces = String(result.panel_count);
}

// ---------------------------------------------------------------- the pattern view

const pattern = $('pattern');
let patternBox = null;

function drawPatternViewBox() {
  if (!patternBox) return;
  const [x0, y0, x1, y1] = patternBox, margin = 0.03 * Math.max(x1 - x0, y1 - y0);
  pattern.setAttribute('viewBox', `${x0 - margin} ${-y1 - margin} ${x1 - x0 + 2 * margin} ${y1 - y0 + 2 * margin}`);
}

// Strain s relative to S: green (none) through yellow (S/2) to red (S and over).
function strainColour(strain, limit) {
  const t = Math.min(1, strain / Math.max(limit, 1e-9));
  return `hsl(${Math.round(120 * (1 - t))}, 70%, ${Math.round(62 - 10 * t)}%)`;
}

function element(name, attributes, parent) {
  const node = document.createElementNS(SVG, name);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  if (parent) parent.appendChild(node);
  return node;
}

function points2d(flat) {
  let text = '';
  for (let i = 0; i + 1 < flat.length; i += 2) text += `${flat[i]},${-flat[i + 1]} `;
  return text;
}

function drawPattern(result) {
  pattern.replaceChildren();
  $('tooltip').hidden = true;
  const uv = result.pattern.uv, faces = result.pattern.faces, strain = result.pattern.strain;
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  for (let i = 0; i < uv.length; i += 2) {
    x0 = Math.min(x0, uv[i]); x1 = Math.max(x1, uv[i]); y0 = Math.min(y0, uv[i + 1]); y1 = Math.max(y1, uv[i + 1]);
  }
  patternBox = [x0, y0, x1, y1];
  drawPatternViewBox();
  // The strain map: triangles grouped by colour step into one path each (a few paths, not thousands of nodes).
  const steps = 12, paths = Array.from({ length: steps + 1 }, () => []);
  for (let f = 0; f < faces.length / 3; ++f) {
    const step = Math.round(steps * Math.min(1, strain[f] / result.verdict.max_strain));
    const a = faces[3 * f], b = faces[3 * f + 1], c = faces[3 * f + 2];
    paths[step].push(`M${uv[2 * a]},${-uv[2 * a + 1]}L${uv[2 * b]},${-uv[2 * b + 1]}L${uv[2 * c]},${-uv[2 * c + 1]}Z`);
  }
  const strainGroup = element('g', { class: 'strain' }, pattern);
  paths.forEach((list, step) => {
    if (!list.length) return;
    const colour = strainColour(step / steps, 1);
    element('path', { d: list.join(''), fill: colour, stroke: colour, 'stroke-width': 0.3 }, strainGroup);
  });
  // Seams and darts: both sides, numbered as in the result (data-seam).
  const nearStroke = seamsNearStrokes(result);
  result.seams.forEach((seam, index) => {
    for (const side of [seam.uv_a, seam.uv_b])
      element('polyline', { points: points2d(side), 'data-seam': index,
        class: `seam ${seam.kind === 'dart' ? 'dart' : ''} ${nearStroke.has(index) ? 'stroked' : ''}` }, pattern);
  });
  // The pieces' outlines on top: hover shows name, size, strain and verdict.
  for (const piece of result.pieces) {
    const outline = element('polygon', { points: points2d(piece.outline), class: 'piece', 'data-panel': piece.panel,
      'data-name': piece.name }, pattern);
    outline.addEventListener('mousemove', (event) => showTooltip(event, piece));
    outline.addEventListener('mouseleave', () => { $('tooltip').hidden = true; });
  }
}

function showTooltip(event, piece) {
  const tip = $('tooltip'), box = $('view2d').getBoundingClientRect();
  tip.textContent = `${piece.name}${piece.mirrored ? ' (mirror image)' : ''}\n` +
    `${Math.round(piece.width_mm)} × ${Math.round(piece.height_mm)} mm, ${(piece.area_mm2 / 1e4).toFixed(1)} dm²\n` +
    `worst strain ${(100 * piece.strain).toFixed(2)}%, ${piece.corners} corners\n` +
    (piece.grain_turn_deg ? `grain turned ${piece.grain_turn_deg.toFixed(1)}° (a grain stroke)\n` : '') +
    (piece.goals_met ? 'goals met' : piece.problems);
  tip.style.left = `${event.clientX - box.left + 14}px`;
  tip.style.top = `${event.clientY - box.top + 14}px`;
  tip.hidden = false;
}

// The seams that run along a stroke: most of the stroke's points within 2 mean edges of the seam.
function seamsNearStrokes(result) {
  const near = new Set();
  if (!state.garment) return near;
  const reach = 2 * state.garment.mean_edge_mm;
  for (const stroke of state.strokes)
    result.seams.forEach((seam, index) => {
      let close = 0;
      for (const p of stroke.points)
        if (distanceToPolyline(p, seam.points) <= reach) ++close;
      if (close >= 0.5 * stroke.points.length) near.add(index);
    });
  return near;
}

function distanceToPolyline(p, flat) {
  let best = Infinity;
  const a = new THREE.Vector3(), b = new THREE.Vector3(), q = new THREE.Vector3(...p), line = new THREE.Line3();
  const closest = new THREE.Vector3();
  for (let i = 0; i + 5 < flat.length; i += 3) {
    a.set(flat[i], flat[i + 1], flat[i + 2]); b.set(flat[i + 3], flat[i + 4], flat[i + 5]);
    line.set(a, b).closestPointToPoint(q, true, closest);
    best = Math.min(best, closest.distanceTo(q));
  }
  return best;
}
window.studio.distanceToPolyline = distanceToPolyline;

// ---------------------------------------------------------------- garments

async function openGarment(garment) {
  const full = await api('GET', `/api/garments/${garment.id}`);
  state.garment = full;
  state.strokes = [];
  state.grainStrokes = [];
  state.result = null;
  drawStrokes();
  $('garment-name').textContent = `${full.name}: ${full.faces} faces`;
  showGarment(full.mesh, null, null);
  frameGarment();
  pattern.replaceChildren();
  await startRun();
}

$('open').addEventListener('click', async () => {
  try {
    await openGarment(await api('POST', '/api/garments', { path: $('path').value }));
  } catch (error) {
    showError(error.message);
  }
});
$('upload').addEventListener('change', async () => {
  const file = $('upload').files[0];
  if (!file) return;
  try {
    const name = file.name.replace(/[^A-Za-z0-9._-]/g, '_');
    await openGarment(await api('POST', `/api/garments/upload?name=${encodeURIComponent(name)}`,
      await file.arrayBuffer(), 'application/octet-stream'));
  } catch (error) {
    showError(error.message);
  }
});
$('run').addEventListener('click', startRun);
$('cancel').addEventListener('click', () => api('POST', `/api/garments/${state.garment.id}/cancel`, {}));
for (const id of ['max-strain', 'max-corners', 'max-pieces', 'darts', 'consolidate', 'mirror-sketch', 'symmetry', 'fabric'])
  $(id).addEventListener('change', startRun);
for (const mode of ['orbit', 'draw', 'grain', 'erase']) $(`mode-${mode}`).addEventListener('click', () => setMode(mode));

async function start() {
  resize();
  setMode('orbit');
  animate();
  const list = await api('GET', '/api/garments');
  if (list.garments.length) await openGarment(list.garments[list.garments.length - 1]);
  else $('progress-text').textContent = 'open a garment';
  document.body.dataset.ready = '1';
}
start().catch((error) => showError(error.message));
