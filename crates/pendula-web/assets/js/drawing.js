// The pendulum picture (rods and bobs, or a block on a spring), the bobs' trails, and
// dragging a bob to set the start state.
import { $, FONT, FONT_B, unitOf, fmt, fitCanvas, toClient, fromEvent, rodPoints, legendLayout, drawLegend, niceStep } from './util.js';
import { TRAIL_TIME, TRAIL_GAP, lab, st, timeUnit, trackColour, trackLabel } from './state.js';
import { send, token } from './connection.js';

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

export function drawSim() {
  const canvas = $('sim-canvas');
  const c = fitCanvas(canvas);
  if (!c) return;
  const { ctx, w, h } = c;
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, w, h);
  if (!lab.config) {
    ctx.fillStyle = '#5d6677'; ctx.font = FONT_B; ctx.textAlign = 'center';
    ctx.fillText(token ? 'waiting for the server…' : 'no access token in the address', w / 2, h / 2);
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
export function bobClientPositions() {
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
export function initDrag() {
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

