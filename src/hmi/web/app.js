// The operator page: status events in (DRO, state, plots, tool), controls out (POST /api/…).
import { View3D } from './view3d.js';
import { Plots } from './plots.js';

const $ = (id) => document.getElementById(id);
const fmt = (v, d = 3) => (typeof v === 'number' ? v.toFixed(d) : '—');

let token = sessionStorage.getItem('cncore-token') || '';
const fromUrl = new URLSearchParams(location.hash.slice(1)).get('token');
if (fromUrl) { token = fromUrl; sessionStorage.setItem('cncore-token', token); }

let machine = null, program = null, programSerial = -1, programLines = [], errorLine = 0;
let machineSerial = 0;  // the server's count of travel changes since it started
let lastStatus = null, shownLine = -1, canControl = false;
let heightmapVersion = 0, heightmapFetching = false, heightmapFetchedAt = 0;
const view = new View3D($('view3d'));
const plots = new Plots();

// What the test (and an operator's console) can read: how the page keeps up with the stream.
const stats = window.hmiStats = { events: 0, eventsPerS: 0, lagMs: 0, maxLagMs: 0, programLoads: 0,
                                  heightmaps: 0 };
let rateCount = 0, rateStart = performance.now(), clockOffset = null;

async function post(name, body, contentType = 'application/json') {
  const headers = { 'Content-Type': contentType };
  if (token) headers.Authorization = 'Bearer ' + token;
  const res = await fetch('/api/' + name, { method: 'POST', headers,
      body: contentType === 'application/json' ? JSON.stringify(body || {}) : body });
  let reply = {};
  try { reply = await res.json(); } catch { reply = { ok: false, error: res.statusText }; }
  if (!reply.ok) showError(reply.error || ('HTTP ' + res.status));
  else if (name !== 'override' && name !== 'jog' && name !== 'jog-cancel') showError('');
  return reply;
}

function showError(text) {
  const e = $('error');
  e.hidden = !text;
  e.textContent = text;
}

// ---- program text: the lines around the one under the tool ----
function renderProgramText(center, cls) {
  const box = $('program-text');
  const lo = Math.max(1, center - 60), hi = Math.min(programLines.length, center + 60);
  const frag = document.createDocumentFragment();
  for (let n = lo; n <= hi; ++n) {
    const d = document.createElement('span');
    d.className = 'ln' + (n === center && cls ? ' ' + cls : '');
    d.dataset.line = n;
    d.textContent = programLines[n - 1] + '\n';
    frag.appendChild(d);
  }
  box.replaceChildren(frag);
  const cur = box.querySelector('.' + (cls || 'none'));
  if (cur) box.scrollTop = cur.offsetTop - box.clientHeight / 2;
}

async function loadProgram() {
  const res = await fetch('/api/program');
  program = await res.json();
  programLines = (program.text || '').split('\n');
  $('program-name').textContent = program.name || '';
  const [lo, hi] = view.setPath(program);
  view.setColorMode($('color-actual').checked ? 'actual' : 'programmed');
  $('legend-min').textContent = Math.round(lo);
  $('legend-max').textContent = Math.round(hi);
  errorLine = 0;
  shownLine = -1;
  renderProgramText(1, '');
  stats.programLoads++;
}

// ---- the cutting simulation's height map: fetched when its version changed, at most 2 a second ----
async function fetchHeightmap() {
  heightmapFetching = true;
  heightmapFetchedAt = performance.now();
  try {
    const res = await fetch('/api/heightmap');
    if (!res.ok) return;
    const buf = await res.arrayBuffer();
    // "CNCZMAP1", u32 nx, ny, f64 x0, y0, cell, then float32 heights (docs/hmi.md).
    const d = new DataView(buf);
    const nx = d.getUint32(8, true), ny = d.getUint32(12, true);
    view.setHeightmap({ version: Number(res.headers.get('X-Heightmap-Version')), nx, ny,
                        x0: d.getFloat64(16, true), y0: d.getFloat64(24, true),
                        cell: d.getFloat64(32, true), z: new Float32Array(buf, 40, nx * ny) });
    stats.heightmaps++;
  } finally {
    heightmapFetching = false;
  }
}

function maybeFetchHeightmap(version) {
  if (!version || version === heightmapVersion || heightmapFetching ||
      performance.now() - heightmapFetchedAt < 500) return;
  heightmapVersion = version;
  fetchHeightmap();
}

