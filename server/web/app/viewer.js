// A 3D view of a glTF file of region surfaces (a job's surfaces.glb, or a
// project's structures from /api/surfaces): orbit with the mouse, click a
// surface to pick its region; a result's final displacement shown as a
// deformation and as colour, a structure's own colour otherwise; a second
// file drawn over the first (two revisions of a structure).
import * as THREE from '/vendor/three.module.js';
import {OrbitControls} from '/vendor/OrbitControls.js';
import {GLTFLoader} from '/vendor/GLTFLoader.js';

// Viridis, sampled: blue-purple (no displacement) to yellow (the largest).
const kColours = [[0.267, 0.005, 0.329], [0.231, 0.322, 0.545], [0.129, 0.569, 0.549],
                  [0.369, 0.788, 0.384], [0.993, 0.906, 0.144]];

function colourOf(t) {
  const x = Math.min(Math.max(t, 0), 1) * (kColours.length - 1);
  const i = Math.min(Math.floor(x), kColours.length - 2), f = x - i;
  return kColours[i].map((c, k) => c + f * (kColours[i + 1][k] - c));
}

// Fetches `url` and parses it as glTF: the scene and the bytes fetched.
// An error names the server's reason.
async function fetchGltf(url) {
  const response = await fetch(url);
  if (!response.ok) {
    let message = response.statusText;
    try { message = (await response.json()).message || message; } catch (e) { /* not JSON */ }
    throw new Error(message);
  }
  const buffer = await response.arrayBuffer();
  // (three.js r111, Debian's: no parseAsync yet.)
  const gltf = await new Promise((resolve, reject) => {
    new GLTFLoader().parse(buffer, '', resolve, reject);
  });
  // three.js makes node names fit its animation paths ("Corpus callosum"
  // becomes "Corpus_callosum"); each node's extras keep its region's
  // index, by which the file's own name is found again.
  const named = {};
  for (const node of gltf.parser.json.nodes || []) {
    if (node.extras && node.extras.region !== undefined) named[node.extras.region] = node.name;
  }
  gltf.scene.traverse((o) => {
    if (o.isMesh && o.userData && named[o.userData.region] !== undefined) {
      o.name = named[o.userData.region];
    }
  });
  return {gltf, bytes: buffer.byteLength};
}

