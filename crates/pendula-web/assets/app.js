// pendula lab: the browser side of `pendula serve`. The physics runs on the server (see
// PROTOCOL.md); the page only draws what arrives over the WebSocket and sends the user's
// commands. This entry module routes the server's messages to the modules under js/ —
// util (helpers), state (what the page knows), messages, connection, share, tabs, drawing
// (the pendulum), plots, one module per view (view-sim, view-graphs, view-fractal,
// view-export, view-studies) and views (redrawing one) — and runs the drawing loop.
import { $, isNum, fmt, el, fillOptions } from './js/util.js';
import { lab, st, resetHistories, onGrowth, onSimFrame, timeUnit } from './js/state.js';
import { showNotice, showError } from './js/messages.js';
import { send, connect } from './js/connection.js';
import { shareFromHash, shareUrl } from './js/share.js';
import { showView } from './js/tabs.js';
import { drawSim, bobClientPositions, initDrag } from './js/drawing.js';
import { applyConfig, onRaceChange, initSimControls, updateNumbers, drawEnergyPlot, drawSeparationPlot } from './js/view-sim.js';
import { drawGraphs, initGraphControls } from './js/view-graphs.js';
import { onFractalFrame, fractalNote, drawFractal, fractalPixelClient, initFractal } from './js/view-fractal.js';
import { exportFigure, initExports } from './js/view-export.js';
import { onStudies, onStudyResult, onStudyRefused, initStudies } from './js/view-studies.js';

// Config messages whose share must not replace the address's fragment (the defaults sent on
// connecting, before the fragment's own configure is answered), and when the charts were
// last drawn.
let skipHashUpdates = 0;
let lastPlotDraw = 0;

function handleMessage(msg) {
  switch (msg.type) {
    case 'hello': onHello(msg); break;
    case 'config': onConfig(msg); break;
    case 'error':
      showError(`${msg.command ? msg.command + ' refused' : 'refused'}: ${msg.message}`, msg.message);
      onRefused(msg);
      break;
    case 'growth': onGrowth(msg); break;
    case 'study': onStudyResult(msg); break;
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

function onHello(msg) {
  lab.hello = msg;
  fillOptions($('system'), msg.systems.map((s) => [s.name, s.name, s.description]));
  fillOptions($('method'), msg.methods.map((m) => [m.name, `${m.title || m.name} (order ${m.order})`, m.name]));
  fillOptions($('fractal-method'), (msg.fractal_methods || ['rk4']).map((m) => [m, m, m]));
  onStudies(msg);
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
    skipHashUpdates = 1;
    send(Object.assign({ cmd: 'configure' }, share));
  }
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
  if (skipHashUpdates > 0) skipHashUpdates--;
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
  if (msg.command === 'study') onStudyRefused();
  if (msg.command === 'fractal') $('fractal-info').textContent = 'The fractal was refused: see the message above.';
  if (lab.config && (msg.command === 'configure' || msg.command === 'set_state' || msg.command === null)) applyConfig(lab.config);
}

function loop(now) {
  if (st.view === 'view-sim') drawSim();
  // charts at ~10 Hz: thousands of points per track need not follow every display frame
  if (st.plotsDirty && now - lastPlotDraw > 100) {
    st.plotsDirty = false;
    lastPlotDraw = now;
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

// What the tests (and a curious user's console) reach as window.lab: the state, and these.
Object.assign(lab, { send, bobClientPositions, fractalPixelClient, shareUrl, exportFigure });
window.lab = lab;

for (const b of document.querySelectorAll('.tab')) b.addEventListener('click', () => showView(b.dataset.view));
$('error-close').addEventListener('click', () => { $('error').hidden = true; $('error-list').textContent = ''; });
window.addEventListener('resize', () => { st.plotsDirty = true; st.fractalDirty = true; });
initSimControls();
initGraphControls();
initDrag();
initFractal();
initExports();
initStudies();
showView('view-sim');
connect({ text: handleMessage, binary: handleBinary });
requestAnimationFrame(loop);
