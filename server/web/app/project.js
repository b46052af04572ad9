// A project: its structures with their locks (redrawn at each of the
// project's events) and in 3D (atlas.js), a structure's history with the
// diff figures the server computes and two revisions overlaid, its colour
// edited through the metadata etag, and the snapshots with their tags.
import {api, button, cell, link, show} from '/app/api.js';
import {drawAtlas, onEvent, overlayRevisions, setStructures} from '/app/atlas.js';

let project = '';
let events = null;
let historyOf = '';  // the structure whose history is shown
// Lock ids of the locks this page took (only AcquireLock answers one).
const locks = {};

// Shows `name` and follows its events (server-sent, from the gRPC Watch).
export async function openProject(name) {
  project = name;
  if (events) events.close();
  events = new EventSource('/api/events?project=' + encodeURIComponent(project));
  events.onmessage = (message) => {
    showStructures().catch(() => {});
    showSnapshots().catch(() => {});
    if (historyOf) showHistory(historyOf).catch(() => {});
    try { onEvent(JSON.parse(message.data).kind); } catch (e) { /* not an event */ }
  };
  historyOf = '';
  show('history', false);
  await showStructures();
  await showSnapshots();
  const of = document.getElementById('atlas-of');
  of.value = '';
  of.onchange = () => drawAtlas(project, of.value).catch(() => {});
  // Not awaited: the first view of new shapes takes the server seconds
  // (it says so, and any error, beside the view).
  drawAtlas(project).catch(() => {});
}

function colourText(c) { return c ? [c.r || 0, c.g || 0, c.b || 0].join(',') : ''; }

export async function showStructures() {
  const listed = await api('AtlasService/ListStructures', {project});
  setStructures(project, listed.structures || []);
  document.getElementById('project-name').textContent = project;
  const body = document.querySelector('#structures tbody');
  body.replaceChildren();
  for (const s of listed.structures || []) {
    const row = body.insertRow();
    row.dataset.structure = s.name;
    row.insertCell().append(link(s.name, () => showHistory(s.name).catch((e) => {
      document.getElementById('action-error').textContent = e.message;
    })));
    cell(row, s.head);
    cell(row, s.lock ? s.lock.holder : '');
    const colour = row.insertCell();
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    const c = (s.metadata && s.metadata.colour) || {};
    swatch.dataset.rgb = colourText(c);
    swatch.title = colourText(c);
    colour.append(swatch, ' ' + colourText(c));
    const actions = row.insertCell();
    if (!s.lock || locks[s.name]) {
      actions.append(button(s.lock ? 'Release' : 'Lock', () => lockAction(s), 'action-error'));
    }
    actions.append(button('Colour', () => recolour(s), 'action-error'));
  }
  // Swatches take their colour from a data attribute (no inline styles:
  // the page's content security policy allows none).
  for (const swatch of body.querySelectorAll('.swatch')) {
    const [r, g, b] = swatch.dataset.rgb.split(',').map(Number);
    swatch.style.backgroundColor = 'rgb(' + r + ',' + g + ',' + b + ')';
  }
  show('project', true);
}

async function lockAction(s) {
  if (s.lock) {
    await api('AtlasService/ReleaseLock', {lock_id: locks[s.name]});
    delete locks[s.name];
  } else {
    const lock = await api('AtlasService/AcquireLock', {project, structure: s.name});
    locks[s.name] = lock.lock_id;
  }
  await showStructures();
}

// A new display colour through the metadata's etag: a change by someone
// else since the table was drawn is refused, not overwritten.
async function recolour(s) {
  const text = window.prompt('Colour of ' + s.name + ' (r,g,b, 0-255)', colourText(
      (s.metadata && s.metadata.colour) || {}));
  if (text === null) return;
  const [r, g, b] = text.split(',').map((v) => parseInt(v, 10));
  await api('AtlasService/UpdateMetadata', {
    project, structure: s.name, etag: s.metadata_etag, colour: {r, g, b},
    message: 'colour set in the web view',
  });
  await showStructures();
}

// A structure's revisions, newest first, each with what changed from its
// parent (volume, Dice, Hausdorff distance).
export async function showHistory(structure) {
  const listed = await api('AtlasService/ListRevisions', {project, structure, page_size: 50});
  historyOf = structure;
  document.getElementById('history-name').textContent = structure;
  const body = document.querySelector('#revisions tbody');
  body.replaceChildren();
  for (const r of listed.revisions || []) {
    const row = body.insertRow();
    row.dataset.revision = r.number;
    cell(row, r.number);
    cell(row, r.author);
    cell(row, r.kind);
    cell(row, r.message);
    const diff = row.insertCell();
    if (Number(r.parent) > 0) {
      diff.append(button('compare with ' + r.parent, async () => {
        const d = await api('AtlasService/DiffRevisions', {
          project, structure, from_revision: r.parent, to_revision: r.number});
        diff.replaceChildren(diffText(d));
      }, 'action-error'));
      if (r.kind !== 'metadata') {
        diff.append(' ', button('overlay on ' + r.parent, () => overlayRevisions(
            project, structure, Number(r.parent), Number(r.number)), 'action-error'));
      }
    }
  }
  show('history', true);
}

function diffText(d) {
  const parts = [];
  const shape = d.shape, contours = d.contours;
  const f = (x) => Number(x || 0).toPrecision(4);
  if (shape) {
    parts.push('volume ' + f(shape.from_volume_mm3) + ' → ' + f(shape.to_volume_mm3) + ' mm³');
    parts.push('Dice ' + f(shape.dice));
    parts.push('Hausdorff ' + f(shape.hausdorff_mm) + ' mm');
  } else if (contours) {
    parts.push('volume ' + f(contours.from_volume_mm3) + ' → ' + f(contours.to_volume_mm3) + ' mm³');
    parts.push('Hausdorff ' + f(contours.hausdorff_mm) + ' mm');
  }
  if (!d.geometry_changed) parts.push('geometry unchanged');
  if (d.from_colour || d.to_colour) {
    parts.push('colour ' + colourText(d.from_colour) + ' → ' + colourText(d.to_colour));
  }
  for (const m of d.material_changes || []) parts.push(m.parameter + ' ' + m.from + ' → ' + m.to);
  const span = document.createElement('span');
  span.className = 'diff';
  span.textContent = parts.join('; ');
  return span;
}

export async function showSnapshots() {
  const listed = await api('AtlasService/ListSnapshots', {project, page_size: 20});
  const body = document.querySelector('#snapshots tbody');
  body.replaceChildren();
  // The 3D view's choice: the heads or a snapshot.
  const of = document.getElementById('atlas-of');
  const chosen = of.value;
  of.replaceChildren(new Option('every structure at its head', ''));
  for (const s of listed.snapshots || []) {
    of.append(new Option('snapshot ' + s.id + (s.name ? ' (' + s.name + ')' : ''), String(s.id)));
  }
  of.value = [...of.options].some((o) => o.value === chosen) ? chosen : '';
  for (const s of listed.snapshots || []) {
    const row = body.insertRow();
    row.dataset.snapshot = s.id;
    cell(row, s.id);
    cell(row, s.name);
    cell(row, s.author);
    cell(row, (s.tags || []).join(', '));
    row.insertCell().append(button('Tag', async () => {
      const tag = window.prompt('Tag for snapshot ' + s.id);
      if (!tag) return;
      await api('AtlasService/TagSnapshot', {project, snapshot_id: s.id, tag});
      await showSnapshots();
    }, 'action-error'));
  }
}
