// The Graphs view: a time series, a phase portrait and the live Poincaré section.
import { $, withUnit, fillOptions } from './util.js';
import { lab, st, trackColour, trackLabel } from './state.js';
import { drawPlot, log10pos, tLabel, stateAxis } from './plots.js';

// The system the graph choices were made on (they are kept only within one).
const chosen = { system: null, dim: 0 };

export function drawGraphs() {
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

export function buildGraphSelects(cfg) {
  const names = cfg.state.map((s, i) => [String(i), withUnit(s.name, s.unit), s.description]);
  // Choices are kept only within one system: index 1 is theta2 on one and omega on another.
  const same = chosen.system === cfg.system && chosen.dim === cfg.state.length;
  chosen.system = cfg.system; chosen.dim = cfg.state.length;
  const keep = same ? [$('ts-var').value, $('phase-x').value, $('phase-y').value] : [];
  fillOptions($('ts-var'), [...names, ['energy', 'energy error |E − E₀| / scale', 'relative energy error']]);
  fillOptions($('phase-x'), names);
  fillOptions($('phase-y'), names);
  // default portrait: first position against its velocity
  $('ts-var').value = keep[0] || '0';
  $('phase-x').value = keep[1] || '0';
  $('phase-y').value = keep[2] || String(Math.min(cfg.positions, cfg.state.length - 1));
}

export function initGraphControls() {
  for (const id of ['ts-var', 'phase-x', 'phase-y']) $(id).addEventListener('change', () => { st.plotsDirty = true; });
}