export class Viewer {
  // `onPick(name)` is told the region clicked ('' for none).
  constructor(element, onPick) {
    this.element = element;
    this.onPick = onPick;
    this.renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
    this.renderer.setPixelRatio(window.devicePixelRatio);
    this.renderer.localClippingEnabled = true;
    // The section plane: x = const, off until asked for.
    this.section = new THREE.Plane(new THREE.Vector3(-1, 0, 0), 0);
    this.sectioned = false;
    element.append(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color(0xf4f4f4);
    this.camera = new THREE.PerspectiveCamera(40, 1, 1e-4, 10);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 0.9));
    const sun = new THREE.DirectionalLight(0xffffff, 0.6);
    sun.position.set(1, 2, 3);
    this.camera.add(sun);
    this.scene.add(this.camera);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener('change', () => this.render());
    this.renderer.domElement.addEventListener('click', (e) => this.pick(e));
    this.model = null;
    this.meshes = [];
    this.overlay = null;
    this.resize();
    window.addEventListener('resize', () => this.resize());
  }

  resize() {
    const width = this.element.clientWidth || 640, height = this.element.clientHeight || 480;
    this.renderer.setSize(width, height);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() { this.renderer.render(this.scene, this.camera); }

  // Loads `url`; resolves to what was drawn: region names, the largest
  // displacement [m] and the bytes fetched. When `current()` says no once
  // the file is in (another load was asked for meanwhile), nothing is
  // drawn and it resolves to null.
  async load(url, current = () => true) {
    const {gltf, bytes} = await fetchGltf(url);
    if (!current()) return null;
    if (this.model) this.scene.remove(this.model);
    if (this.overlay) this.scene.remove(this.overlay);
    this.overlay = null;
    this.model = gltf.scene;
    this.meshes = [];
    let largest = 0;
    this.model.traverse((o) => {
      if (!o.isMesh) return;
      this.meshes.push(o);
      const u = o.geometry.getAttribute('_displacement');
      if (!u) return;
      for (let i = 0; i < u.count; ++i) {
        largest = Math.max(largest, Math.hypot(u.getX(i), u.getY(i), u.getZ(i)));
      }
    });
    // The steps through time: their times, and the file of their
    // displacements, fetched when first asked for.
    const extras = (gltf.asset && gltf.asset.extras) || {};
    this.stepTimes = extras.step_times || [];
    this.stepsUrl = extras.step_file ? url.replace(/[^/]*$/, extras.step_file) : '';
    this.steps = null;
    this.vertices = extras.vertices || 0;
    // Values per vertex the file has besides the displacement (pressure,
    // strain: of the final state), by attribute, with their ranges.
    this.scalars = extras.scalars || {};
    this.colouring = '_displacement';
    for (const mesh of this.meshes) {
      const geometry = mesh.geometry;
      mesh.userData.reference = geometry.getAttribute('position').array.slice();
      const u = geometry.getAttribute('_displacement');
      if (!u) continue;
      mesh.material = mesh.material.clone();
      mesh.material.vertexColors = THREE.VertexColors !== undefined ? THREE.VertexColors : true;
      mesh.material.color = new THREE.Color(1, 1, 1);
      this.deform(mesh, u.array, 0, largest);
    }
    this.scene.add(this.model);
    const box = new THREE.Box3().setFromObject(this.model);
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3()).length() || 1;
    this.camera.near = size / 1000;
    this.camera.far = size * 100;
    this.camera.position.copy(centre).add(new THREE.Vector3(0.6, -1.2, 0.8).multiplyScalar(0.7 * size));
    this.camera.up.set(0, 0, 1);
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.render();
    return {regions: this.meshes.map((m) => m.name), largest_m: largest, bytes,
            scalars: this.scalars};
  }

  // Draws `url` over what is loaded, every surface as a mesh of lines of
  // `colour` (0xRRGGBB); the camera stays. Resolves to its region names
  // (null, drawing nothing, when `current()` says no once the file is in).
  async addOverlay(url, colour, current = () => true) {
    const {gltf, bytes} = await fetchGltf(url);
    if (!current()) return null;
    if (this.overlay) this.scene.remove(this.overlay);
    this.overlay = gltf.scene;
    const names = [];
    this.overlay.traverse((o) => {
      if (!o.isMesh) return;
      names.push(o.name);
      o.material = new THREE.MeshBasicMaterial({color: colour, wireframe: true});
      o.material.clippingPlanes = this.sectioned ? [this.section] : [];
    });
    this.scene.add(this.overlay);
    this.render();
    return {regions: names, bytes};
  }

  // The colour region `name` is drawn in (0..255 each), null without it.
  colourOf(name) {
    const mesh = this.meshes.find((m) => m.name === name);
    return mesh ? mesh.material.color.toArray().map((c) => Math.round(255 * c)) : null;
  }

  // Each region named in `colours` ({name: [r, g, b]}, 0..255 each) in its
  // colour, drawn once (software WebGL takes a while per frame).
  setColours(colours) {
    for (const mesh of this.meshes) {
      const rgb = colours[mesh.name];
      if (!rgb || mesh.geometry.getAttribute('_displacement')) continue;
      const colour = new THREE.Color(rgb[0] / 255, rgb[1] / 255, rgb[2] / 255);
      if (mesh.material.color.equals(colour)) continue;
      mesh.material = mesh.material.clone();
      mesh.material.color = colour;
    }
    this.render();
  }

  // Moves `mesh` to its reference plus `u` (x y z per vertex from `from`)
  // and paints it (by |u| / `scale`, or the chosen value).
  deform(mesh, u, from, scale) {
    const geometry = mesh.geometry, position = geometry.getAttribute('position');
    const reference = mesh.userData.reference;
    for (let i = 0; i < position.count; ++i) {
      const x = u[from + 3 * i], y = u[from + 3 * i + 1], z = u[from + 3 * i + 2];
      position.setXYZ(i, reference[3 * i] + x, reference[3 * i + 1] + y, reference[3 * i + 2] + z);
    }
    position.needsUpdate = true;
    geometry.computeVertexNormals();
    mesh.userData.shown = {u, from, scale};
    this.paint(mesh);
  }

  // Colours `mesh` by this.colouring: the displacement shown, or a value
  // of the file (its vertex attribute) over that value's whole range.
  paint(mesh) {
    const geometry = mesh.geometry, count = geometry.getAttribute('position').count;
    const shown = mesh.userData.shown;
    if (!shown) return;
    const colours = new Float32Array(3 * count);
    const values = this.colouring !== '_displacement' && geometry.getAttribute(this.colouring);
    const range = values && this.scalars[this.colouring.toUpperCase()];
    for (let i = 0; i < count; ++i) {
      let t = 0;
      if (range) {
        t = range.max > range.min ? (values.getX(i) - range.min) / (range.max - range.min) : 0;
      } else if (shown.scale > 0) {
        const at = shown.from + 3 * i;
        t = Math.hypot(shown.u[at], shown.u[at + 1], shown.u[at + 2]) / shown.scale;
      }
      colours.set(colourOf(t), 3 * i);
    }
    geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
    mesh.material.needsUpdate = true;
  }

  // Colours by `attribute`: '_displacement', or one of this.scalars
  // ('_PRESSURE', '_STRAIN'); resolves to its range, or null for the
  // displacement.
  setColouring(attribute) {
    this.colouring = attribute === '_displacement' ? attribute : attribute.toLowerCase();
    for (const mesh of this.meshes) this.paint(mesh);
    this.render();
    return attribute === '_displacement' ? null : this.scalars[attribute] || null;
  }

  // Shows step `k` (of stepTimes): resolves to its index, time and largest
  // displacement [m]; the colour scale is the largest over all steps.
  async setStep(k) {
    if (!this.steps) {
      const response = await fetch(this.stepsUrl);
      if (!response.ok) throw new Error('steps: ' + response.statusText);
      this.steps = new Float32Array(await response.arrayBuffer());
      this.stepsLargest = 0;
      for (let i = 0; i < this.steps.length; i += 3) {
        this.stepsLargest = Math.max(this.stepsLargest,
                                     Math.hypot(this.steps[i], this.steps[i + 1], this.steps[i + 2]));
      }
    }
    const per = 3 * this.vertices;
    if (this.steps.length !== per * this.stepTimes.length) throw new Error('steps: wrong size');
    let from = k * per, largest = 0;
    for (const mesh of this.meshes) {
      const count = mesh.geometry.getAttribute('position').count;
      for (let i = 0; i < 3 * count; i += 3) {
        largest = Math.max(largest, Math.hypot(this.steps[from + i], this.steps[from + i + 1],
                                               this.steps[from + i + 2]));
      }
      this.deform(mesh, this.steps, from, this.stepsLargest);
      from += 3 * count;
    }
    this.render();
    return {index: k, time: this.stepTimes[k], largest_m: largest};
  }

  // Shows or hides region `name`.
  setVisible(name, visible) {
    for (const mesh of this.meshes) if (mesh.name === name) mesh.visible = visible;
    this.render();
  }

  // Every region see-through (opacity below 1) or solid.
  setOpacity(opacity) {
    for (const mesh of this.meshes) {
      mesh.material.transparent = opacity < 1;
      mesh.material.opacity = opacity;
      mesh.material.depthWrite = opacity >= 1;
      mesh.material.needsUpdate = true;
    }
    this.render();
  }

  // Cuts the model at x = `fraction` of its extent (0..1) and keeps the
  // low side; null: no cut.
  setSection(fraction) {
    const box = new THREE.Box3().setFromObject(this.model);
    this.section.constant = box.min.x + fraction * (box.max.x - box.min.x);
    this.sectioned = fraction !== null;
    const cut = [...this.meshes];
    if (this.overlay) this.overlay.traverse((o) => { if (o.isMesh) cut.push(o); });
    for (const mesh of cut) {
      mesh.material.clippingPlanes = this.sectioned ? [this.section] : [];
      mesh.material.needsUpdate = true;
    }
    this.render();
  }

  // The regions drawn now.
  visibleRegions() { return this.meshes.filter((m) => m.visible).map((m) => m.name); }

  // The region under the pointer, by its name.
  pick(event) {
    const rect = this.renderer.domElement.getBoundingClientRect();
    const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
                                      -((event.clientY - rect.top) / rect.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(pointer, this.camera);
    const hit = ray.intersectObjects(this.meshes.filter((m) => m.visible), false).find(
        (h) => !this.sectioned || this.section.distanceToPoint(h.point) >= 0);
    const name = hit ? hit.object.name : '';
    if (this.onPick) this.onPick(name);
    return name;
  }
}

// The controls of a view: a box per region to show or hide it (in the
// element `ids.regions`), a see-through switch and a section plane at x.
// `changed()` is called after each change.
export function bindControls(viewer, regions, ids, changed = () => {}) {
  const list = document.getElementById(ids.regions);
  list.replaceChildren();
  for (const name of regions) {
    const item = document.createElement('label');
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = true;
    box.dataset.region = name;
    box.onchange = () => {
      viewer.setVisible(name, box.checked);
      changed();
    };
    item.append(box, ' ' + name);
    list.append(item);
  }
  const through = document.getElementById(ids.through);
  through.checked = false;
  through.onchange = () => viewer.setOpacity(through.checked ? 0.3 : 1);
  const section = document.getElementById(ids.section);
  const cut = document.getElementById(ids.cut);
  cut.checked = false;
  const apply = () => viewer.setSection(cut.checked ? Number(section.value) / 100 : null);
  cut.onchange = apply;
  section.oninput = apply;
}
