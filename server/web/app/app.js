// The PBA web view: sign-in, then the projects and the jobs. Every call
// goes to the server's JSON API, a gateway to its gRPC services, with this
// session's CSRF token; the session cookie is out of this script's reach.
import {api, link, setCsrf, show, signedIn} from '/app/api.js';
import {openProject} from '/app/project.js';
import {showJob, showJobs} from '/app/jobs.js';

async function start(session) {
  setCsrf(session.csrf);
  document.getElementById('who').textContent = session.user.name;
  show('sign-in', false);
  show('sign-out', true);
  show('home', true);
  const projects = await api('AtlasService/ListProjects');
  const list = document.getElementById('projects');
  list.replaceChildren();
  for (const p of projects.projects || []) {
    const item = document.createElement('li');
    item.append(link(p.name, () => openProject(p.name).catch((e) => {
      document.getElementById('action-error').textContent = e.message;
    })));
    list.append(item);
  }
  await showJobs();
  // A link to a job's page: /#job=ID.
  const linked = location.hash.match(/^#job=([A-Za-z0-9]+)$/);
  if (linked) {
    await showJob(linked[1]).catch((e) => {
      document.getElementById('job-error').textContent = e.message;
    });
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
  await start(json);
};

document.getElementById('sign-out').onclick = async () => {
  await fetch('/api/session', {method: 'DELETE'});
  location.reload();
};

// Already signed in (the cookie): straight to the projects.
const session = await fetch('/api/session');
if (session.ok) {
  await start(await session.json());
} else {
  show('sign-in', true);
}
// The jobs' progress, every two seconds.
setInterval(() => { if (signedIn()) showJobs().catch(() => {}); }, 2000);
