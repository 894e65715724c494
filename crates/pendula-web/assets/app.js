// pendula lab: the browser side of `pendula serve`. The physics runs on the server (see
// PROTOCOL.md); this script only draws what arrives and sends the user's commands.
'use strict';

// ======================================================================================
// helpers
// ======================================================================================

const $ = (id) => document.getElementById(id);
const DEG = 180 / Math.PI;
const HISTORY_MAX = 4000;   // per track; halved (every other point dropped) when reached
// The last bob's trail: the frames of the last TRAIL_TIME of simulated time (s, or the
// system's own time unit), at most TRAIL_MAX of them. Two frames further apart than TRAIL_GAP
// are not joined: at high speed a frame comes every speed/60 s, and a straight chord across
// a whole swing is no path the bob took (at speed 50 they scribbled over the picture); those
// frames are drawn as dots, each a state the bob really passed through.
const TRAIL_TIME = 3;
const TRAIL_MAX = 240;
const TRAIL_GAP = 0.1;
const POINCARE_MAX = 50000;
const FONT = '12px system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif';
const FONT_B = '600 13px system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif';
const RACE_COLOURS = ['#d62728', '#1f77b4', '#2ca02c', '#9467bd'];

// "1" is the library's unit of a dimensionless quantity: show nothing rather than a bare 1
const unitOf = (u) => (u && u !== '1' ? u : '');
const withUnit = (name, u) => (unitOf(u) ? `${name} (${unitOf(u)})` : name);
const isNum = (v) => typeof v === 'number' && Number.isFinite(v);

function fmt(v, digits = 5) {
  if (!isNum(v)) return v === null || v === undefined ? '–' : String(v);
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e-3 && a < 1e6) return String(Number(v.toPrecision(digits)));
  return v.toExponential(Math.max(1, digits - 3));
}

function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}

// Canvas backing store follows the CSS box × devicePixelRatio so lines stay sharp; drawing is
// done in CSS pixels. Returns null while the canvas is hidden (zero size).
function fitCanvas(canvas) {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (!w || !h) return null;
  const dpr = window.devicePixelRatio || 1;
  const bw = Math.round(w * dpr), bh = Math.round(h * dpr);
  if (canvas.width !== bw || canvas.height !== bh) { canvas.width = bw; canvas.height = bh; }
  const ctx = canvas.getContext('2d');
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  return { ctx, w, h };
}

// CSS-pixel point inside a canvas → client (viewport) coordinates, and back
function toClient(canvas, x, y) {
  const r = canvas.getBoundingClientRect();
  const sx = canvas.clientWidth ? r.width / canvas.clientWidth : 1;
  const sy = canvas.clientHeight ? r.height / canvas.clientHeight : 1;
  return { x: r.left + x * sx, y: r.top + y * sy };
}
function fromEvent(canvas, e) {
  const r = canvas.getBoundingClientRect();
  return {
    x: (e.clientX - r.left) * (canvas.clientWidth / (r.width || 1)),
    y: (e.clientY - r.top) * (canvas.clientHeight / (r.height || 1)),
  };
}

// ======================================================================================
// state
// ======================================================================================

const lab = window.lab = {
  connected: false,
  hello: null,
  config: null,
  framesReceived: 0,
  frame: null,
  energyHistory: [],
  stateHistory: [],
  separation: [],
  growth: null,                 // the server's last `growth` message (PROTOCOL.md)
  growthRate: null,
  fractal: null,
  fractalFrames: 0,
  errors: [],
  notices: [],
  socketAttempts: 0,
  gaveUp: false,
  send,
  bobClientPositions,
  fractalPixelClient,
  shareUrl,
  exportFigure,
  geometry: (id) => st.geometry[id] || null,
  get trail() {
    const spans = st.trails.map((tr) => (tr.length ? tr[tr.length - 1].t - tr[0].t : 0));
    return { spans, points: st.trails.map((tr) => tr.length), ...st.trailDrawn, gap: frameGap() };
  },
  // Every Poincaré point received since the last config: [track, x, y].
  get poincarePoints() { return st.poincarePts; },
};

const st = {
  ws: null,
  token: new URLSearchParams(location.search).get('token'),
  retries: 0,
  everOpened: false,
  view: 'view-sim',
  lastPictureView: 'view-sim',  // the PNG export pictures the last view other than Export
  controlsKey: '',
  graphKey: '',
  skipHashUpdates: 0,
  // history bookkeeping shared by all per-track arrays so they stay aligned in time
  histStride: 1,
  histCounter: 0,
  lastT: -Infinity,
  exportHistory: [],            // track 0: [t, ...state, K, V, energyError]
  sepTracks: [],                // butterfly: per track k ≥ 1, [t, |s_k − s_0|]
  growthFit: null,              // the server's fit, drawn: {slope, intercept, a, b, final}
  trails: [],                   // per track: [{x, y, t}], the last bob's positions
  trailDrawn: { segments: 0, dots: 0 },
  frameGaps: [],                // simulated time between the last frames
  geometry: {},                 // per canvas id: where its legend and its data were drawn
  exporting: false,             // drawing for the PNG: legends always, a scale and the time
  poincarePts: [],
  springRange: 0,
  drag: null,
  plotsDirty: true,
  lastPlotDraw: 0,
  fractalDirty: true,
  fractalImg: null,
  fractalReq: { size: 256, t_max: 100, theta1: [-Math.PI, Math.PI], theta2: [-Math.PI, Math.PI] },
  fdrag: null,
};

// ======================================================================================
// connection
// ======================================================================================

function setStatus(text, cls) {
  const s = $('status');
  s.textContent = text;
  s.className = 'status' + (cls ? ' ' + cls : '');
}

function send(obj) {
  if (!st.ws || st.ws.readyState !== WebSocket.OPEN) {
    showError('Not connected to the server: the command was not sent.');
    return false;
  }
  st.ws.send(JSON.stringify(obj));
  return true;
}

function connect() {
  if (!st.token) {
    setStatus('No access token in the address', 'bad');
    showError('This page needs the access token printed by `pendula serve`: open the full URL it prints (it ends in ?token=…).');
    return;
  }
  const proto = location.protocol === 'https:' ? 'wss' : 'ws';
  const ws = new WebSocket(`${proto}://${location.host}/ws?token=${encodeURIComponent(st.token)}`);
  ws.binaryType = 'arraybuffer';
  st.ws = ws;
  lab.socketAttempts++;
  setStatus('connecting…');
  let opened = false;
  ws.onopen = () => {
    opened = true;
    st.everOpened = true;
    st.retries = 0;
    lab.connected = true;
    setStatus('connected', 'ok');
  };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') {
      let msg;
      try { msg = JSON.parse(ev.data); } catch (err) { showError('Unreadable message from the server: ' + err.message); return; }
      handleMessage(msg);
    } else {
      const buf = ev.data;
      if (buf.byteLength % 8 !== 0 || buf.byteLength < 8) return;
      handleBinary(new Float64Array(buf));
    }
  };
  ws.onclose = async () => {
    lab.connected = false;
    st.ws = null;
    let why = 'disconnected';
    if (!opened) {
      // The browser hides the HTTP status of a refused upgrade: ask the same address plainly.
      const refusal = await whyRefused();
      if (refusal.fatal) {
        lab.gaveUp = true;
        const token = /token/.test(refusal.message);
        setStatus(token ? 'refused: wrong access token' : 'refused by the server', 'bad');
        showError(`The server refused this page: ${refusal.message}. ` +
          (token ? 'Open the URL that `pendula serve` printed in its terminal, token included (…/?token=…); each start of the server makes a new token. ' : '') +
          'This page does not retry.');
        return;
      }
      why = refusal.message;
    }
    const delay = Math.min(10, 1 + st.retries++ * 2);
    setStatus(`${why}: retrying in ${delay} s`, 'bad');
    setTimeout(connect, delay * 1000);
  };
}

// Why the WebSocket did not open, from a plain GET of its address (PROTOCOL.md): a wrong
// token (403) is fatal, as no retry can mend it; a full server (503) or no answer may pass.
async function whyRefused() {
  try {
    const r = await fetch(`/ws?token=${encodeURIComponent(st.token)}`, { cache: 'no-store' });
    const text = (await r.text()).trim().slice(0, 200);
    if (r.status === 403) return { fatal: true, message: text || 'HTTP 403' };
    if (r.status === 503) return { fatal: false, message: `the server is full: ${text}; close another lab page` };
    return { fatal: false, message: 'could not connect' };
  } catch (_) {
    return { fatal: false, message: 'the server does not answer (stopped?)' };
  }
}

function handleMessage(msg) {
  switch (msg.type) {
    case 'hello': onHello(msg); break;
    case 'config': onConfig(msg); break;
    case 'error':
      showError(`${msg.command ? msg.command + ' refused' : 'refused'}: ${msg.message}`, msg.message);
      onRefused(msg);
      break;
    case 'growth': onGrowth(msg); break;
    case 'run_failed':
      showError(`Run failed at t = ${fmt(msg.t)} ${timeUnit()}: ${msg.message}`);
      break;
    case 'fractal_done':
      $('fractal-info').textContent = `Done: ${msg.size}² in ${fmt(msg.seconds, 3)} s.` + fractalNote();
      break;
    default: break;
  }
}

function handleBinary(a) {
  if (a[0] === 1) onSimFrame(a);
  else if (a[0] === 2) onFractalFrame(a);
}

// The fragment holds the last accepted `share`; replaying it after hello reopens a shared or
// reloaded page where it was. Only configure's own fields go out: anything else is refused.
const CONFIGURE_FIELDS = ['system', 'params', 'state', 'method', 'dt', 'mode', 'methods', 'count', 'delta', 'speed', 'poincare'];
// Returns {share, problem}: the fields to send (or null), and what could not be read of a
// fragment that is there (or null), for the page to say rather than open the defaults silently.
function shareFromHash() {
  if (location.hash.length < 2) return { share: null, problem: null };
  let text, obj;
  try {
    text = decodeURIComponent(location.hash.slice(1));
  } catch (_) {
    return { share: null, problem: 'it is not URL-encoded text' };
  }
  try {
    obj = JSON.parse(text);
  } catch (err) {
    return { share: null, problem: `it is not JSON (${err.message})` };
  }
  if (!obj || typeof obj !== 'object' || Array.isArray(obj)) {
    return { share: null, problem: 'it is not a JSON object of settings' };
  }
  const out = {};
  for (const k of CONFIGURE_FIELDS) if (k in obj) out[k] = obj[k];
  const unknown = Object.keys(obj).filter((k) => !CONFIGURE_FIELDS.includes(k));
  const problem = unknown.length
    ? `unknown ${unknown.length > 1 ? 'fields' : 'field'} ${unknown.slice(0, 5).map((k) => JSON.stringify(k).slice(0, 40)).join(', ')}${unknown.length > 5 ? ', …' : ''} (known: ${CONFIGURE_FIELDS.join(', ')})`
    : null;
  return { share: Object.keys(out).length ? out : null, problem };
}

