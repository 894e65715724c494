// The Export view: the share link, the command and scenario file, the time series as CSV
// or NPY, and the PNG of the last view's pictures.
import { $, FONT, FONT_B, unitOf, fmt, el } from './util.js';
import { HISTORY_MAX, lab, st, timeUnit, trackLabel } from './state.js';
import { shareUrl } from './share.js';
import { showView } from './tabs.js';
import { redrawView } from './views.js';

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
export function exportFigure() {
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

export function initExports() {
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
