// Redrawing a view at once, whole (the PNG export draws its pictures this way).
import { lab } from './state.js';
import { drawSim } from './drawing.js';
import { updateNumbers, drawEnergyPlot, drawSeparationPlot } from './view-sim.js';
import { drawGraphs } from './view-graphs.js';
import { drawFractal } from './view-fractal.js';

export function redrawView(view) {
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
