// The page's state: `lab`, what the page knows of the server's session (also the tests'
// window onto it, as window.lab, with the hooks app.js adds), and `st`, the page's own
// bookkeeping; the frames' histories, which every view draws from.
import { isNum, rodPoints } from './util.js';

export const HISTORY_MAX = 4000;   // per track; halved (every other point dropped) when reached

// The last bob's trail: the frames of the last TRAIL_TIME of simulated time (s, or the
// system's own time unit), at most TRAIL_MAX of them. Two frames further apart than TRAIL_GAP
// are not joined: at high speed a frame comes every speed/60 s, and a straight chord across
// a whole swing is no path the bob took (at speed 50 they scribbled over the picture); those
// frames are drawn as dots, each a state the bob really passed through.
export const TRAIL_TIME = 3;
const TRAIL_MAX = 240;
export const TRAIL_GAP = 0.1;
const POINCARE_MAX = 50000;
const RACE_COLOURS = ['#d62728', '#1f77b4', '#2ca02c', '#9467bd'];

export const lab = {
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
  geometry: (id) => st.geometry[id] || null,
  get trail() {
    const spans = st.trails.map((tr) => (tr.length ? tr[tr.length - 1].t - tr[0].t : 0));
    return { spans, points: st.trails.map((tr) => tr.length), ...st.trailDrawn, gap: frameGap() };
  },
  // Every Poincaré point received since the last config: [track, x, y].
  get poincarePoints() { return st.poincarePts; },
};

// What several modules share; what one module alone keeps is that module's.
export const st = {
  view: 'view-sim',
  lastPictureView: 'view-sim',  // the PNG export pictures the last view other than Export
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
  speedBefore: null,             // the speed to put back if the server refuses a new one
  plotsDirty: true,
  fractalDirty: true,
  mapPixel: null,               // the fractal pixel last opened in the simulation
};

export function resetHistories(K) {
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
export function onGrowth(msg) {
  if (lab.config && lab.config.mode === 'butterfly') setGrowth(msg);
}

function setGrowth(msg) {
  lab.growth = msg;
  lab.growthRate = msg && isNum(msg.rate) ? msg.rate : null;
  st.growthFit = lab.growthRate === null ? null
    : { slope: msg.rate, intercept: msg.intercept, a: msg.t_start, b: msg.t_end, final: msg.final };
  st.plotsDirty = true;
}

export function onSimFrame(a) {
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

export const timeUnit = () => (lab.config ? lab.config.time_unit : 's');

export const energyUnit = () => (lab.config ? lab.config.energy_unit : 'J');

export function trackColour(k, K) {
  const mode = lab.config ? lab.config.mode : 'single';
  if (mode === 'butterfly') return `hsl(${Math.round((k / Math.max(1, K)) * 300)}, 75%, 42%)`;
  if (mode === 'race') return RACE_COLOURS[k % RACE_COLOURS.length];
  return '#1f5fbf';
}

export function trackLabel(k) {
  const cfg = lab.config;
  if (!cfg) return '';
  if (cfg.mode === 'race') return (cfg.tracks && cfg.tracks[k] && cfg.tracks[k].method) || (cfg.methods && cfg.methods[k]) || `track ${k}`;
  if (cfg.mode === 'butterfly') return `k=${k}`;
  return cfg.method;
}

// How far apart in simulated time the last frames came (the median of the newest gaps),
// or null before there are any.
export function frameGap() {
  if (st.frameGaps.length < 3) return null;
  const gaps = st.frameGaps.slice().sort((a, b) => a - b);
  return gaps[gaps.length >> 1];
}
