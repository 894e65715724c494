// The Flip fractal view: the server's maps of the double pendulum's first flip time,
// zoomed by dragging, a pixel opened in the simulation by a click.
import { $, DEG, FONT, FONT_B, fmt, fitCanvas, toClient, fromEvent, niceStep, tickLabel } from './util.js';
import { lab, st } from './state.js';
import { showError } from './messages.js';
import { send, configure } from './connection.js';
import { showView } from './tabs.js';

// The map's picture, the last request, and a zoom rectangle being dragged.
const fractal = {
  img: null,
  req: { size: 256, t_max: 100, theta1: [-Math.PI, Math.PI], theta2: [-Math.PI, Math.PI] },
  drag: null,
};

// viridis at nine stops, interpolated linearly
const VIRIDIS = [[68, 1, 84], [72, 40, 120], [62, 73, 137], [49, 104, 142], [38, 130, 142],
  [31, 158, 137], [53, 183, 121], [110, 206, 88], [253, 231, 37]];

function viridis(u) {
  const x = Math.min(1, Math.max(0, u)) * (VIRIDIS.length - 1);
  const i = Math.min(VIRIDIS.length - 2, Math.floor(x)), f = x - i;
  const a = VIRIDIS[i], b = VIRIDIS[i + 1];
  return [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f];
}

export function onFractalFrame(a) {
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
  $('fractal-info').textContent = `${level} of ${fractal.req.size}², ${fmt(f.seconds, 2)} s` +
    (f.final ? ' (final level)' : ' (refining…)') + fractalNote();
  st.fractalDirty = true;
}

export function fractalNote() {
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
  fractal.img = { img, over, loL, hiL };
}

function fractalLayout(w, h) {
  const m = { l: 66, t: 14, b: 46, r: 120 };
  const S = Math.max(50, Math.floor(Math.min(w - m.l - m.r, h - m.t - m.b)));
  return { x: m.l, y: m.t, S };
}

function fractalRanges() {
  const f = lab.fractal;
  return f ? { theta1: f.theta1, theta2: f.theta2 } : { theta1: fractal.req.theta1, theta2: fractal.req.theta2 };
}

export function drawFractal() {
  const canvas = $('fractal-canvas');
  const c = fitCanvas(canvas);
  if (!c) return;
  const { ctx, w, h } = c;
  ctx.fillStyle = '#fff'; ctx.fillRect(0, 0, w, h);
  const g = fractalLayout(w, h);
  const img = fractal.img;
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
  if (fractal.drag && fractal.drag.moved) {
    const r = fractal.drag;
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

export function fractalPixelClient(i, j) {
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
  fractal.req = { size, t_max: tmax, theta1, theta2, method: msg.method };
  if (send(msg)) $('fractal-info').textContent = `Computing up to ${size}²…`;
}

export function initFractal() {
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
    fractal.drag = { sx: p.x, sy: p.y, x0: p.x, y0: p.y, x1: p.x, y1: p.y, moved: false };
    canvas.setPointerCapture(e.pointerId);
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!fractal.drag) return;
    const g = fractalLayout(canvas.clientWidth, canvas.clientHeight);
    const p = clampToMap(fromEvent(canvas, e), g);
    const d = fractal.drag;
    if (Math.hypot(p.x - d.sx, p.y - d.sy) > 5) d.moved = true;
    Object.assign(d, { x0: Math.min(d.sx, p.x), x1: Math.max(d.sx, p.x), y0: Math.min(d.sy, p.y), y1: Math.max(d.sy, p.y) });
    st.fractalDirty = true;
  });
  canvas.addEventListener('pointerup', (e) => {
    const d = fractal.drag;
    fractal.drag = null;
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
  canvas.addEventListener('pointercancel', () => { fractal.drag = null; st.fractalDirty = true; });
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
  const req = fractal.req || {};
  const method = !req.method || req.method.startsWith('tao') ? 'rk4' : req.method;
  if (configure({ system: 'double', mode: 'single', method, dt: 0.01, state: { theta1, theta2, omega1: 0, omega2: 0 } })) send({ cmd: 'play' });
  showView('view-sim');
}