// ---- status ----
function updateDro(s) {
  const body = $('dro-body');
  if (!body.children.length) {
    for (const a of Object.keys(s.machine)) {
      const tr = document.createElement('tr');
      tr.innerHTML = `<td>${a.toUpperCase()}</td><td id="dro-${a}-work"></td>` +
          `<td id="dro-${a}-machine" class="small"></td><td id="dro-${a}-offset" class="small"></td>`;
      body.appendChild(tr);
    }
  }
  for (const a of Object.keys(s.machine)) {
    $(`dro-${a}-work`).textContent = fmt(s.work[a]);
    $(`dro-${a}-machine`).textContent = fmt(s.machine[a]);
    $(`dro-${a}-offset`).textContent = fmt(s.work_offset[a]);
  }
}

function onStatus(msg) {
  const s = msg.status;
  lastStatus = s;
  stats.events++;
  rateCount++;
  const now = performance.now();
  if (now - rateStart >= 1000) {
    stats.eventsPerS = rateCount * 1000 / (now - rateStart);
    rateCount = 0;
    rateStart = now;
  }
  // Lag: how much later than the first event's pace this one is handled (server clock vs page).
  const offset = now - s.t * 1000;
  if (clockOffset === null || offset < clockOffset) clockOffset = offset;
  stats.lagMs = offset - clockOffset;
  stats.maxLagMs = Math.max(stats.maxLagMs, stats.lagMs);

  const st = $('state');
  const label = s.state + (s.state === 'Hold' && !s.hold_complete ? ' …' : '');
  if (st.textContent !== label) { st.textContent = label; st.className = 'state ' + s.state; }
  $('alarm').textContent = s.alarm ? s.alarm + (s.alarm_line ? ` (line ${s.alarm_line})` : '') : '';
  updateDro(s);
  $('feed-actual').textContent = Math.round(s.feed_mm_min);
  $('feed-programmed').textContent = Math.round(s.programmed_feed_mm_min);
  $('ovr-feed').textContent = Math.round(s.feed_override_pct);
  $('ovr-rapid').textContent = Math.round(s.rapid_override_pct);
  $('spindle').textContent = (s.spindle_on ? 'on' : 'off') + `, S${Math.round(s.spindle_rpm)}`;
  $('tool').textContent = s.tool ? 'T' + s.tool : '—';
  $('line').textContent = s.line || '—';
  $('load').textContent = s.load_pct.toFixed(1);
  syncSlider('feed-override', s.feed_override_pct);
  syncSlider('rapid-override', s.rapid_override_pct);
  $('sw-optional-stop').checked = s.switches.optional_stop;
  $('sw-single-block').checked = s.switches.single_block;
  $('sw-block-delete').checked = s.switches.block_delete;
  if (msg.program_serial !== programSerial) {
    programSerial = msg.program_serial;
    loadProgram();
  } else if (!errorLine && s.line && s.line !== shownLine && programLines.length) {
    shownLine = s.line;
    renderProgramText(s.line, 'current');
  }
  for (const [, text] of msg.messages) {
    const d = document.createElement('div');
    d.textContent = text;
    $('messages').prepend(d);
    while ($('messages').children.length > 5) $('messages').lastChild.remove();
  }
  const [lo, hi] = view.feedRange || [0, 1];
  view.setTool([s.machine.x ?? 0, s.machine.y ?? 0, s.machine.z ?? 0], (s.feed_mm_min - lo) / (hi - lo));
  plots.push(s.t, s);
  maybeFetchHeightmap(msg.heightmap_version);
  if (msg.machine_serial !== machineSerial) {
    machineSerial = msg.machine_serial;
    fetch('/api/machine').then((r) => r.json()).then((m) => {
      machine = m;
      view.setTravel(m);
    });
  }
}

function syncSlider(id, value) {
  const el = $(id);
  if (document.activeElement === el && performance.now() - (el.lastInput || 0) < 1500) return;
  el.value = value;
  $(id + '-value').textContent = Math.round(value) + ' %';
}

function connect() {
  const es = new EventSource('/api/events');
  es.onopen = () => { $('link').textContent = 'live'; };
  es.onmessage = (e) => onStatus(JSON.parse(e.data));
  es.onerror = () => { $('link').textContent = 'reconnecting…'; };
}

// ---- controls ----
async function upload(file) {
  const text = await file.text();
  const reply = await post('program?name=' + encodeURIComponent(file.name), text, 'text/plain');
  if (reply.ok) return;
  // FILE:LINE:COL: error: MESSAGE — the uploaded text with its failing line marked.
  const m = /:(\d+):(\d+): error: (.*)$/s.exec(reply.error || '');
  if (!m) return;
  programLines = text.split('\n');
  errorLine = Number(m[1]);
  showError(`${file.name} line ${m[1]}, column ${m[2]}: ${m[3]}`);
  renderProgramText(errorLine, 'error-line');
}

