// Helpers without state: the DOM, numbers and units, canvas geometry, axis ticks, legends,
// and the pendulum's rod geometry.

export const $ = (id) => document.getElementById(id);
export const DEG = 180 / Math.PI;
export const FONT = '12px system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif';
export const FONT_B = '600 13px system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif';

// "1" is the library's unit of a dimensionless quantity: show nothing rather than a bare 1
export const unitOf = (u) => (u && u !== '1' ? u : '');
export const withUnit = (name, u) => (unitOf(u) ? `${name} (${unitOf(u)})` : name);
export const isNum = (v) => typeof v === 'number' && Number.isFinite(v);

export function fmt(v, digits = 5) {
  if (!isNum(v)) return v === null || v === undefined ? '–' : String(v);
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e-3 && a < 1e6) return String(Number(v.toPrecision(digits)));
  return v.toExponential(Math.max(1, digits - 3));
}

export function el(tag, cls, text) {
  const e = document.createElement(tag);
  if (cls) e.className = cls;
  if (text !== undefined) e.textContent = text;
  return e;
}

// Canvas backing store follows the CSS box × devicePixelRatio so lines stay sharp; drawing is
// done in CSS pixels. Returns null while the canvas is hidden (zero size).
export function fitCanvas(canvas) {
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
export function toClient(canvas, x, y) {
  const r = canvas.getBoundingClientRect();
  const sx = canvas.clientWidth ? r.width / canvas.clientWidth : 1;
  const sy = canvas.clientHeight ? r.height / canvas.clientHeight : 1;
  return { x: r.left + x * sx, y: r.top + y * sy };
}

export function fromEvent(canvas, e) {
  const r = canvas.getBoundingClientRect();
  return {
    x: (e.clientX - r.left) * (canvas.clientWidth / (r.width || 1)),
    y: (e.clientY - r.top) * (canvas.clientHeight / (r.height || 1)),
  };
}

export function fillOptions(select, items) {
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

// The joints of a chain of rods (drawing.rods of the config) from the pivot at the origin,
// y up, in the system's lengths.
export function rodPoints(state, rods) {
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

// A legend's entries ([text, colour]) flowed left to right in rows no wider than `width`,
// from (x, y): laid out, not drawn, so that a picture can keep its data clear of the box (a
// legend inside a plot covered the newest data, at its right end).
export function legendLayout(ctx, entries, x, y, width) {
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

export function drawLegend(ctx, lay) {
  ctx.font = FONT; ctx.textAlign = 'left';
  for (const it of lay.items) {
    const yy = it.y + 11;
    ctx.strokeStyle = it.colour; ctx.lineWidth = 3;
    ctx.beginPath(); ctx.moveTo(it.x + 1, yy - 4); ctx.lineTo(it.x + 17, yy - 4); ctx.stroke();
    ctx.fillStyle = '#1d2330';
    ctx.fillText(it.text, it.x + 22, yy);
  }
}

export function niceStep(span, n) {
  const raw = span / Math.max(1, n);
  const p = 10 ** Math.floor(Math.log10(raw));
  const f = raw / p;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * p;
}

export function tickLabel(v, step) {
  if (Math.abs(v) < step * 1e-6) return '0';
  const a = Math.abs(v);
  if (a >= 1e5 || step < 1e-4) return v.toExponential(1);
  return v.toFixed(Math.max(0, -Math.floor(Math.log10(step) + 1e-9)));
}