function onHello(msg) {
  lab.hello = msg;
  fillOptions($('system'), msg.systems.map((s) => [s.name, s.name, s.description]));
  fillOptions($('method'), msg.methods.map((m) => [m.name, `${m.title || m.name} (order ${m.order})`, m.name]));
  fillOptions($('fractal-method'), (msg.fractal_methods || ['rk4']).map((m) => [m, m, m]));
  const race = $('race-methods');
  race.textContent = '';
  for (const m of msg.methods) {
    const lbl = el('label');
    lbl.title = `${m.title || m.name}, order ${m.order}`;
    const cb = el('input');
    cb.type = 'checkbox';
    cb.value = m.name;
    cb.addEventListener('change', onRaceChange);
    lbl.append(cb, document.createTextNode(m.name));
    race.append(lbl);
  }
  const lim = msg.limits || {};
  if (isNum(lim.max_speed)) $('speed').max = lim.max_speed;
  if (isNum(lim.max_tracks)) $('count').max = Math.min(16, lim.max_tracks);
  if (isNum(lim.max_fractal_size)) $('fractal-size').max = lim.max_fractal_size;
  if (isNum(lim.max_t_max)) $('fractal-tmax').max = lim.max_t_max;
  const { share, problem } = shareFromHash();
  if (problem) {
    showNotice(share
      ? `Some of this link's settings (the part of the address after #) were ignored: ${problem}. The others were applied.`
      : `This link's settings (the part of the address after #) could not be read: ${problem}. The lab opened with its defaults.`);
  }
  if (share) {
    // the connect-time config (defaults) arrives before the answer to this: keep the hash
    st.skipHashUpdates = 1;
    send(Object.assign({ cmd: 'configure' }, share));
  }
}

function fillOptions(select, items) {
  const keep = select.value;
  select.textContent = '';
  for (const [value, text, title] of items) {
    const o = el('option', null, text);
    o.value = value;
    if (title) o.title = title;
    select.append(o);
  }
  if (items.some((i) => i[0] === keep)) select.value = keep;
}

function onConfig(cfg) {
  lab.config = cfg;
  st.drag = null;
  $('sim-canvas').classList.remove('dragging');
  resetHistories(cfg.tracks ? cfg.tracks.length : 1);
  applyConfig(cfg);
  // the server accepted the change but had to alter something (e.g. a method the new system
  // refuses): say so where refusals appear
  if (cfg.notice) showNotice(cfg.notice);
  if (st.skipHashUpdates > 0) st.skipHashUpdates--;
  else history.replaceState(null, '', '#' + encodeURIComponent(JSON.stringify(cfg.share)));
  $('share-link').value = shareUrl();
}

// A refused command changes nothing on the server: put the controls back to what it runs.
function onRefused(msg) {
  if (msg.command === 'set_state') st.drag = null;
  if (msg.command === 'speed' && lab.config && isNum(st.speedBefore)) {
    lab.config.speed = st.speedBefore;
    if (lab.config.share) lab.config.share.speed = st.speedBefore;
    $('speed').value = st.speedBefore;
  }
  if (msg.command === 'fractal') $('fractal-info').textContent = 'The fractal was refused: see the message above.';
  if (lab.config && (msg.command === 'configure' || msg.command === 'set_state' || msg.command === null)) applyConfig(lab.config);
}

// ======================================================================================
// state: frames and histories
// ======================================================================================

function resetHistories(K) {
  lab.energyHistory = Array.from({ length: K }, () => []);
  lab.stateHistory = [];
  lab.separation = [];
  setGrowth(null);
  st.exportHistory = [];
  st.sepTracks = Array.from({ length: K }, () => []);
  st.trails = Array.from({ length: K }, () => []);
  st.poincarePts = [];
  st.histStride = 1;
  st.histCounter = 0;
  st.lastT = -Infinity;
  st.frameGaps = [];
  st.springRange = 0;
  st.plotsDirty = true;
}

// The butterfly's growth rate is measured by the server with the library's rule, on every
// step of pendulums 0 and 1 (PROTOCOL.md, `growth`): the page shows it and draws its line.
function onGrowth(msg) {
  if (lab.config && lab.config.mode === 'butterfly') setGrowth(msg);
}

function setGrowth(msg) {
  lab.growth = msg;
  lab.growthRate = msg && isNum(msg.rate) ? msg.rate : null;
  st.growthFit = lab.growthRate === null ? null
    : { slope: msg.rate, intercept: msg.intercept, a: msg.t_start, b: msg.t_end, final: msg.final };
  st.plotsDirty = true;
}

function onSimFrame(a) {
  const K = a[3], D = a[4];
  let o = 7;
  const tracks = [];
  for (let k = 0; k < K; k++) {
    const state = Array.from(a.subarray(o, o + D));
    o += D;
    tracks.push({ state, kinetic: a[o], potential: a[o + 1], energyError: a[o + 2], flipTime: a[o + 3] });
    o += 4;
  }
  const P = o < a.length ? a[o++] : 0;
  const poincare = [];
  for (let p = 0; p < P && o + 2 < a.length; p++, o += 3) poincare.push([a[o], a[o + 1], a[o + 2]]);
  const frame = { seq: a[1], t: a[2], paused: a[5] === 1, steps: a[6], tracks, poincare };
  const before = lab.frame;
  lab.frame = frame;
  // A pause or a play changes the controls and the info line even when the time does not
  // (the paused frame repeats the last instant, which record() skips).
  if (!before || before.paused !== frame.paused) st.plotsDirty = true;
  lab.framesReceived++;
  record(frame);
}

function halve(arr) {
  let j = 0;
  for (let i = 0; i < arr.length; i += 2) arr[j++] = arr[i];
  arr.length = j;
}

function record(f) {
  const K = f.tracks.length;
  // a frame of the previous system, still in flight when its config was replaced
  if (lab.config && f.tracks[0] && f.tracks[0].state.length !== lab.config.state.length) return;
  // a reset (or any restart we were not told about) shows up as time going backwards; a
  // growth fit of the new run (sent just before this frame, at its time) is kept
  if (K !== lab.energyHistory.length || f.t < st.lastT) {
    const growth = lab.growth && lab.growth.t <= f.t ? lab.growth : null;
    resetHistories(K);
    if (growth) setGrowth(growth);
  }
  for (const p of f.poincare) st.poincarePts.push(p);
  if (st.poincarePts.length > POINCARE_MAX) st.poincarePts.splice(0, st.poincarePts.length - POINCARE_MAX);
  if (f.poincare.length) st.plotsDirty = true;
  if (f.t === st.lastT) return;  // paused: the same instant again
  if (Number.isFinite(st.lastT)) {
    st.frameGaps.push(f.t - st.lastT);
    if (st.frameGaps.length > 9) st.frameGaps.shift();
  }
  st.lastT = f.t;

  const rods = lab.config && lab.config.drawing && lab.config.drawing.kind === 'rods' ? lab.config.drawing.rods : null;
  for (let k = 0; k < K; k++) {
    const s = f.tracks[k].state;
    if (rods) {
      const pts = rodPoints(s, rods), tr = st.trails[k];
      tr.push({ ...pts[pts.length - 1], t: f.t });
      let drop = 0;
      while (drop < tr.length - 1 && (f.t - tr[drop].t > TRAIL_TIME || tr.length - drop > TRAIL_MAX)) drop++;
      if (drop) tr.splice(0, drop);
    } else if (lab.config && lab.config.drawing) {
      st.springRange = Math.max(st.springRange, Math.abs(s[lab.config.drawing.x] || 0));
    }
  }

  // store every histStride-th new instant; doubling the stride at each halving keeps the
  // stored points evenly spaced in time
  if (st.histCounter++ % st.histStride !== 0) return;
  const t = f.t, t0 = f.tracks[0];
  for (let k = 0; k < K; k++) lab.energyHistory[k].push([t, f.tracks[k].energyError]);
  lab.stateHistory.push([t, ...t0.state]);
  st.exportHistory.push([t, ...t0.state, t0.kinetic, t0.potential, t0.energyError]);
  if (lab.config && lab.config.mode === 'butterfly' && K > 1) {
    let max = 0;
    for (let k = 1; k < K; k++) {
      const s = f.tracks[k].state;
      let d2 = 0;
      for (let i = 0; i < s.length; i++) d2 += (s[i] - t0.state[i]) ** 2;
      const d = Math.sqrt(d2);
      st.sepTracks[k].push([t, d]);
      if (d > max) max = d;
    }
    lab.separation.push([t, max]);
  }
  if (lab.stateHistory.length >= HISTORY_MAX) {
    lab.energyHistory.forEach(halve);
    st.sepTracks.forEach(halve);
    halve(lab.stateHistory);
    halve(st.exportHistory);
    halve(lab.separation);
    st.histStride *= 2;
  }
  st.plotsDirty = true;
}

// ======================================================================================
// drawing: the pendulum
// ======================================================================================

const timeUnit = () => (lab.config ? lab.config.time_unit : 's');
const energyUnit = () => (lab.config ? lab.config.energy_unit : 'J');

function trackColour(k, K) {
  const mode = lab.config ? lab.config.mode : 'single';
  if (mode === 'butterfly') return `hsl(${Math.round((k / Math.max(1, K)) * 300)}, 75%, 42%)`;
  if (mode === 'race') return RACE_COLOURS[k % RACE_COLOURS.length];
  return '#1f5fbf';
}

function trackLabel(k) {
  const cfg = lab.config;
  if (!cfg) return '';
  if (cfg.mode === 'race') return (cfg.tracks && cfg.tracks[k] && cfg.tracks[k].method) || (cfg.methods && cfg.methods[k]) || `track ${k}`;
  if (cfg.mode === 'butterfly') return `k=${k}`;
  return cfg.method;
}

function rodPoints(state, rods) {
  let x = 0, y = 0;
  const pts = [{ x, y }];
  for (const r of rods) {
    const a = state[r.angle];
    x += r.length * Math.sin(a);
    y -= r.length * Math.cos(a);
    pts.push({ x, y });
  }
  return pts;
}

// the states to draw: the newest frame, or the start state before any frame, with the
// dragged positions in place of track 0's while a drag is on
function displayStates() {
  const cfg = lab.config;
  let states;
  if (lab.frame && lab.frame.tracks.length && lab.frame.tracks[0].state.length === cfg.state.length) {
    states = lab.frame.tracks.map((tr) => tr.state);
  } else {
    states = [cfg.state.map((s) => s.value)];
  }
  if (st.drag) {
    const s0 = states[0].slice();
    st.drag.positions.forEach((v, i) => { s0[i] = v; });
    states = [s0, ...states.slice(1)];
  }
  return states;
}

