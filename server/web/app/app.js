// The PBA web view: every call goes to the server's JSON API, a gateway to
// its gRPC services (POST /api/v1/SERVICE/METHOD with this session's CSRF
// token); the session cookie itself is out of this script's reach.
import {Viewer} from '/app/viewer.js';

let csrf = '';
let viewer = null;
// The shown project's changes as they happen (server-sent events).
let events = null;
let project = '';
// Lock ids of the locks this page took (only AcquireLock answers one).
const locks = {};

async function api(name, body = {}) {
  const response = await fetch('/api/v1/' + name, {
    method: 'POST',
    headers: {'Content-Type': 'application/json', 'X-PBA-CSRF': csrf},
    body: JSON.stringify(body),
  });
  const json = await response.json();
  if (!response.ok) throw new Error(json.message || response.statusText);
  return json;
}

function show(id, visible) { document.getElementById(id).hidden = !visible; }

function cell(row, text) {
  const td = row.insertCell();
  td.textContent = text === undefined ? '' : String(text);
  return td;
}

async function signedIn(session) {
  csrf = session.csrf;
  document.getElementById('who').textContent = session.user.name;
  show('sign-in', false);
  show('sign-out', true);
  show('home', true);
  await refresh();
}

async function refresh() {
  const projects = await api('AtlasService/ListProjects');
  const list = document.getElementById('projects');
  list.replaceChildren();
  for (const p of projects.projects || []) {
    const item = document.createElement('li');
    const link = document.createElement('a');
    link.textContent = p.name;
    link.onclick = () => { project = p.name; follow(); refresh(); };
    item.append(link);
    list.append(item);
  }
  if (project) await showProject();
  await showJobs();
}

// Locks and commits by others show as they happen: every event of the
// project redraws its table.
function follow() {
  if (events) events.close();
  events = new EventSource('/api/events?project=' + encodeURIComponent(project));
  events.onmessage = () => showProject().catch(() => {});
}

async function showProject() {
  const listed = await api('AtlasService/ListStructures', {project});
  document.getElementById('project-name').textContent = project;
  const body = document.querySelector('#structures tbody');
  body.replaceChildren();
  for (const s of listed.structures || []) {
    const row = body.insertRow();
    row.dataset.structure = s.name;
    cell(row, s.name);
    cell(row, s.head);
    cell(row, s.lock ? s.lock.holder : '');
    const action = row.insertCell();
    if (s.lock && !locks[s.name]) continue;
    const button = document.createElement('button');
    button.textContent = s.lock ? 'Release' : 'Lock';
    button.onclick = () => lockAction(s).catch(e => {
      document.getElementById('action-error').textContent = e.message;
    });
    action.append(button);
  }
  show('project', true);
}

async function lockAction(s) {
  document.getElementById('action-error').textContent = '';
  if (s.lock) {
    await api('AtlasService/ReleaseLock', {lock_id: locks[s.name]});
    delete locks[s.name];
  } else {
    const lock = await api('AtlasService/AcquireLock', {project, structure: s.name});
    locks[s.name] = lock.lock_id;
  }
  await showProject();
}

async function showJobs() {
  const listed = await api('JobService/ListJobs', {page_size: 50});
  const body = document.querySelector('#jobs tbody');
  body.replaceChildren();
  for (const j of listed.jobs || []) {
    const row = body.insertRow();
    cell(row, j.id);
    cell(row, j.name);
    cell(row, j.state);
    cell(row, j.progress !== undefined ? Math.round(100 * j.progress) + ' %' : '');
    const action = row.insertCell();
    if (j.state === 'SUCCEEDED') {
      const link = document.createElement('a');
      link.textContent = 'view';
      link.onclick = () => showJob(j.id).catch((e) => {
        document.getElementById('job-error').textContent = e.message;
      });
      action.append(link);
    }
  }
}

// A finished job: its summary, its files, and its surfaces in 3D.
async function showJob(id) {
  document.getElementById('job-error').textContent = '';
  const job = await api('JobService/GetJob', {id});
  document.getElementById('job-name').textContent = job.name + ' (' + id + ')';
  const summary = job.summary || {};
  const facts = document.getElementById('job-summary');
  facts.replaceChildren();
  const fact = (name, value) => {
    if (value === undefined) return;
    const item = document.createElement('li');
    item.textContent = name ? name + ': ' + value : value;
    facts.append(item);
  };
  const modelled = summary.modelled || {}, results = summary.results || {};
  fact('analysis', modelled.analysis);
  fact('', modelled.material);
  fact('elements', modelled.elements);
  fact('largest displacement [mm]', results.max_displacement_mm);
  const estimate = summary.error_estimate || {};
  fact('estimated error', estimate.estimated ? (100 * estimate.relative_error).toPrecision(3) + ' %'
                                             : estimate.note);
  const performance = summary.performance || {};
  fact('wall time [s]', performance.wall_time_s);
  for (const phase of performance.phases || []) fact('  ' + phase.phase + ' [s]', phase.seconds);
  const files = document.getElementById('job-files');
  files.replaceChildren();
  for (const f of job.result_files || []) {
    const item = document.createElement('li');
    const link = document.createElement('a');
    link.href = '/api/jobs/' + id + '/files/' + f.name;
    link.textContent = f.name + ' (' + f.size_bytes + ' bytes)';
    item.append(link);
    files.append(item);
  }
  show('job', true);
  const hasSurfaces = (job.result_files || []).some((f) => f.name === 'surfaces.glb');
  if (!hasSurfaces) return;
  if (!viewer) {
    viewer = new Viewer(document.getElementById('view'), document.getElementById('picked'));
  }
  const drawn = await viewer.load('/api/jobs/' + id + '/files/surfaces.glb');
  document.getElementById('view').dataset.regions = String(drawn.regions.length);
  document.getElementById('legend').textContent =
      'colour: displacement, 0 to ' + (1000 * drawn.largest_m).toPrecision(3) + ' mm (shown deformed)';
  window.pbaView = drawn;
}

document.getElementById('sign-in-form').onsubmit = async (event) => {
  event.preventDefault();
  const response = await fetch('/api/session', {
    method: 'POST',
    headers: {'Content-Type': 'application/json'},
    body: JSON.stringify({token: document.getElementById('token').value}),
  });
  const json = await response.json();
  if (!response.ok) {
    document.getElementById('sign-in-error').textContent = json.message;
    return;
  }
  document.getElementById('token').value = '';
  await signedIn(json);
};

document.getElementById('sign-out').onclick = async () => {
  await fetch('/api/session', {method: 'DELETE'});
  location.reload();
};

// Already signed in (the cookie): straight to the projects.
const session = await fetch('/api/session');
if (session.ok) {
  await signedIn(await session.json());
} else {
  show('sign-in', true);
}
// The jobs' progress, every two seconds.
setInterval(() => { if (csrf) showJobs().catch(() => {}); }, 2000);
