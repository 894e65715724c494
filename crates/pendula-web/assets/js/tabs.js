// The tabs: which view shows.
import { $ } from './util.js';
import { st } from './state.js';

const VIEW_NAMES = { 'view-sim': 'Simulation', 'view-graphs': 'Graphs', 'view-fractal': 'Flip fractal' };

export function showView(id) {
  st.view = id;
  for (const b of document.querySelectorAll('.tab')) b.classList.toggle('active', b.dataset.view === id);
  for (const s of document.querySelectorAll('.view')) s.hidden = s.id !== id;
  // The studies' pictures are the server's PNGs, saved from the page itself.
  if (id !== 'view-export' && id !== 'view-studies') st.lastPictureView = id;
  $('export-png').textContent = `Picture (PNG) of the ${VIEW_NAMES[st.lastPictureView]} view`;
  st.plotsDirty = true;
  st.fractalDirty = true;
}