// geometry of the picture (CSS pixels), computed the same way for drawing and for hit tests
function simLayout(w, h) {
  const dr = lab.config.drawing;
  const legend = simLegend(w);
  const band = legend ? legend.box.y + legend.box.h + 4 : 0;
  if (dr.kind === 'rods') {
    const total = dr.rods.reduce((s, r) => s + r.length, 0) || 1;
    const masses = dr.rods.map((r) => r.mass);
    const mref = Math.max(...masses) || 1;
    const radii = masses.map((m) => Math.max(4, Math.min(22, 16 * Math.cbrt(m / mref))));
    // The rods fully stretched, bob included, stay inside the square below the legend.
    const side = Math.min(w, h - band), reach = Math.max(10, side / 2 - Math.max(...radii) - 6);
    return { kind: 'rods', cx: w / 2, cy: band + (h - band) / 2, scale: reach / total, radii, legend, reach: reach + Math.max(...radii) };
  }
  const x0 = Math.abs((lab.config.state[dr.x] || {}).value || 0);
  const range = Math.max(st.springRange, x0, 0.1) * 1.15;
  const side = Math.max(16, Math.min(70, 34 * Math.cbrt(dr.mass || 1)));
  const K = lab.frame ? lab.frame.tracks.length : 1;
  const lane = Math.min(120, (h - 40 - band) / Math.max(1, K));
  return { kind: 'spring', cx: w / 2, scale: (w / 2 - side - 40) / range, side: Math.min(side, lane * 0.8), lane, top: 30 + band, legend };
}

function toScreen(L, p) { return { x: L.cx + p.x * L.scale, y: L.cy - p.y * L.scale }; }

function drawSim() {
  const canvas = $('sim-canvas');
  const c = fitCanvas(canvas);
  if (!c) return;
  const { ctx, w, h } = c;
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, w, h);
  if (!lab.config) {
    ctx.fillStyle = '#5d6677'; ctx.font = FONT_B; ctx.textAlign = 'center';
    ctx.fillText(st.token ? 'waiting for the server…' : 'no access token in the address', w / 2, h / 2);
    return;
  }
  const states = displayStates();
  const L = simLayout(w, h);
  if (L.kind === 'rods') drawRods(ctx, L, states);
  else drawSpring(ctx, L, states, w);
  if (L.legend) drawLegend(ctx, L.legend);
  // Where the pendulum can be (every angle, bobs included) and the legend: kept apart.
  const data = L.kind === 'rods'
    ? { x: L.cx - L.reach, y: L.cy - L.reach, w: 2 * L.reach, h: 2 * L.reach }
    : { x: 0, y: L.top - 24, w, h: h - L.top + 24 };
  st.geometry['sim-canvas'] = { legend: L.legend && L.legend.box, legendTexts: L.legend ? L.legend.items.map((i) => i.text) : [], area: data };
  if (st.exporting) drawSimScale(ctx, L, w, h);
}

// For the PNG, which has no page around it: the time, and for rods a scale bar.
function drawSimScale(ctx, L, w, h) {
  ctx.font = FONT; ctx.fillStyle = '#1d2330'; ctx.textAlign = 'left';
  const tu = unitOf(timeUnit());
  if (lab.frame) ctx.fillText(`t = ${lab.frame.t.toFixed(3)}${tu ? ' ' + tu : ''}`, 10, h - 10);
  if (L.kind !== 'rods') return;
  const rods = lab.config.drawing.rods;
  const unit = lab.config.dimensionless ? 'length unit' : 'm';
  const len = niceStep(rods.reduce((s, r) => s + r.length, 0), 3);
  const px = len * L.scale;
  ctx.strokeStyle = '#1d2330'; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(w - 14 - px, h - 14); ctx.lineTo(w - 14, h - 14); ctx.stroke();
  ctx.textAlign = 'right';
  ctx.fillText(`${fmt(len, 3)} ${unit}`, w - 14, h - 20);
}

function drawRods(ctx, L, states) {
  const rods = lab.config.drawing.rods;
  const K = states.length;
  // ceiling and pivot
  ctx.strokeStyle = '#8b93a1'; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(L.cx - 40, L.cy); ctx.lineTo(L.cx + 40, L.cy); ctx.stroke();
  drawTrails(ctx, L, K);
  // track 0 last, so it lies on top
  for (let k = K - 1; k >= 0; k--) {
    const pts = rodPoints(states[k], rods).map((p) => toScreen(L, p));
    const colour = trackColour(k, K);
    ctx.globalAlpha = K > 1 && k > 0 ? 0.75 : 1;
    ctx.strokeStyle = '#2b313c'; ctx.lineWidth = 2.5;
    ctx.beginPath();
    pts.forEach((p, i) => (i ? ctx.lineTo(p.x, p.y) : ctx.moveTo(p.x, p.y)));
    ctx.stroke();
    for (let j = 1; j < pts.length; j++) {
      ctx.fillStyle = colour;
      ctx.beginPath(); ctx.arc(pts[j].x, pts[j].y, L.radii[j - 1], 0, 2 * Math.PI); ctx.fill();
      ctx.strokeStyle = '#1d2330'; ctx.lineWidth = 1; ctx.stroke();
    }
  }
  ctx.globalAlpha = 1;
  ctx.fillStyle = '#1d2330';
  ctx.beginPath(); ctx.arc(L.cx, L.cy, 4, 0, 2 * Math.PI); ctx.fill();
}

// Each track's trail, fading with its age in simulated time: frames at most TRAIL_GAP apart
// joined by lines (one path per chunk of 16 segments, each chunk one shade: 16 tracks stay
// cheap), a frame with no such neighbour drawn as a dot.
function drawTrails(ctx, L, K) {
  let segments = 0, dots = 0;
  const now = lab.frame ? lab.frame.t : 0;
  const alpha = (t) => 0.6 * Math.max(0, 1 - (now - t) / TRAIL_TIME);
  for (let k = 0; k < K; k++) {
    const tr = st.trails[k];
    if (!tr || !tr.length || st.drag) continue;
    ctx.strokeStyle = ctx.fillStyle = trackColour(k, K);
    ctx.lineWidth = 1.5;
    const joined = (i) => i > 0 && i < tr.length && tr[i].t - tr[i - 1].t <= TRAIL_GAP;
    // the newest frame is the bob itself: no dot under it
    for (let i = 0; i < tr.length - 1; i++) {
      if (joined(i) || joined(i + 1)) continue;
      ctx.globalAlpha = alpha(tr[i].t);
      const p = toScreen(L, tr[i]);
      ctx.beginPath(); ctx.arc(p.x, p.y, 2, 0, 2 * Math.PI); ctx.fill();
      dots++;
    }
    for (let i0 = 1; i0 < tr.length; i0 += 16) {
      ctx.globalAlpha = alpha(tr[i0 - 1].t);
      ctx.beginPath();
      for (let i = i0; i < Math.min(tr.length, i0 + 16); i++) {
        if (!joined(i)) continue;
        const p = toScreen(L, tr[i - 1]), q = toScreen(L, tr[i]);
        ctx.moveTo(p.x, p.y); ctx.lineTo(q.x, q.y);
        segments++;
      }
      ctx.stroke();
    }
  }
  ctx.globalAlpha = 1;
  st.trailDrawn = { segments, dots };
}

// How far apart in simulated time the last frames came (the median of the newest gaps),
// or null before there are any.
function frameGap() {
  if (st.frameGaps.length < 3) return null;
  const gaps = st.frameGaps.slice().sort((a, b) => a - b);
  return gaps[gaps.length >> 1];
}

function drawSpring(ctx, L, states, w) {
  const dr = lab.config.drawing;
  const xu = unitOf((lab.config.state[dr.x] || {}).unit);
  ctx.setLineDash([4, 4]); ctx.strokeStyle = '#b9c0cc'; ctx.lineWidth = 1;
  ctx.beginPath(); ctx.moveTo(L.cx, L.top - 10); ctx.lineTo(L.cx, L.top + L.lane * states.length); ctx.stroke();
  ctx.setLineDash([]);
  ctx.fillStyle = '#5d6677'; ctx.font = FONT; ctx.textAlign = 'center';
  ctx.fillText('x = 0', L.cx, L.top - 14);
  states.forEach((s, k) => {
    const yc = L.top + L.lane * (k + 0.5);
    const bx = L.cx + s[dr.x] * L.scale;
    const wallX = 16;
    ctx.fillStyle = '#8b93a1'; ctx.fillRect(wallX - 8, yc - L.lane * 0.4, 8, L.lane * 0.8);
    // zigzag spring from the wall to the block's left face
    const x1 = bx - L.side / 2, n = 14, amp = Math.min(10, L.lane * 0.15);
    ctx.strokeStyle = '#2b313c'; ctx.lineWidth = 1.5;
    ctx.beginPath(); ctx.moveTo(wallX, yc);
    for (let i = 1; i < n; i++) ctx.lineTo(wallX + ((x1 - wallX) * i) / n, yc + (i % 2 ? -amp : amp));
    ctx.lineTo(x1, yc); ctx.stroke();
    ctx.fillStyle = trackColour(k, states.length);
    ctx.fillRect(bx - L.side / 2, yc - L.side / 2, L.side, L.side);
    ctx.strokeStyle = '#1d2330'; ctx.lineWidth = 1;
    ctx.strokeRect(bx - L.side / 2, yc - L.side / 2, L.side, L.side);
    if (k === 0) {
      ctx.fillStyle = '#1d2330'; ctx.textAlign = 'center';
      ctx.fillText(`x = ${fmt(s[dr.x], 4)}${xu ? ' ' + xu : ''}`, bx, yc + L.side / 2 + 14);
    }
  });
}

// A legend's entries ([text, colour]) flowed left to right in rows no wider than `width`,
// from (x, y): laid out, not drawn, so that a picture can keep its data clear of the box (a
// legend inside a plot covered the newest data, at its right end).
function legendLayout(ctx, entries, x, y, width) {
  ctx.font = FONT;
  const items = [];
  let cx = x, row = 0, right = x;
  for (const [text, colour] of entries) {
    const w = ctx.measureText(text).width + 22;
    if (cx > x && cx + w > x + width) { cx = x; row++; }
    items.push({ text, colour, x: cx, y: y + row * 15 });
    right = Math.max(right, cx + w);
    cx += w + 12;
  }
  return { items, box: { x, y, w: right - x, h: items.length ? (row + 1) * 15 + 3 : 0 } };
}

function drawLegend(ctx, lay) {
  ctx.font = FONT; ctx.textAlign = 'left';
  for (const it of lay.items) {
    const yy = it.y + 11;
    ctx.strokeStyle = it.colour; ctx.lineWidth = 3;
    ctx.beginPath(); ctx.moveTo(it.x + 1, yy - 4); ctx.lineTo(it.x + 17, yy - 4); ctx.stroke();
    ctx.fillStyle = '#1d2330';
    ctx.fillText(it.text, it.x + 22, yy);
  }
}

// The pendulum picture's legend (one entry per track; in a single run only in the PNG), in a
// band along the top that the pendulum is kept out of.
function simLegend(w) {
  const cfg = lab.config;
  const K = displayStates().length;
  if (!(K > 1 || cfg.mode !== 'single' || st.exporting)) return null;
  const entries = Array.from({ length: K }, (_, k) => [trackLabel(k), trackColour(k, K)]);
  return legendLayout($('sim-canvas').getContext('2d'), entries, 10, 8, w - 20);
}

