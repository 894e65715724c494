// The Simulation view: its controls, built from the server's config, and what it shows
// beside the pendulum (the energies, the energy error plot, the butterfly's separation).
import { $, DEG, unitOf, isNum, fmt, el } from './util.js';
import { TRAIL_GAP, lab, st, timeUnit, energyUnit, trackColour, trackLabel, frameGap } from './state.js';
import { send, configure } from './connection.js';
import { shareUrl } from './share.js';
import { drawPlot, log10pos, tLabel } from './plots.js';
import { buildGraphSelects } from './view-graphs.js';

// The system whose parameter and state controls are built (rebuilt when it changes).
let controlsKey = '';

export function applyConfig(cfg) {
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
  if (key !== controlsKey) {
    controlsKey = key;
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

export function onRaceChange() {
  const chosen = [...$('race-methods').querySelectorAll('input:checked')].map((c) => c.value);
  if (chosen.length < 2 || chosen.length > 4) {
    $('race-hint').textContent = `Choose 2 to 4 methods (${chosen.length} chosen): nothing sent yet.`;
    return;
  }
  $('race-hint').textContent = '';
  configure({ methods: chosen });
}

// The Simulation view's controls: each sends its command (a configure restarts the run).
export function initSimControls() {
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
}

export function updateNumbers() {
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

export function drawEnergyPlot() {
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

export function drawSeparationPlot() {
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
  // The window's bounds as the server fits them (before its first message, as it will).
  const from = g ? fmt(g.fit_from, 3) : 'min(100 δ, 0.01)', to = g ? fmt(g.saturation, 3) : '0.1';
  const over = fit && `t = ${fmt(fit.a, 3)}…${fmt(fit.b, 3)}${tu ? ' ' + tu : ''}`;
  const distance = 'ln(distance of k=1 from k=0)';
  $('growth-rate').textContent = !fit
    ? (g && g.final
      ? `λ: not measurable: the distance of k=1 from k=0 passed ${to} with fewer than 3 samples above ${from}`
      : `λ: not yet measured (the fit of ${distance} starts when it passes ${from} and ends at ${to})`)
    : `λ ≈ ${fmt(fit.slope, 3)} ${tu ? '1/' + tu : '(per unit time)'}` + (fit.final
      ? `: the slope of ${distance} while it grew from ${from} to ${to}, fitted over ${over} (dashed line)`
      : ` so far: the slope of ${distance} since it passed ${from}, over ${over} (dashed line); final once it passes ${to}`);
}
