// A project's structures in 3D: their surfaces as the server meshes them
// (/api/surfaces: the heads, a snapshot, or one revision), each in its
// colour; a structure picked shows its revision, author, lock holder and
// material, which an editor may change through the metadata etag; two
// revisions of one structure overlaid.
import {api, button, show} from '/app/api.js';
import {Viewer, bindControls} from '/app/viewer.js';

let viewer = null;
let project = '';
let structures = {};  // name -> the Structure of the last ListStructures
let showing = null;   // what is drawn: {snapshot} or {structure, from, to}
let picked = '';
let drawing = 0;     // the latest draw's number: an older one's answer is dropped
let redraw = null;   // a redraw waiting for the project's events to pause
let describing = 0;  // the latest description's number, as `drawing`

const kControls = {regions: 'atlas-regions', through: 'atlas-see-through', cut: 'atlas-cut',
                   section: 'atlas-section'};

function status(text) { document.getElementById('atlas-status').textContent = text; }

function rgbOf(s) {
  const c = (s && s.metadata && s.metadata.colour) || {};
  return [c.r || 0, c.g || 0, c.b || 0];
}

// The structures as ListStructures answered: colours follow at once, and
// the picked one's facts.
export function setStructures(name, list) {
  project = name;
  structures = {};
  for (const s of list) structures[s.name] = s;
  if (viewer && showing && showing.structure === undefined) recolour();
  // Not while someone types a material: their text would be lost.
  const field = document.getElementById('atlas-material');
  const editing = field && (document.activeElement === field ||
                            field.value !== field.dataset.original);
  if (picked && !editing) describe(picked).catch(() => {});
}

// Every structure drawn in its colour of the store.
function recolour() {
  const colours = {};
  for (const [name, s] of Object.entries(structures)) colours[name] = rgbOf(s);
  viewer.setColours(colours);
}

function ensureViewer() {
  if (!viewer) {
    viewer = new Viewer(document.getElementById('atlas-view'), (name) => {
      picked = name;
      window.pbaAtlas.picked = name;
      describe(name).catch((e) => { document.getElementById('atlas-error').textContent = e.message; });
    });
  }
  return viewer;
}

// Draws the project's structures: at their heads, or the members of
// `snapshot` (an id or a tag). Resolves once the first frame is drawn.
export async function drawAtlas(name, snapshot = '') {
  const mine = ++drawing;
  project = name;
  showing = {snapshot};
  picked = '';
  document.getElementById('atlas-error').textContent = '';
  document.getElementById('atlas-picked').replaceChildren();
  show('atlas', true);
  show('atlas-back', false);
  status('meshing the structures\u2019 surfaces\u2026');
  const started = performance.now();
  window.pbaAtlas = {project, snapshot, ready: false};
  const query = 'project=' + encodeURIComponent(project) +
      (snapshot ? '&snapshot=' + encodeURIComponent(snapshot) : '');
  let drawn;
  try {
    drawn = await ensureViewer().load('/api/surfaces?' + query, () => mine === drawing);
  } catch (e) {
    if (mine !== drawing) return;
    status('');
    document.getElementById('atlas-error').textContent = e.message;
    window.pbaAtlas.error = e.message;
    throw e;
  }
  // (Another draw began meanwhile: its answer is the one to show.)
  if (!drawn) return;
  recolour();
  const ms = performance.now() - started;
  status(drawn.regions.length + ' structures, ' + (drawn.bytes / 1e6).toFixed(2) + ' MB in ' +
         (ms / 1000).toFixed(2) + ' s' + (snapshot ? ' (snapshot ' + snapshot + ')' : ''));
  bindControls(viewer, drawn.regions, kControls, () => {
    window.pbaAtlas.visible = viewer.visibleRegions();
  });
  window.pbaAtlas = {project, snapshot, ready: true, regions: drawn.regions, bytes: drawn.bytes,
                     first_frame_ms: ms, drawn_at_ms: performance.now(), picked: '',
                     colourOf: (region) => viewer.colourOf(region)};
}