// client coordinates of track 0's bobs (or block) as drawn now
function bobClientPositions() {
  const canvas = $('sim-canvas');
  if (!lab.config || !canvas.clientWidth) return [];
  const L = simLayout(canvas.clientWidth, canvas.clientHeight);
  return bobScreen(L, displayStates()[0]).map((p) => toClient(canvas, p.x, p.y));
}

function bobScreen(L, s) {
  if (L.kind === 'rods') return rodPoints(s, lab.config.drawing.rods).slice(1).map((p) => toScreen(L, p));
  return [{ x: L.cx + s[lab.config.drawing.x] * L.scale, y: L.top + L.lane * 0.5 }];
}

// Dragging a bob: the clock pauses, the bob follows the pointer, and on release the new
// positions become the start state (velocities 0) through set_state.
function initDrag() {
  const canvas = $('sim-canvas');
  canvas.addEventListener('pointerdown', (e) => {
    if (!lab.config || !lab.connected || (st.drag && st.drag.pending)) return;
    const p = fromEvent(canvas, e);
    const L = simLayout(canvas.clientWidth, canvas.clientHeight);
    const s0 = displayStates()[0];
    let best = -1, bestD = Infinity;
    bobScreen(L, s0).forEach((b, j) => {
      const d = Math.hypot(b.x - p.x, b.y - p.y);
      const reach = L.kind === 'rods' ? Math.max(12, L.radii[j]) : Math.max(12, L.side / 2);
      if (d <= reach && d < bestD) { best = j; bestD = d; }
    });
    if (best < 0) return;
    const wasPlaying = lab.frame ? !lab.frame.paused : !lab.config.paused;
    if (wasPlaying) send({ cmd: 'pause' });
    st.drag = { index: best, wasPlaying, positions: s0.slice(0, lab.config.positions), pending: false };
    canvas.setPointerCapture(e.pointerId);
    canvas.classList.add('dragging');
    e.preventDefault();
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!st.drag || st.drag.pending) return;
    moveDrag(fromEvent(canvas, e));
  });
  const finish = (e) => {
    if (!st.drag || st.drag.pending) return;
    moveDrag(fromEvent(canvas, e));
    st.drag.pending = true;  // keep drawing the dropped pose until the new config arrives
    canvas.classList.remove('dragging');
    send({ cmd: 'set_state', positions: st.drag.positions });
    if (st.drag.wasPlaying) send({ cmd: 'play' });
    const d = st.drag;
    setTimeout(() => { if (st.drag === d) st.drag = null; }, 3000);
  };
  canvas.addEventListener('pointerup', finish);
  canvas.addEventListener('pointercancel', finish);
}

function moveDrag(p) {
  const canvas = $('sim-canvas');
  const L = simLayout(canvas.clientWidth, canvas.clientHeight);
  const dr = lab.config.drawing;
  if (L.kind === 'spring') {
    st.drag.positions[dr.x] = (p.x - L.cx) / L.scale;
    return;
  }
  // physical pointer position, y up; the dragged rod turns about the end of the rod above it
  const X = (p.x - L.cx) / L.scale, Y = -(p.y - L.cy) / L.scale;
  const j = st.drag.index;
  const s = displayStates()[0];
  const piv = rodPoints(s, dr.rods)[j];
  st.drag.positions[dr.rods[j].angle] = Math.atan2(X - piv.x, -(Y - piv.y));
}

// ======================================================================================
// plots
// ======================================================================================

function niceStep(span, n) {
  const raw = span / Math.max(1, n);
  const p = 10 ** Math.floor(Math.log10(raw));
  const f = raw / p;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * p;
}

function tickLabel(v, step) {
  if (Math.abs(v) < step * 1e-6) return '0';
  const a = Math.abs(v);
  if (a >= 1e5 || step < 1e-4) return v.toExponential(1);
  return v.toFixed(Math.max(0, -Math.floor(Math.log10(step) + 1e-9)));
}

// One plot routine for every chart. Series: {data, x(p), y(p), colour, label, dots}.
// With logY the y accessor already returns log10 values and ticks fall on whole decades.
function drawPlot(canvas, o) {
  const c = fitCanvas(canvas);
  if (!c) return null;
  const { ctx, w, h } = c;
  ctx.fillStyle = '#fff'; ctx.fillRect(0, 0, w, h);
  const m = { l: 62, r: 12, t: o.title ? 24 : 10, b: 36 };
  if (o.title) {
    ctx.fillStyle = '#1d2330'; ctx.font = FONT_B; ctx.textAlign = 'left';
    ctx.fillText(o.title, 8, 16);
  }
  // The legend in a band above the plot area, never over the data; one series gets none
  // (the page says whose it is), except in the PNG, which stands alone.
  const entries = o.series.filter((s) => s.label).map((s) => [s.label, s.colour]);
  const legend = entries.length > 1 || ((o.legendAlways || st.exporting) && entries.length)
    ? legendLayout(ctx, entries, m.l, m.t - 2, w - m.l - m.r) : null;
  if (legend) m.t += legend.box.h + 2;
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const s of o.series) {
    for (const p of s.data) {
      const x = s.x(p), y = s.y(p);
      if (!Number.isFinite(x) || !Number.isFinite(y)) continue;
      if (x < x0) x0 = x; if (x > x1) x1 = x;
      if (y < y0) y0 = y; if (y > y1) y1 = y;
    }
  }
  const pw = w - m.l - m.r, ph = h - m.t - m.b;
  if (legend) drawLegend(ctx, legend);
  const geometry = st.geometry[canvas.id] = {
    legend: legend && legend.box, legendTexts: entries.map((e) => e[0]), area: { x: m.l, y: m.t, w: pw, h: ph },
    title: o.title || '', xLabel: o.xLabel, yLabel: o.yLabel, newest: [],
  };
  ctx.strokeStyle = '#8b93a1'; ctx.lineWidth = 1;
  ctx.strokeRect(m.l + 0.5, m.t + 0.5, pw, ph);
  ctx.font = FONT;
  ctx.fillStyle = '#1d2330'; ctx.textAlign = 'center';
  ctx.fillText(o.xLabel, m.l + pw / 2, h - 4);
  ctx.save(); ctx.translate(12, m.t + ph / 2); ctx.rotate(-Math.PI / 2); ctx.fillText(o.yLabel, 0, 0); ctx.restore();
  if (!(x0 <= x1)) {
    ctx.fillStyle = '#5d6677';
    ctx.fillText(o.empty || 'no data yet', m.l + pw / 2, m.t + ph / 2);
    return null;
  }
  if (o.xFrom0 && x0 > 0) x0 = 0;
  if (x1 === x0) { x1 = x0 + 1; }
  if (o.logY) {
    y0 = Math.floor(y0); y1 = Math.ceil(y1);
    if (y1 - y0 < 2) { y0 -= 1; y1 = y0 + 3; }
  } else {
    const pad = (y1 - y0) * 0.05 || Math.abs(y0) * 0.1 || 1;
    y0 -= pad; y1 += pad;
  }
  if (!o.logY && !o.xFrom0) { const pad = (x1 - x0) * 0.03; x0 -= pad; x1 += pad; }
  const X = (x) => m.l + ((x - x0) / (x1 - x0)) * pw;
  const Y = (y) => m.t + (1 - (y - y0) / (y1 - y0)) * ph;

  // grid and tick labels
  ctx.strokeStyle = '#eceff4'; ctx.fillStyle = '#5d6677';
  const xs = niceStep(x1 - x0, pw / 90);
  ctx.textAlign = 'center';
  for (let v = Math.ceil(x0 / xs) * xs; v <= x1 + xs * 1e-9; v += xs) {
    ctx.beginPath(); ctx.moveTo(X(v), m.t); ctx.lineTo(X(v), m.t + ph); ctx.stroke();
    ctx.fillText(tickLabel(v, xs), X(v), m.t + ph + 14);
  }
  ctx.textAlign = 'right';
  const ys = o.logY ? Math.max(1, Math.ceil((y1 - y0) / Math.max(2, ph / 28))) : niceStep(y1 - y0, ph / 40);
  for (let v = Math.ceil(y0 / ys) * ys; v <= y1 + ys * 1e-9; v += ys) {
    ctx.beginPath(); ctx.moveTo(m.l, Y(v)); ctx.lineTo(m.l + pw, Y(v)); ctx.stroke();
    ctx.fillText(o.logY ? `1e${Math.round(v)}` : tickLabel(v, ys), m.l - 4, Y(v) + 4);
  }

  ctx.save();
  ctx.beginPath(); ctx.rect(m.l, m.t, pw, ph); ctx.clip();
  for (const s of o.series) {
    ctx.strokeStyle = ctx.fillStyle = s.colour;
    ctx.lineWidth = s.width || 1.5;
    if (s.dots) {
      for (const p of s.data) {
        const x = s.x(p), y = s.y(p);
        if (Number.isFinite(x) && Number.isFinite(y)) ctx.fillRect(X(x) - 1, Y(y) - 1, 2, 2);
      }
      continue;
    }
    ctx.beginPath();
    let pen = false;
    for (const p of s.data) {
      const x = s.x(p), y = s.y(p);
      if (!Number.isFinite(x) || !Number.isFinite(y)) { pen = false; continue; }
      if (pen) ctx.lineTo(X(x), Y(y)); else ctx.moveTo(X(x), Y(y));
      pen = true;
    }
    ctx.stroke();
  }
  const tf = { X, Y, x0, x1, y0, y1 };
  if (o.after) o.after(ctx, tf);
  ctx.restore();
  // each series' newest point as drawn, for the tests: it must be clear of the legend
  for (const s of o.series) {
    for (let i = s.data.length - 1; i >= 0; i--) {
      const x = s.x(s.data[i]), y = s.y(s.data[i]);
      if (Number.isFinite(x) && Number.isFinite(y)) { geometry.newest.push({ x: X(x), y: Y(y) }); break; }
    }
  }
  return tf;
}

const log10pos = (v) => (v > 0 ? Math.log10(v) : NaN);
const tLabel = () => withUnit('t', timeUnit());

function drawEnergyPlot() {
  const K = lab.energyHistory.length;
  drawPlot($('energy-plot'), {
    // Damping and a drive change the energy for real: then |E − E₀| is no integration error.
    title: lab.config && lab.config.conserves_energy === false
      ? 'Relative energy change (log scale)' : 'Relative energy error (log scale)',
    xLabel: tLabel(), yLabel: '|E − E₀| / scale', logY: true, xFrom0: true,
    empty: 'no energy error above zero yet',
    series: lab.energyHistory.map((data, k) => ({
      data, x: (p) => p[0], y: (p) => log10pos(p[1]), colour: trackColour(k, K), label: trackLabel(k),
    })),
    legendAlways: lab.config && lab.config.mode !== 'single',
  });
}

