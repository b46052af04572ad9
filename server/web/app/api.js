// The JSON API (a gateway to the server's gRPC services) and small helpers
// the page's modules share.
let csrf = '';

export function setCsrf(value) { csrf = value; }
export function signedIn() { return csrf !== ''; }

// The gRPC call `name` ("Service/Method") with `body` as its request; its
// response, or an Error with the server's message.
export async function api(name, body = {}) {
  const response = await fetch('/api/v1/' + name, {
    method: 'POST',
    headers: {'Content-Type': 'application/json', 'X-PBA-CSRF': csrf},
    body: JSON.stringify(body),
  });
  const json = await response.json();
  if (!response.ok) throw new Error(json.message || response.statusText);
  return json;
}

export function show(id, visible) { document.getElementById(id).hidden = !visible; }

export function cell(row, text) {
  const td = row.insertCell();
  td.textContent = text === undefined || text === null ? '' : String(text);
  return td;
}

export function button(label, action, errorId) {
  const b = document.createElement('button');
  b.textContent = label;
  b.onclick = () => {
    document.getElementById(errorId).textContent = '';
    action().catch((e) => { document.getElementById(errorId).textContent = e.message; });
  };
  return b;
}

export function link(label, action) {
  const a = document.createElement('a');
  a.textContent = label;
  a.onclick = action;
  return a;
}
