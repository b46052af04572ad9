// The PBA web view: every call goes to the server's JSON API, a gateway to
// its gRPC services (POST /api/v1/SERVICE/METHOD with this session's CSRF
// token); the session cookie itself is out of this script's reach.
let csrf = '';
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
    link.onclick = () => { project = p.name; refresh(); };
    item.append(link);
    list.append(item);
  }
  if (project) await showProject();
  await showJobs();
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
  }
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
// Locks and commits by others show without reloading.
setInterval(() => { if (csrf) refresh().catch(() => {}); }, 2000);