function drawSeparationPlot() {
  const K = st.sepTracks.length;
  const series = st.sepTracks.slice(1).map((data, i) => ({
    data, x: (p) => p[0], y: (p) => log10pos(p[1]), colour: trackColour(i + 1, K), label: trackLabel(i + 1), width: 1,
  }));
  const fit = st.growthFit;
  drawPlot($('separation-plot'), {
    xLabel: tLabel(), yLabel: 'distance from k=0', logY: true, xFrom0: true, series,
    after: fit && ((ctx, tf) => {
      // the fitted exponential is a straight line on log10 axes: log10 s = (c + λ t) / ln 10
      ctx.strokeStyle = '#000'; ctx.lineWidth = 2; ctx.setLineDash([6, 4]);
      const f = (t) => (fit.intercept + fit.slope * t) / Math.LN10;
      ctx.beginPath(); ctx.moveTo(tf.X(fit.a), tf.Y(f(fit.a))); ctx.lineTo(tf.X(fit.b), tf.Y(f(fit.b))); ctx.stroke();
      ctx.setLineDash([]);
    }),
  });
  const tu = timeUnit(), g = lab.growth;
  const span = g ? `from ${fmt(g.fit_from, 3)} to ${fmt(g.saturation, 3)}` : 'from min(100 δ, 0.01) to 0.1';
  $('growth-rate').textContent = fit
    ? `λ ≈ ${fmt(fit.slope, 3)} ${tu ? '1/' + tu : '(per unit time)'}${fit.final ? '' : ' so far'} ` +
      `(the slope of ln distance of k=1 from k=0 while ${span}, fitted over t = ${fmt(fit.a, 3)}…${fmt(fit.b, 3)}${tu ? ' ' + tu : ''}; dashed line)`
    : g && g.final
      ? `λ: not measurable: the distance of k=1 from k=0 passed ${fmt(g.saturation, 3)} with fewer than 3 samples above ${fmt(g.fit_from, 3)}`
      : `λ: not yet measured (the fit of ln distance of k=1 from k=0 uses it ${span})`;
}

function stateAxis(i) { const s = lab.config.state[i]; return s ? withUnit(s.name, s.unit) : `s${i}`; }

function drawGraphs() {
  if (!lab.config) return;
  const v = $('ts-var').value;
  if (v === 'energy') {
    drawPlot($('ts-plot'), {
      xLabel: tLabel(), yLabel: '|E − E₀| / scale (log)', logY: true, xFrom0: true,
      series: [{ data: lab.energyHistory[0] || [], x: (p) => p[0], y: (p) => log10pos(p[1]), colour: trackColour(0, 1) }],
    });
  } else {
    const i = Number(v) || 0;
    drawPlot($('ts-plot'), {
      xLabel: tLabel(), yLabel: stateAxis(i), xFrom0: true,
      series: [{ data: lab.stateHistory, x: (p) => p[0], y: (p) => p[1 + i], colour: trackColour(0, 1) }],
    });
  }
  const ix = Number($('phase-x').value) || 0, iy = Number($('phase-y').value) || 0;
  drawPlot($('phase-plot'), {
    xLabel: stateAxis(ix), yLabel: stateAxis(iy), width: 1,
    series: [{ data: lab.stateHistory, x: (p) => p[1 + ix], y: (p) => p[1 + iy], colour: trackColour(0, 1), width: 1 }],
  });
  const cfg = lab.config;
  const axes = cfg.poincare_axes && cfg.poincare_axes.length === 2 ? cfg.poincare_axes : ['x', 'y'];
  const unitFor = (name) => { const s = cfg.state.find((q) => q.name === name); return s ? s.unit : ''; };
  const K = lab.energyHistory.length || 1;
  const byTrack = Array.from({ length: K }, () => []);
  for (const p of st.poincarePts) if (byTrack[p[0]]) byTrack[p[0]].push(p);
  drawPlot($('poincare-plot'), {
    xLabel: withUnit(axes[0], unitFor(axes[0])), yLabel: withUnit(axes[1], unitFor(axes[1])),
    empty: cfg.poincare ? 'no crossings yet' : 'the section is off',
    series: byTrack.map((data, k) => ({ data, x: (p) => p[1], y: (p) => p[2], colour: trackColour(k, K), label: K > 1 ? trackLabel(k) : '', dots: true })),
  });
}

function updateNumbers() {
  const f = lab.frame, cfg = lab.config;
  if (!cfg) return;
  const eu = unitOf(energyUnit()), tu = unitOf(timeUnit());
  const e = (v) => (isNum(v) ? `${fmt(v, 6)}${eu ? ' ' + eu : ''}` : '–');
  const t0 = f && f.tracks[0];
  $('energy-k').textContent = t0 ? e(t0.kinetic) : '–';
  $('energy-v').textContent = t0 ? e(t0.potential) : '–';
  $('energy-e').textContent = t0 ? e(t0.kinetic + t0.potential) : '–';
  $('energy-err').textContent = t0 ? fmt(t0.energyError, 3) : '–';
  $('energy-scale').textContent = `scale = ${cfg.energy_scale_words} = ${fmt(cfg.energy_scale, 6)}${eu ? ' ' + eu : ''}`;
  if (f) {
    const state = f.paused ? 'paused' : 'running';
    const flip = t0 && isNum(t0.flipTime) ? ` · first flip at t = ${fmt(t0.flipTime, 4)}${tu ? ' ' + tu : ''}` : '';
    // A pendulum opened from the fractal: what the map said, beside what this run finds.
    const c = lab.config, m = st.mapPixel;
    const fromMap = m && c && c.system === 'double' && c.state[0].value === m.theta1 && c.state[1].value === m.theta2
      ? ` · the map: ${isNum(m.t) ? 'first flip at ' + fmt(m.t, 4) + ' s' : 'no flip before ' + fmt(m.tMax) + ' s'}` : '';
    // At high speed the trail shows the frames as dots: say why, with the frames' spacing.
    const gap = frameGap();
    const dots = cfg.drawing && cfg.drawing.kind === 'rods' && !f.paused && gap > TRAIL_GAP
      ? ` · trail as dots: frames ${fmt(gap, 2)}${tu ? ' ' + tu : ''} apart` : '';
    $('sim-info').textContent = `t = ${f.t.toFixed(3)}${tu ? ' ' + tu : ''} · ${Math.round(f.steps).toLocaleString('en')} steps · ${state}${flip}${fromMap}${dots}`;
    $('play').classList.toggle('active', !f.paused);
    $('pause').classList.toggle('active', f.paused);
    // Step advances a paused run only: while running it would do nothing.
    $('step').disabled = !f.paused;
  }
}

// ======================================================================================
// views: tabs, controls built from config, fractal explorer
// ======================================================================================

const VIEW_NAMES = { 'view-sim': 'Simulation', 'view-graphs': 'Graphs', 'view-fractal': 'Flip fractal' };

function showView(id) {
  st.view = id;
  for (const b of document.querySelectorAll('.tab')) b.classList.toggle('active', b.dataset.view === id);
  for (const s of document.querySelectorAll('.view')) s.hidden = s.id !== id;
  if (id !== 'view-export') st.lastPictureView = id;
  $('export-png').textContent = `Picture (PNG) of the ${VIEW_NAMES[st.lastPictureView]} view`;
  st.plotsDirty = true;
  st.fractalDirty = true;
}

function configure(fields) { return send(Object.assign({ cmd: 'configure' }, fields)); }

function applyConfig(cfg) {
  // Only systems with angles take degrees and have bobs to drag (the oscillator has a block).
  const angles = cfg.state.some((q) => q.unit === 'rad');
  $('state-hint').textContent = angles
    ? 'Angles are entered in degrees and sent to the server in radians. Drag a bob on the picture to set the start angles (velocities become 0).'
    : 'Drag the block on the picture to set the start position (the velocity becomes 0).';
  $('energy-err-label').textContent = cfg.conserves_energy
    ? 'Relative error |E − E₀| / scale'
    : 'Relative change |E − E₀| / scale (damping or drive: not conserved)';
  // The numbers are the first pendulum's: name it (a race's first method, a butterfly's k = 0).
  const first = cfg.mode === 'butterfly' ? 'k=0' : (cfg.tracks[0] ? cfg.tracks[0].label : '');
  $('energy-track').textContent = cfg.mode === 'single' ? '' : `(${first})`;
  $('system').value = cfg.system;
  $('system-desc').textContent = cfg.description + (cfg.dimensionless ? ' (dimensionless units)' : '');
  $('method').value = cfg.method;
  $('dt').value = cfg.dt;
  $('mode').value = cfg.mode;
  $('speed').value = cfg.speed;
  $('count').value = cfg.count;
  $('delta').value = cfg.delta;
  const tu = unitOf(cfg.time_unit);
  $('dt-unit').textContent = tu ? `(${tu})` : '(dimensionless time)';
  $('speed-unit').textContent = tu ? `(simulated ${tu} per wall-clock s)` : '(time units per wall-clock s)';
  for (const cb of $('race-methods').querySelectorAll('input')) cb.checked = (cfg.methods || []).includes(cb.value);
  $('race-hint').textContent = '';
  $('race-box').classList.toggle('inactive', cfg.mode !== 'race');
  $('butterfly-box').classList.toggle('inactive', cfg.mode !== 'butterfly');
  // A control the server ignores in this mode is disabled, not left to do nothing: a race
  // runs the methods ticked in its list, not the Integrator menu's (a butterfly's pendulums
  // all run the menu's method: it stays on there); the list, N and δ only act in their modes.
  const race = cfg.mode === 'race';
  $('method').disabled = race;
  $('method-hint').hidden = !race;
  for (const cb of $('race-methods').querySelectorAll('input')) cb.disabled = !race;
  $('count').disabled = $('delta').disabled = cfg.mode !== 'butterfly';
  $('poincare').checked = !!cfg.poincare;
  $('poincare').disabled = !cfg.poincare_available;
  const axes = cfg.poincare_axes ? cfg.poincare_axes.join(', ') : '';
  $('poincare-hint').textContent = cfg.poincare_available
    ? `Plotted in Graphs (${axes}).`
    : 'Only for systems with 2 degrees of freedom that conserve energy.';
  $('poincare-note').textContent = cfg.poincare_available
    ? (cfg.poincare ? `Crossings of the section, plotted as ${axes}.` : 'Turn on “Record a Poincaré section” in the Simulation view.')
    : 'Not available for this system (needs 2 degrees of freedom and conserved energy).';
  $('separation-box').hidden = cfg.mode !== 'butterfly';

  const key = cfg.system + '|' + cfg.params.map((p) => p.name).join(',') + '|' + cfg.state.map((s) => s.name).join(',');
  if (key !== st.controlsKey) {
    st.controlsKey = key;
    buildParams(cfg);
    buildState(cfg);
    buildGraphSelects(cfg);
  }
  for (const p of cfg.params) {
    const row = document.querySelector(`#params [data-name="${CSS.escape(p.name)}"]`);
    if (!row) continue;
    const slider = row.querySelector('input[type=range]');
    if (p.value < Number(slider.min)) slider.min = p.value;
    if (p.value > Number(slider.max)) slider.max = p.value;
    slider.value = p.value;
    row.querySelector('input[type=number]').value = p.value;
  }
  cfg.state.forEach((s, i) => {
    const input = $(`state-${i}`);
    if (input) input.value = isAngle(s) ? Number((s.value * DEG).toPrecision(12)) : s.value;
  });
  $('export-command').textContent = cfg.command || '';
  $('toml-text').textContent = cfg.toml || '';
  st.plotsDirty = true;
}