function jogButtons() {
  const box = $('jog-buttons');
  for (const a of machine.axes) {
    for (const sign of [-1, 1]) {
      const b = document.createElement('button');
      b.textContent = a.name + (sign > 0 ? '+' : '−');
      b.id = `jog-${a.name.toLowerCase()}${sign > 0 ? 'p' : 'm'}`;
      b.addEventListener('pointerdown', () => jogStart(a.name.toLowerCase(), sign));
      b.addEventListener('pointerup', jogStop);
      b.addEventListener('pointerleave', jogStop);
      box.appendChild(b);
    }
  }
}

let jogging = false;
function jogStart(axis, sign) {
  const step = $('jog-step').value;
  if (step === 'cont') {
    jogging = true;
    post('jog', { mode: 'cont', axes: { [axis]: sign } });
  } else {
    post('jog', { mode: 'inc', axes: { [axis]: sign * Number(step) } });
  }
}
function jogStop() {
  if (!jogging) return;
  jogging = false;
  post('jog-cancel');
}

// Arrow keys jog X and Y, Page Up / Page Down jog Z (not while typing in a field).
const KEYS = { ArrowLeft: ['x', -1], ArrowRight: ['x', 1], ArrowDown: ['y', -1], ArrowUp: ['y', 1],
               PageUp: ['z', 1], PageDown: ['z', -1] };
document.addEventListener('keydown', (e) => {
  if (!canControl || e.repeat || !(e.key in KEYS) || e.target.matches('input, select')) return;
  e.preventDefault();
  jogStart(...KEYS[e.key]);
});
document.addEventListener('keyup', (e) => { if (e.key in KEYS) jogStop(); });

function wire() {
  $('upload-file').addEventListener('change', (e) => {
    if (e.target.files.length) upload(e.target.files[0]);
    e.target.value = '';
  });
  const simple = { start: 'btn-start', hold: 'btn-hold', resume: 'btn-resume', reset: 'btn-reset',
                   home: 'btn-home', unlock: 'btn-unlock', estop: 'btn-estop',
                   'reset-stock': 'btn-reset-stock' };
  for (const [name, id] of Object.entries(simple)) $(id).addEventListener('click', () => post(name));
  for (const [id, key] of [['feed-override', 'feed_pct'], ['rapid-override', 'rapid_pct']]) {
    const el = $(id);
    let timer = null;
    el.addEventListener('input', () => {
      el.lastInput = performance.now();
      $(id + '-value').textContent = el.value + ' %';
      clearTimeout(timer);
      timer = setTimeout(() => post('override', { [key]: Number(el.value) }), 60);
    });
  }
  const mdi = () => { if ($('mdi').value.trim()) post('mdi', { line: $('mdi').value }); };
  $('btn-mdi').addEventListener('click', mdi);
  $('mdi').addEventListener('keydown', (e) => { if (e.key === 'Enter') mdi(); });
  const sw = () => post('switches', { optional_stop: $('sw-optional-stop').checked,
                                      single_block: $('sw-single-block').checked,
                                      block_delete: $('sw-block-delete').checked });
  $('sw-optional-stop').addEventListener('change', sw);
  $('sw-single-block').addEventListener('change', sw);
  $('sw-block-delete').addEventListener('change', sw);
  for (const b of document.querySelectorAll('#view-buttons button')) {
    b.addEventListener('click', () => view.setView(b.dataset.view));
  }
  $('color-actual').addEventListener('change', (e) => {
    const actual = e.target.checked;
    view.setColorMode(actual ? 'actual' : 'programmed');
    $('legend-title').textContent = actual ? 'actual speed (trail), mm/min' : 'programmed feed, mm/min';
  });
  $('token-set').addEventListener('click', () => {
    token = $('token').value;
    sessionStorage.setItem('cncore-token', token);
    session();
  });
}

async function session() {
  const headers = token ? { Authorization: 'Bearer ' + token } : {};
  const s = await (await fetch('/api/session', { headers })).json();
  canControl = s.authorized;
  $('controls').disabled = !canControl;
  $('access').textContent = canControl ? '' : 'read-only: controls need the token';
  $('token-box').hidden = !s.token_required || canControl;
}

async function main() {
  machine = await (await fetch('/api/machine')).json();
  $('machine-name').textContent = machine.name;
  $('feed-override').max = machine.max_override_pct;
  plots.setMaxOverride(machine.max_override_pct);
  plots.setLoadTarget(machine.load_target_pct);
  $('btn-reset-stock').hidden = !machine.stock;
  view.setMachine(machine);
  jogButtons();
  wire();
  await session();
  connect();
}

window.hmi = { view, plots, stats, lastStatus: () => lastStatus };
main();
