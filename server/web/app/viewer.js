// A 3D view of a glTF file of region surfaces (surfaces.glb, written by
// pba-solve): orbit with the mouse, click a surface to see its region,
// the final displacement shown as a deformation and as colour.
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

export class Viewer {
  constructor(element, label) {
    this.element = element;
    this.label = label;
    this.renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
    this.renderer.setPixelRatio(window.devicePixelRatio);
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

  // Loads `url`; resolves to what was drawn: region names and the largest
  // displacement [m].
  async load(url) {
    // (three.js r111, Debian's: no loadAsync yet.)
    const gltf = await new Promise((resolve, reject) => {
      new GLTFLoader().load(url, resolve, undefined, reject);
    });
    if (this.model) this.scene.remove(this.model);
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
    for (const mesh of this.meshes) {
      const geometry = mesh.geometry, u = geometry.getAttribute('_displacement');
      if (!u) continue;
      const position = geometry.getAttribute('position');
      const colours = new Float32Array(3 * position.count);
      for (let i = 0; i < position.count; ++i) {
        position.setXYZ(i, position.getX(i) + u.getX(i), position.getY(i) + u.getY(i),
                        position.getZ(i) + u.getZ(i));
        const magnitude = Math.hypot(u.getX(i), u.getY(i), u.getZ(i));
        colours.set(colourOf(largest > 0 ? magnitude / largest : 0), 3 * i);
      }
      position.needsUpdate = true;
      geometry.setAttribute('color', new THREE.BufferAttribute(colours, 3));
      geometry.computeVertexNormals();
      mesh.material = mesh.material.clone();
      mesh.material.vertexColors = THREE.VertexColors !== undefined ? THREE.VertexColors : true;
      mesh.material.color = new THREE.Color(1, 1, 1);
      mesh.material.needsUpdate = true;
    }
    this.scene.add(this.model);
    const box = new THREE.Box3().setFromObject(this.model);
    const centre = box.getCenter(new THREE.Vector3());
    const size = box.getSize(new THREE.Vector3()).length() || 1;
    this.camera.near = size / 1000;
    this.camera.far = size * 100;
    this.camera.position.copy(centre).add(new THREE.Vector3(0.6, -1.2, 0.8).multiplyScalar(size));
    this.camera.up.set(0, 0, 1);
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.render();
    return {regions: this.meshes.map((m) => m.name), largest_m: largest};
  }

  // The region under the pointer, by its name.
  pick(event) {
    const rect = this.renderer.domElement.getBoundingClientRect();
    const pointer = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
                                      -((event.clientY - rect.top) / rect.height) * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(pointer, this.camera);
    const hit = ray.intersectObjects(this.meshes, false)[0];
    this.label.textContent = hit ? hit.object.name : '';
    return hit ? hit.object.name : '';
  }
}