function isAngle(s) { return s.unit === 'rad'; }

// Slider range: the domain's bounds where finite, else a span around the default
// ([0, 4×default] for a positive default), always stretched to hold the current value.
function sliderRange(p) {
  const d = isNum(p.default) ? p.default : p.value;
  let lo = isNum(p.lo) ? p.lo : null, hi = isNum(p.hi) ? p.hi : null;
  if (lo === null && hi === null) {
    if (d > 0) { lo = 0; hi = 4 * d; } else if (d < 0) { lo = 4 * d; hi = -4 * d; } else { lo = -1; hi = 1; }
  } else if (hi === null) {
    hi = d > lo ? lo + 4 * (d - lo) : lo + 1;
  } else if (lo === null) {
    lo = d < hi ? hi - 4 * (hi - d) : hi - 1;
  }
  lo = Math.min(lo, p.value); hi = Math.max(hi, p.value);
  const integer = /whole|0 or 1/.test(p.domain || '');
  // an open bound ("> 0") cannot be reached: keep the slider just inside it
  if (/> ?0\b/.test(p.domain || '') && lo === 0 && !integer) lo = Math.min(p.value, hi / 1000);
  return { lo, hi, step: integer ? '1' : 'any' };
}

function buildParams(cfg) {
  const box = $('params');
  box.textContent = '';
  if (!cfg.params.length) box.append(el('p', 'hint', 'This system has no parameters.'));
  for (const p of cfg.params) {
    const row = el('div', 'param');
    row.dataset.name = p.name;
    row.title = `${p.description}. Domain: ${p.domain}. Default ${p.default}.`;
    const name = el('label', 'name');
    const u = unitOf(p.unit);
    name.append(el('b', null, p.name), document.createTextNode(u ? ` (${u}) ` : ' '), el('span', 'hint', p.description));
    const r = sliderRange(p);
    const slider = el('input');
    Object.assign(slider, { type: 'range', min: r.lo, max: r.hi, step: r.step, value: p.value });
    slider.setAttribute('aria-label', p.name);
    const num = el('input');
    Object.assign(num, { type: 'number', step: r.step, value: p.value, id: `param-${p.name}` });
    name.htmlFor = num.id;
    const sendValue = (v) => {
      if (!Number.isFinite(v)) { applyConfig(lab.config); return; }
      configure({ params: { [p.name]: v } });
    };
    // the slider previews while moving and sends once on release: every configure restarts the run
    slider.addEventListener('input', () => { num.value = Number(Number(slider.value).toPrecision(6)); });
    slider.addEventListener('change', () => sendValue(Number(num.value)));
    num.addEventListener('change', () => sendValue(parseFloat(num.value)));
    const line = el('div', 'row');
    line.append(slider, num);
    row.append(name, line);
    box.append(row);
  }
}

function buildState(cfg) {
  const box = $('state');
  box.textContent = '';
  cfg.state.forEach((s, i) => {
    const lbl = el('label');
    lbl.title = s.description;
    const unit = isAngle(s) ? 'deg, sent in rad' : unitOf(s.unit);
    lbl.append(el('b', null, s.name), document.createTextNode(unit ? ` (${unit}) ` : ' '), el('span', 'hint', s.description), el('br'));
    const input = el('input');
    Object.assign(input, { type: 'number', step: 'any', id: `state-${i}` });
    input.addEventListener('change', () => {
      const v = parseFloat(input.value);
      if (!Number.isFinite(v)) { applyConfig(lab.config); return; }
      configure({ state: { [s.name]: isAngle(s) ? v / DEG : v } });
    });
    lbl.append(input);
    box.append(lbl);
  });
}

function buildGraphSelects(cfg) {
  const names = cfg.state.map((s, i) => [String(i), withUnit(s.name, s.unit), s.description]);
  // Choices are kept only within one system: index 1 is theta2 on one and omega on another.
  const same = st.graphSystem === cfg.system && st.graphDim === cfg.state.length;
  st.graphSystem = cfg.system; st.graphDim = cfg.state.length;
  const keep = same ? [$('ts-var').value, $('phase-x').value, $('phase-y').value] : [];
  fillOptions($('ts-var'), [...names, ['energy', 'energy error |E − E₀| / scale', 'relative energy error']]);
  fillOptions($('phase-x'), names);
  fillOptions($('phase-y'), names);
  // default portrait: first position against its velocity
  $('ts-var').value = keep[0] || '0';
  $('phase-x').value = keep[1] || '0';
  $('phase-y').value = keep[2] || String(Math.min(cfg.positions, cfg.state.length - 1));
}

function onRaceChange() {
  const chosen = [...$('race-methods').querySelectorAll('input:checked')].map((c) => c.value);
  if (chosen.length < 2 || chosen.length > 4) {
    $('race-hint').textContent = `Choose 2 to 4 methods (${chosen.length} chosen): nothing sent yet.`;
    return;
  }
  $('race-hint').textContent = '';
  configure({ methods: chosen });
}

function initControls() {
  for (const b of document.querySelectorAll('.tab')) b.addEventListener('click', () => showView(b.dataset.view));
  $('error-close').addEventListener('click', () => { $('error').hidden = true; $('error-list').textContent = ''; });
  $('play').addEventListener('click', () => send({ cmd: 'play' }));
  $('pause').addEventListener('click', () => send({ cmd: 'pause' }));
  $('step').addEventListener('click', () => send({ cmd: 'step' }));
  $('reset').addEventListener('click', () => send({ cmd: 'reset' }));
  $('system').addEventListener('change', () => configure({ system: $('system').value }));
  $('method').addEventListener('change', () => configure({ method: $('method').value }));
  $('mode').addEventListener('change', () => configure({ mode: $('mode').value }));
  $('poincare').addEventListener('change', () => configure({ poincare: $('poincare').checked }));
  const numeric = (id, field, integer) => $(id).addEventListener('change', () => {
    const v = integer ? parseInt($(id).value, 10) : parseFloat($(id).value);
    if (!Number.isFinite(v)) { if (lab.config) applyConfig(lab.config); return; }
    configure({ [field]: v });
  });
  numeric('dt', 'dt');
  numeric('count', 'count', true);
  numeric('delta', 'delta');
  // speed has its own command, which does not restart the run; the share copy is patched
  // so the link keeps it
  $('speed').addEventListener('change', () => {
    const v = parseFloat($('speed').value);
    if (!Number.isFinite(v)) return;
    if (send({ cmd: 'speed', value: v }) && lab.config) {
      st.speedBefore = lab.config.speed;  // put back if the server refuses it
      lab.config.speed = v;
      if (lab.config.share) {
        lab.config.share.speed = v;
        history.replaceState(null, '', '#' + encodeURIComponent(JSON.stringify(lab.config.share)));
        $('share-link').value = shareUrl();
      }
    }
  });
  for (const id of ['ts-var', 'phase-x', 'phase-y']) $(id).addEventListener('change', () => { st.plotsDirty = true; });
  window.addEventListener('resize', () => { st.plotsDirty = true; st.fractalDirty = true; });
  initDrag();
  initFractal();
  initExports();
}

// ----- fractal explorer ---------------------------------------------------------------

// viridis at nine stops, interpolated linearly
const VIRIDIS = [[68, 1, 84], [72, 40, 120], [62, 73, 137], [49, 104, 142], [38, 130, 142],
  [31, 158, 137], [53, 183, 121], [110, 206, 88], [253, 231, 37]];
function viridis(u) {
  const x = Math.min(1, Math.max(0, u)) * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(x)), f = x - i;
  const a = VIRIDIS[i], b = VIRIDIS[i + 1];
  return [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f];
}

function onFractalFrame(a) {
  const n1 = a[2], n2 = a[3], N = n1 * n2, hasFlags = a[9] === 1;
  if (a.length < 12 + N * (hasFlags ? 2 : 1)) { showError('Truncated fractal frame from the server.'); return; }
  lab.fractal = {
    job: a[1], n1, n2, tMax: a[4], theta1: [a[5], a[6]], theta2: [a[7], a[8]], hasFlags,
    final: a[10] === 1, seconds: a[11],
    times: a.slice(12, 12 + N), flags: hasFlags ? a.slice(12 + N, 12 + 2 * N) : null,
  };
  lab.fractalFrames++;
  buildFractalImage(lab.fractal);
  const f = lab.fractal;
  const level = n1 === n2 ? `${n1}²` : `${n1}×${n2}`;
  $('fractal-info').textContent = `${level} of ${st.fractalReq.size}², ${fmt(f.seconds, 2)} s` +
    (f.final ? ' (final level)' : ' (refining…)') + fractalNote();
  st.fractalDirty = true;
}

function fractalNote() {
  const f = lab.fractal;
  if (!f || !f.flags) return '';
  let bad = 0;
  for (const v of f.flags) if (v === 0) bad++;
  return ` ${bad.toLocaleString('en')} of ${f.flags.length.toLocaleString('en')} pixels not converged at dt/2.`;
}

// colour by log10(flip time) between the earliest flip in the map and t_max
function buildFractalImage(f) {
  let lo = Infinity;
  for (const t of f.times) if (t > 0 && t < lo) lo = t;
  const hiL = Math.log10(f.tMax);
  let loL = Number.isFinite(lo) ? Math.log10(lo) : hiL - 2;
  if (hiL - loL < 0.1) loL = hiL - 1;
  const img = document.createElement('canvas');
  img.width = f.n1; img.height = f.n2;
  const over = document.createElement('canvas');
  over.width = f.n1; over.height = f.n2;
  const id = img.getContext('2d').createImageData(f.n1, f.n2);
  const od = over.getContext('2d').createImageData(f.n1, f.n2);
  for (let j = 0; j < f.n2; j++) {
    const row = f.n2 - 1 - j;   // θ₂ lo at the bottom
    for (let i = 0; i < f.n1; i++) {
      const t = f.times[j * f.n1 + i];
      const q = (row * f.n1 + i) * 4;
      const [r, g, b] = Number.isFinite(t) ? viridis((Math.log10(Math.max(t, 1e-12)) - loL) / (hiL - loL)) : [0, 0, 0];
      id.data[q] = r; id.data[q + 1] = g; id.data[q + 2] = b; id.data[q + 3] = 255;
      if (f.flags && f.flags[j * f.n1 + i] === 0) {
        od.data[q] = 230; od.data[q + 1] = 0; od.data[q + 2] = 0; od.data[q + 3] = (i + row) % 2 ? 110 : 150;
      }
    }
  }
  img.getContext('2d').putImageData(id, 0, 0);
  over.getContext('2d').putImageData(od, 0, 0);
  st.fractalImg = { img, over, loL, hiL };
}