// Revision `from` of `structure` drawn solid (blue) and revision `to`
// over it as lines (red): where one reaches past the other.
export async function overlayRevisions(name, structure, from, to) {
  const mine = ++drawing;
  project = name;
  showing = {structure, from, to};
  picked = '';
  show('atlas', true);
  show('atlas-back', true);
  document.getElementById('atlas-error').textContent = '';
  document.getElementById('atlas-picked').replaceChildren();
  status('meshing revisions ' + from + ' and ' + to + ' of ' + structure + '\u2026');
  window.pbaAtlas = {project, structure, ready: false};
  const url = (r) => '/api/surfaces?project=' + encodeURIComponent(project) + '&structure=' +
      encodeURIComponent(structure) + '&revision=' + r;
  const v = ensureViewer();
  const current = () => mine === drawing;
  const base = await v.load(url(from), current);
  if (!base) return;
  v.setColours({[structure]: [61, 123, 217]});
  v.setOpacity(0.55);
  const over = await v.addOverlay(url(to), 0xd0303d, current);
  if (!over) return;
  status(structure + ': revision ' + from + ' solid blue, revision ' + to + ' red lines');
  bindControls(v, base.regions, kControls);
  window.pbaAtlas = {project, structure, from, to, ready: true,
                     bytes: base.bytes + over.bytes, overlay: over.regions};
}

// What is known of structure `name`: its head, author, lock holder and
// material, and a field to change the material (through the etag).
async function describe(name) {
  const mine = ++describing;
  const box = document.getElementById('atlas-picked');
  box.replaceChildren();
  if (!name) return;
  const s = structures[name];
  const facts = document.createElement('p');
  facts.className = 'picked-name';
  facts.textContent = name;
  box.append(facts);
  if (!s || (showing && showing.structure !== undefined)) return;
  const head = await api('AtlasService/GetRevision', {project, structure: name, revision: s.head});
  if (picked !== name || mine !== describing) return;  // another came first
  const line = (text) => {
    const p = document.createElement('p');
    p.textContent = text;
    box.append(p);
    return p;
  };
  line('revision ' + s.head + ' by ' + head.author + ' (' + head.kind + ': ' + head.message + ')');
  line(s.lock ? 'locked by ' + s.lock.holder : 'not locked').dataset.lock = s.lock ? s.lock.holder : '';
  const material = document.createElement('textarea');
  material.id = 'atlas-material';
  material.rows = 3;
  material.cols = 48;
  material.value = (s.metadata && s.metadata.material_json) || '';
  material.dataset.original = material.value;
  material.placeholder = '{"neo_hookean": {"shear_modulus_pa": 1000}}  (a JSON object)';
  const label = document.createElement('label');
  label.append('material ', material);
  box.append(label);
  box.append(button('Save material', async () => {
    await api('AtlasService/UpdateMetadata', {
      project, structure: name, etag: s.metadata_etag, material_json: material.value.trim(),
      message: 'material set in the web view',
    });
    material.dataset.original = material.value;
    status('material of ' + name + ' saved');
    window.pbaAtlas.saved = name;
  }, 'atlas-error'));
}

// After a project's event: a shape that changed is drawn again when the
// heads are shown (a colour alone is only recoloured), once the events
// pause for a second (an import creates many structures at once).
export function onEvent(kind) {
  if (!showing || showing.structure !== undefined || showing.snapshot) return;
  if (!['COMMITTED', 'REVERTED', 'STRUCTURE_CREATED'].includes(kind)) return;
  clearTimeout(redraw);
  redraw = setTimeout(() => {
    redraw = null;
    drawAtlas(project).catch(() => {});
  }, 1000);
}

document.getElementById('atlas-back').onclick = () => {
  drawAtlas(project).catch(() => {});
};
