// What the page tells the user in its message box: the server's refusals and the page's
// own errors (kept in lab.errors), and notes (kept in lab.notices).
import { $, el } from './util.js';
import { lab } from './state.js';

// A note, not a refusal: shown where refusals are, kept in lab.notices.
export function showNotice(text) {
  lab.notices.push(text);
  showError(`Note: ${text}`, undefined, false);
}

export function showError(text, raw, record = true) {
  if (record) lab.errors.push(raw === undefined ? text : raw);
  const list = $('error-list');
  const li = el('li', null, text);
  list.append(li);
  while (list.children.length > 6) list.firstChild.remove();
  $('error').hidden = false;
}