function fractalLayout(w, h) {
  const m = { l: 66, t: 14, b: 46, r: 120 };
  const S = Math.max(50, Math.floor(Math.min(w - m.l - m.r, h - m.t - m.b)));
  return { x: m.l, y: m.t, S };
}

function fractalRanges() {
  const f = lab.fractal;
  return f ? { theta1: f.theta1, theta2: f.theta2 } : { theta1: st.fractalReq.theta1, theta2: st.fractalReq.theta2 };
}

function drawFractal() {
  const canvas = $('fractal-canvas');
  const c = fitCanvas(canvas);
  if (!c) return;
  const { ctx, w, h } = c;
  ctx.fillStyle = '#fff'; ctx.fillRect(0, 0, w, h);
  const g = fractalLayout(w, h);
  const img = st.fractalImg;
  if (img) {
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(img.img, g.x, g.y, g.S, g.S);
    if ($('fractal-overlay').checked && lab.fractal.flags) ctx.drawImage(img.over, g.x, g.y, g.S, g.S);
  } else {
    ctx.fillStyle = '#eef0f4'; ctx.fillRect(g.x, g.y, g.S, g.S);
    ctx.fillStyle = '#5d6677'; ctx.font = FONT_B; ctx.textAlign = 'center';
    ctx.fillText('press Compute', g.x + g.S / 2, g.y + g.S / 2);
  }
  ctx.strokeStyle = '#8b93a1'; ctx.lineWidth = 1; ctx.strokeRect(g.x - 0.5, g.y - 0.5, g.S + 1, g.S + 1);
  // axes in rad
  const { theta1, theta2 } = fractalRanges();
  ctx.font = FONT; ctx.fillStyle = '#1d2330';
  const s1 = niceStep(theta1[1] - theta1[0], 6), s2 = niceStep(theta2[1] - theta2[0], 6);
  ctx.textAlign = 'center';
  for (let v = Math.ceil(theta1[0] / s1) * s1; v <= theta1[1] + 1e-12; v += s1) {
    const x = g.x + ((v - theta1[0]) / (theta1[1] - theta1[0])) * g.S;
    ctx.fillRect(x, g.y + g.S, 1, 5);
    ctx.fillText(tickLabel(v, s1), x, g.y + g.S + 17);
  }
  ctx.fillText('θ₁ (rad), upper arm', g.x + g.S / 2, g.y + g.S + 36);
  st.geometry['fractal-canvas'] = {
    xLabel: 'θ₁ (rad), upper arm', yLabel: 'θ₂ (rad), lower arm',
    legendTexts: img ? ['first flip time (log scale)', 'no flip'] : [], area: { x: g.x, y: g.y, w: g.S, h: g.S },
  };
  ctx.textAlign = 'right';
  for (let v = Math.ceil(theta2[0] / s2) * s2; v <= theta2[1] + 1e-12; v += s2) {
    const y = g.y + g.S - ((v - theta2[0]) / (theta2[1] - theta2[0])) * g.S;
    ctx.fillRect(g.x - 5, y, 5, 1);
    ctx.fillText(tickLabel(v, s2), g.x - 8, y + 4);
  }
  ctx.save(); ctx.translate(14, g.y + g.S / 2); ctx.rotate(-Math.PI / 2); ctx.textAlign = 'center';
  ctx.fillText('θ₂ (rad), lower arm', 0, 0); ctx.restore();
  if (img) drawColourBar(ctx, g, img);
  if (st.fdrag && st.fdrag.moved) {
    const r = st.fdrag;
    ctx.setLineDash([5, 3]); ctx.lineWidth = 1.5;
    ctx.strokeStyle = '#fff'; ctx.strokeRect(r.x0, r.y0, r.x1 - r.x0, r.y1 - r.y0);
    ctx.setLineDash([]);
  }
}

function drawColourBar(ctx, g, img) {
  const bx = g.x + g.S + 22, bw = 16, top = g.y, bh = g.S - 40;
  for (let y = 0; y < bh; y++) {
    const [r, gg, b] = viridis(1 - y / bh);
    ctx.fillStyle = `rgb(${r | 0},${gg | 0},${b | 0})`;
    ctx.fillRect(bx, top + y, bw, 1.5);
  }
  ctx.strokeStyle = '#8b93a1'; ctx.strokeRect(bx, top, bw, bh);
  ctx.font = FONT; ctx.fillStyle = '#1d2330'; ctx.textAlign = 'left';
  const Y = (L) => top + (1 - (L - img.loL) / (img.hiL - img.loL)) * bh;
  const label = (t) => (t >= 100 ? t.toFixed(0) : Number(t.toPrecision(2)).toString()) + ' s';
  const marks = new Set([img.loL, img.hiL]);
  for (let d = Math.ceil(img.loL); d <= Math.floor(img.hiL); d++) marks.add(d);
  let lastY = -100;
  for (const L of [...marks].sort((a, b) => b - a)) {
    const y = Y(L);
    if (Math.abs(y - lastY) < 13) continue;   // keep labels from overlapping
    lastY = y;
    ctx.fillRect(bx + bw, y, 4, 1);
    ctx.fillText(label(10 ** L), bx + bw + 6, y + 4);
  }
  ctx.fillStyle = '#000'; ctx.fillRect(bx, top + bh + 12, bw, 12);
  ctx.fillStyle = '#1d2330'; ctx.fillText('no flip', bx + bw + 6, top + bh + 22);
  ctx.save(); ctx.translate(bx - 6, top + bh / 2); ctx.rotate(-Math.PI / 2); ctx.textAlign = 'center';
  ctx.fillText('first flip time (log scale)', 0, 0); ctx.restore();
}

function fractalPixelClient(i, j) {
  const canvas = $('fractal-canvas'), f = lab.fractal;
  if (!f || !canvas.clientWidth) return null;
  const g = fractalLayout(canvas.clientWidth, canvas.clientHeight);
  return toClient(canvas, g.x + ((i + 0.5) * g.S) / f.n1, g.y + ((f.n2 - 1 - j + 0.5) * g.S) / f.n2);
}

function requestFractal(theta1, theta2) {
  const maxSize = Number($('fractal-size').max) || 1024;
  const size = Math.max(16, Math.min(maxSize, parseInt($('fractal-size').value, 10) || 256));
  const tmax = Math.max(1e-3, Math.min(Number($('fractal-tmax').max) || 1000, parseFloat($('fractal-tmax').value) || 100));
  $('fractal-size').value = size;
  $('fractal-tmax').value = tmax;
  const msg = { cmd: 'fractal', size, t_max: tmax, theta1, theta2 };
  if ($('fractal-method').value) msg.method = $('fractal-method').value;
  st.fractalReq = { size, t_max: tmax, theta1, theta2, method: msg.method };
  if (send(msg)) $('fractal-info').textContent = `Computing up to ${size}²…`;
}

function initFractal() {
  const canvas = $('fractal-canvas');
  $('fractal-start').addEventListener('click', () => { const r = fractalRanges(); requestFractal(r.theta1, r.theta2); });
  $('fractal-reset-zoom').addEventListener('click', () => requestFractal([-Math.PI, Math.PI], [-Math.PI, Math.PI]));
  $('fractal-cancel').addEventListener('click', () => { if (send({ cmd: 'fractal_cancel' })) $('fractal-info').textContent = 'Stopped.'; });
  $('fractal-overlay').addEventListener('change', () => { st.fractalDirty = true; });
  const clampToMap = (p, g) => ({ x: Math.min(g.x + g.S, Math.max(g.x, p.x)), y: Math.min(g.y + g.S, Math.max(g.y, p.y)) });
  canvas.addEventListener('pointerdown', (e) => {
    const g = fractalLayout(canvas.clientWidth, canvas.clientHeight);
    const p = fromEvent(canvas, e);
    if (p.x < g.x || p.x > g.x + g.S || p.y < g.y || p.y > g.y + g.S) return;
    st.fdrag = { sx: p.x, sy: p.y, x0: p.x, y0: p.y, x1: p.x, y1: p.y, moved: false };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!st.fdrag) return;
    const g = fractalLayout(canvas.clientWidth, canvas.clientHeight);
    const p = clampToMap(fromEvent(canvas, e), g);
    const d = st.fdrag;
    if (Math.hypot(p.x - d.sx, p.y - d.sy) > 5) d.moved = true;
    Object.assign(d, { x0: Math.min(d.sx, p.x), x1: Math.max(d.sx, p.x), y0: Math.min(d.sy, p.y), y1: Math.max(d.sy, p.y) });
    st.fractalDirty = true;
  });
  canvas.addEventListener('pointerup', (e) => {
    const d = st.fdrag;
    st.fdrag = null;
    st.fractalDirty = true;
    if (!d) return;
    const g = fractalLayout(canvas.clientWidth, canvas.clientHeight);
    const { theta1, theta2 } = fractalRanges();
    if (d.moved) {
      // screen rectangle → θ ranges; y runs downwards while θ₂ runs upwards
      const t1 = (x) => theta1[0] + ((x - g.x) / g.S) * (theta1[1] - theta1[0]);
      const t2 = (y) => theta2[0] + (1 - (y - g.y) / g.S) * (theta2[1] - theta2[0]);
      requestFractal([t1(d.x0), t1(d.x1)], [t2(d.y1), t2(d.y0)]);
    } else {
      pickFractalPixel(clampToMap(fromEvent(canvas, e), g), g);
    }
  });
  canvas.addEventListener('pointercancel', () => { st.fdrag = null; st.fractalDirty = true; });
}

// a click opens that pixel's pendulum (released from rest) in the simulation
function pickFractalPixel(p, g) {
  const f = lab.fractal;
  if (!f) return;
  const i = Math.min(f.n1 - 1, Math.max(0, Math.floor(((p.x - g.x) / g.S) * f.n1)));
  const j = f.n2 - 1 - Math.min(f.n2 - 1, Math.max(0, Math.floor(((p.y - g.y) / g.S) * f.n2)));
  const theta1 = f.theta1[0] + ((i + 0.5) * (f.theta1[1] - f.theta1[0])) / f.n1;
  const theta2 = f.theta2[0] + ((j + 0.5) * (f.theta2[1] - f.theta2[0])) / f.n2;
  const t = f.times[j * f.n1 + i];
  $('fractal-info').textContent = `Pixel (${i}, ${j}): θ₁ = ${fmt(theta1, 5)} rad (${fmt(theta1 * DEG, 4)}°), ` +
    `θ₂ = ${fmt(theta2, 5)} rad (${fmt(theta2 * DEG, 4)}°), first flip ${Number.isFinite(t) ? 'at ' + fmt(t, 4) + ' s' : 'none before ' + fmt(f.tMax) + ' s'}. Opened in the simulation.`;
  st.mapPixel = { theta1, theta2, t, tMax: f.tMax };
  // The map's own method and step, so that the run shows the flip the map computed; Tao's
  // maps open with rk4 (a single Tao run at dt = 0.01 s exceeds its binding limit w·h ≤ 1).
  const req = st.fractalReq || {};
  const method = !req.method || req.method.startsWith('tao') ? 'rk4' : req.method;
  if (configure({ system: 'double', mode: 'single', method, dt: 0.01, state: { theta1, theta2, omega1: 0, omega2: 0 } })) send({ cmd: 'play' });
  showView('view-sim');
}

