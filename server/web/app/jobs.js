// The jobs: their list with live progress (a cancel for the unfinished),
// and a finished job's summary, files, surfaces in 3D and curves.
import {api, button, cell, link, show} from '/app/api.js';
import {Viewer, bindControls} from '/app/viewer.js';

let viewer = null;
let chart = null;

export async function showJobs() {
  const listed = await api('JobService/ListJobs', {page_size: 50});
  const body = document.querySelector('#jobs tbody');
  body.replaceChildren();
  for (const j of listed.jobs || []) {
    const row = body.insertRow();
    row.dataset.job = j.id;
    cell(row, j.id);
    cell(row, j.name);
    cell(row, j.state);
    cell(row, j.progress !== undefined ? Math.round(100 * j.progress) + ' %' : '');
    const action = row.insertCell();
    if (j.state === 'SUCCEEDED') {
      action.append(link('view', () => showJob(j.id).catch((e) => {
        document.getElementById('job-error').textContent = e.message;
      })));
    } else if (j.state === 'QUEUED' || j.state === 'RUNNING') {
      action.append(button('Cancel', async () => {
        await api('JobService/CancelJob', {id: j.id});
        await showJobs();
      }, 'job-error'));
    }
  }
}

// A finished job: its summary, its files, its surfaces in 3D, and its
// history.csv (or sensors.csv) plotted.
export async function showJob(id) {
  document.getElementById('job-error').textContent = '';
  const job = await api('JobService/GetJob', {id});
  history.replaceState(null, '', '#job=' + id);
  document.getElementById('job-name').textContent = job.name + ' (' + id + ')';
  showSummary(job.summary || {});
  const files = document.getElementById('job-files');
  files.replaceChildren();
  const names = [];
  for (const f of job.result_files || []) {
    names.push(f.name);
    const item = document.createElement('li');
    const a = document.createElement('a');
    a.href = '/api/jobs/' + id + '/files/' + f.name;
    a.textContent = f.name + ' (' + f.size_bytes + ' bytes)';
    item.append(a);
    files.append(item);
  }
  show('job', true);
  await plotCurves(id, names);
  if (!names.includes('surfaces.glb')) return;
  if (!viewer) {
    const picked = document.getElementById('picked');
    viewer = new Viewer(document.getElementById('view'), (name) => { picked.textContent = name; });
  }
  const drawn = await viewer.load('/api/jobs/' + id + '/files/surfaces.glb');
  drawn.drawn_at_ms = performance.now();  // the first frame is drawn (for timings)
  const legend = document.getElementById('legend');
  const displacementLegend = 'colour: displacement, 0 to ' +
      (1000 * drawn.largest_m).toPrecision(3) + ' mm (shown deformed, at the end)';
  legend.textContent = displacementLegend;
  // Colour by the displacement, or by a value of the final state.
  const colourBy = document.getElementById('colour-by');
  colourBy.replaceChildren(new Option('displacement', '_displacement'));
  for (const [attribute, s] of Object.entries(drawn.scalars || {})) {
    colourBy.append(new Option(s.label, attribute));
  }
  colourBy.value = '_displacement';
  show('colouring', colourBy.options.length > 1);
  colourBy.onchange = () => {
    const range = viewer.setColouring(colourBy.value);
    legend.textContent = range
        ? 'colour: ' + range.label + ', ' + Number(range.min).toPrecision(3) + ' to ' +
            Number(range.max).toPrecision(3) + (range.unit ? ' ' + range.unit : '') +
            ' (of the last step)'
        : displacementLegend;
    window.pbaView.colouring = colourBy.value;
  };
  window.pbaView = drawn;
  bindControls(viewer, drawn.regions,
               {regions: 'regions', through: 'see-through', cut: 'cut', section: 'section'},
               () => { window.pbaView.visible = viewer.visibleRegions(); });
  // A slider through the steps, when the result has them.
  const times = viewer.stepTimes;
  show('stepping', times.length > 1 && names.includes('surface_steps.bin'));
  const slider = document.getElementById('step');
  slider.max = String(Math.max(0, times.length - 1));
  slider.value = slider.max;
  const label = document.getElementById('step-label');
  label.textContent = times.length ? 'step ' + times.length + ' of ' + times.length : '';
  slider.oninput = async () => {
    const k = Number(slider.value);
    // Pressure and strain are the last step's: another step shows its own
    // displacement rather than colours of another time.
    if (k !== times.length - 1 && colourBy.value !== '_displacement') {
      colourBy.value = '_displacement';
      colourBy.onchange();
      legend.textContent += '; pressure and strain are of the last step only';
    }
    const step = await viewer.setStep(k);
    label.textContent = 'step ' + (k + 1) + ' of ' + times.length + ', t = ' +
        Number(step.time).toPrecision(4) + ' s, largest ' + (1000 * step.largest_m).toPrecision(3) +
        ' mm';
    window.pbaView.step = step;
  };
}

function showSummary(summary) {
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
}

// The CSV's columns: a header row of names, rows of numbers.
function parseCsv(text) {
  const lines = text.trim().split('\n');
  const names = lines[0].split(',').map((n) => n.replace(/^"|"$/g, ''));
  const rows = lines.slice(1).map((l) => l.split(',').map(Number));
  return {names, rows};
}

// history.csv: the magnitude of each force (columns "... x [N]", y, z)
// against time; sensors.csv: each sensor's pressure against time.
export function curvesOf(file, table) {
  const x = table.rows.map((r) => r[0]);
  const series = {};
  if (file === 'history.csv') {
    for (let c = 0; c + 2 < table.names.length; ++c) {
      const name = table.names[c];
      if (!name.endsWith(' x [N]')) continue;
      series[name.slice(0, -' x [N]'.length) + ' [N]'] =
          table.rows.map((r) => Math.hypot(r[c], r[c + 1], r[c + 2]));
    }
  } else {
    for (let c = 1; c < table.names.length; ++c) {
      if (table.names[c].includes('[Pa]')) series[table.names[c]] = table.rows.map((r) => r[c]);
    }
  }
  return {file, x_name: table.names[0], x, series};
}

async function plotCurves(id, names) {
  const file = names.includes('history.csv') ? 'history.csv'
                                             : names.includes('sensors.csv') ? 'sensors.csv' : '';
  show('curves', file !== '');
  if (chart) { chart.destroy(); chart = null; }
  if (!file) return;
  const response = await fetch('/api/jobs/' + id + '/files/' + file);
  if (!response.ok) throw new Error(file + ': ' + response.statusText);
  const curves = curvesOf(file, parseCsv(await response.text()));
  const palette = ['#1a5fb4', '#c01c28', '#26a269', '#e66100', '#613583', '#865e3c'];
  chart = new window.Chart(document.getElementById('curve'), {
    type: 'line',
    data: {
      datasets: Object.entries(curves.series).map(([name, values], i) => ({
        label: name, data: values.map((y, k) => ({x: curves.x[k], y})),
        borderColor: palette[i % palette.length], pointRadius: 2,
      })),
    },
    options: {
      animation: false,
      scales: {x: {type: 'linear', title: {display: true, text: curves.x_name}}},
    },
  });
  window.pbaChart = curves;
}
