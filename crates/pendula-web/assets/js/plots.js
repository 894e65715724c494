// The charts: one plot routine for every chart on the page.
import { FONT, FONT_B, withUnit, fitCanvas, legendLayout, drawLegend, niceStep, tickLabel } from './util.js';
import { lab, st, timeUnit } from './state.js';

// One plot routine for every chart. Series: {data, x(p), y(p), colour, label, dots}.
// With logY the y accessor already returns log10 values and ticks fall on whole decades.
export function drawPlot(canvas, o) {
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

export const log10pos = (v) => (v > 0 ? Math.log10(v) : NaN);

export const tLabel = () => withUnit('t', timeUnit());

export function stateAxis(i) { const s = lab.config.state[i]; return s ? withUnit(s.name, s.unit) : `s${i}`; }