// ======================================================================================
// exports and errors
// ======================================================================================

function shareUrl() {
  const share = lab.config ? lab.config.share : shareFromHash().share;
  const hash = share ? '#' + encodeURIComponent(JSON.stringify(share)) : '';
  return location.origin + location.pathname + location.search + hash;
}

function download(blob, name) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

async function copyText(text, button) {
  try {
    await navigator.clipboard.writeText(text);
  } catch (_) {
    // clipboard API needs a secure context or permission: fall back to a selection copy
    const ta = el('textarea');
    ta.value = text;
    document.body.append(ta);
    ta.select();
    document.execCommand('copy');
    ta.remove();
  }
  const old = button.textContent;
  button.textContent = 'Copied';
  setTimeout(() => { button.textContent = old; }, 1200);
}

function tableColumns() {
  const cfg = lab.config;
  const tu = unitOf(cfg.time_unit), eu = unitOf(cfg.energy_unit);
  const h = (name, u) => (u ? `${name} [${u}]` : name);
  return [h('t', tu), ...cfg.state.map((s) => h(s.name, unitOf(s.unit))), h('kinetic', eu), h('potential', eu), 'energy_error [relative]'];
}

function exportCsv() {
  if (!lab.config) return;
  const lines = [tableColumns().join(',')];
  for (const row of st.exportHistory) lines.push(row.map((v) => String(v)).join(','));
  download(new Blob([lines.join('\n') + '\n'], { type: 'text/csv' }), `pendula-${lab.config.system}.csv`);
  exportNote();
}

// NPY v1.0: magic, version, little-endian header length, a Python dict literal padded with
// spaces and a newline so the data starts on a multiple of 64 bytes, then row-major <f8
function npyBytes(rows, ncols) {
  const dict = `{'descr': '<f8', 'fortran_order': False, 'shape': (${rows.length}, ${ncols}), }`;
  const base = 10 + dict.length + 1;
  const header = dict + ' '.repeat((64 - (base % 64)) % 64) + '\n';
  const buf = new ArrayBuffer(10 + header.length + rows.length * ncols * 8);
  const u8 = new Uint8Array(buf), dv = new DataView(buf);
  u8.set([0x93, 0x4e, 0x55, 0x4d, 0x50, 0x59, 1, 0]);
  dv.setUint16(8, header.length, true);
  for (let i = 0; i < header.length; i++) u8[10 + i] = header.charCodeAt(i);
  let o = 10 + header.length;
  for (const r of rows) for (let c = 0; c < ncols; c++, o += 8) dv.setFloat64(o, r[c], true);
  return buf;
}

function exportNpy() {
  if (!lab.config) return;
  const ncols = tableColumns().length;
  download(new Blob([npyBytes(st.exportHistory, ncols)], { type: 'application/octet-stream' }), `pendula-${lab.config.system}.npy`);
  exportNote(' NPY columns: ' + tableColumns().join(', ') + '.');
}

function exportNote(extra = '') {
  $('export-note').textContent = `${st.exportHistory.length} rows of track 0 since t = 0, one per frame received (not every step: the frames are at most 60 a second), evenly thinned to at most ${HISTORY_MAX}.${extra}`;
}

// What each picture is, for its caption in the PNG.
function captionOf(canvas) {
  const cfg = lab.config;
  const opt = (id) => { const s = $(id); return s.selectedOptions[0] ? s.selectedOptions[0].textContent : ''; };
  switch (canvas.id) {
    case 'sim-canvas': return cfg && cfg.tracks.length > 1 ? 'The pendulums at the newest frame' : 'The pendulum at the newest frame';
    case 'energy-plot': return cfg && cfg.tracks.length > 1 ? 'Energy of each pendulum' : 'Energy';
    case 'separation-plot': {
      const tu = unitOf(timeUnit());
      return 'Separation from k=0' + (st.growthFit ? `: λ ≈ ${fmt(st.growthFit.slope, 3)} ${tu ? '1/' + tu : 'per unit time'} (dashed)` : '');
    }
    case 'ts-plot': return `Time series of ${opt('ts-var')} (${trackLabel(0)})`;
    case 'phase-plot': return `Phase portrait: ${opt('phase-y')} against ${opt('phase-x')}`;
    case 'poincare-plot': return 'Poincaré section';
    case 'fractal-canvas': return 'Flip fractal: time to the first flip of the double pendulum from rest';
    default: return canvas.getAttribute('aria-label') || '';
  }
}

function modeWords(cfg) {
  const tu = unitOf(cfg.time_unit);
  const dt = `dt = ${fmt(cfg.dt)}${tu ? ' ' + tu : ''}`;
  if (cfg.mode === 'race') return `race of ${cfg.tracks.map((t) => t.label).join(', ')}, ${dt}`;
  if (cfg.mode === 'butterfly') return `butterfly of ${cfg.count} pendulums ${fmt(cfg.delta)} rad apart, ${cfg.method}, ${dt}`;
  return `${cfg.method}, ${dt}`;
}

// The PNG: the last viewed tab's pictures side by side on white, redrawn for a page of their
// own (every plot's legend, the pendulum's time and scale), each under its caption, below a
// title that says what ran. Axis labels are the plots' own. lab.lastExport describes it.
function exportFigure() {
  const view = st.lastPictureView;
  const wasHidden = $(view).hidden;
  if (wasHidden) for (const s of document.querySelectorAll('.view')) s.hidden = s.id !== view;
  st.exporting = true;
  try {
    redrawView(view);
  } finally {
    st.exporting = false;
  }
  const canvases = [...$(view).querySelectorAll('canvas')].filter((c) => c.width && c.height && c.offsetParent !== null);
  const dpr = window.devicePixelRatio || 1;
  const gap = Math.round(12 * dpr), titleH = Math.round(30 * dpr), capH = Math.round(22 * dpr);
  const W = canvases.reduce((s, c) => s + c.width, 0) + gap * (canvases.length + 1);
  const H = titleH + capH + Math.max(1, ...canvases.map((c) => c.height)) + gap;
  const out = document.createElement('canvas');
  out.width = Math.max(1, W); out.height = H;
  const ctx = out.getContext('2d');
  ctx.fillStyle = '#fff'; ctx.fillRect(0, 0, out.width, out.height);
  ctx.scale(dpr, dpr);
  const cfg = lab.config;
  const tu = cfg ? unitOf(cfg.time_unit) : '';
  const title = view === 'view-fractal' || !cfg
    ? 'pendula lab: flip fractal'
    : `pendula lab: ${cfg.system}, ${modeWords(cfg)}${lab.frame ? `, t = ${lab.frame.t.toFixed(3)}${tu ? ' ' + tu : ''}` : ''}`;
  ctx.fillStyle = '#1d2330'; ctx.textAlign = 'left'; ctx.font = FONT_B;
  ctx.fillText(title, 12, 20);
  const panels = [];
  let x = gap;
  ctx.font = FONT;
  for (const c of canvases) {
    const caption = captionOf(c);
    ctx.fillStyle = '#1d2330';
    ctx.fillText(fitText(ctx, caption, c.width / dpr), x / dpr, (titleH + capH) / dpr - 7);
    ctx.drawImage(c, x / dpr, (titleH + capH) / dpr, c.width / dpr, c.height / dpr);
    const g = st.geometry[c.id] || {};
    panels.push({ canvas: c.id, caption, xLabel: g.xLabel || null, yLabel: g.yLabel || null, legend: g.legendTexts || [] });
    x += c.width + gap;
  }
  if (wasHidden) showView(st.view);
  else redrawView(view);
  lab.lastExport = { view, width: out.width, height: out.height, title, titleHeight: titleH, panels };
  return out;
}

// `text`, cut to `width` pixels with an ellipsis.
function fitText(ctx, text, width) {
  if (ctx.measureText(text).width <= width) return text;
  let n = text.length;
  while (n > 1 && ctx.measureText(text.slice(0, n) + '…').width > width) n--;
  return text.slice(0, n) + '…';
}

function exportPng() {
  const view = st.lastPictureView;
  exportFigure().toBlob((blob) => blob && download(blob, `pendula-${view.replace('view-', '')}.png`), 'image/png');
}

function initExports() {
  $('export-csv').addEventListener('click', exportCsv);
  $('export-npy').addEventListener('click', exportNpy);
  $('export-png').addEventListener('click', exportPng);
  $('export-toml').addEventListener('click', () => {
    if (lab.config) download(new Blob([lab.config.toml], { type: 'application/toml' }), 'scenario.toml');
  });
  $('copy-share').addEventListener('click', () => copyText(shareUrl(), $('copy-share')));
  $('copy-command').addEventListener('click', () => copyText(lab.config ? lab.config.command : '', $('copy-command')));
  $('share-link').addEventListener('focus', () => $('share-link').select());
}

// A note, not a refusal: shown where refusals are, kept in lab.notices.
function showNotice(text) {
  lab.notices.push(text);
  showError(`Note: ${text}`, undefined, false);
}

function showError(text, raw, record = true) {
  if (record) lab.errors.push(raw === undefined ? text : raw);
  const list = $('error-list');
  const li = el('li', null, text);
  list.append(li);
  while (list.children.length > 6) list.firstChild.remove();
  $('error').hidden = false;
}

// ======================================================================================
// main loop
// ======================================================================================

function redrawView(view) {
  if (view === 'view-sim') {
    drawSim();
    drawEnergyPlot();
    if (lab.config && lab.config.mode === 'butterfly') drawSeparationPlot();
    updateNumbers();
  } else if (view === 'view-graphs') {
    drawGraphs();
  } else if (view === 'view-fractal') {
    drawFractal();
  }
}

function loop(now) {
  if (st.view === 'view-sim') drawSim();
  // charts at ~10 Hz: thousands of points per track need not follow every display frame
  if (st.plotsDirty && now - st.lastPlotDraw > 100) {
    st.plotsDirty = false;
    st.lastPlotDraw = now;
    updateNumbers();
    if (st.view === 'view-sim') {
      drawEnergyPlot();
      if (lab.config && lab.config.mode === 'butterfly') drawSeparationPlot();
    } else if (st.view === 'view-graphs') {
      drawGraphs();
    }
  }
  if (st.view === 'view-fractal' && st.fractalDirty) {
    st.fractalDirty = false;
    drawFractal();
  }
  requestAnimationFrame(loop);
}

initControls();
showView('view-sim');
connect();
requestAnimationFrame(loop);
