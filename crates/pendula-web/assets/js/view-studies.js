// The Studies view: every study of the library's registry (pendula::study::STUDIES, listed in
// `hello`), a form built from its parameters (their defaults and units are the library's,
// shown as placeholders), and its report as the server sends it: the summary, the numbers,
// and the plots pendula-viz drew (the figures `pendula STUDY` writes).
import { $, el, fmt, fillOptions } from './util.js';
import { lab } from './state.js';
import { send } from './connection.js';

let studies = [];

function current() {
  return studies.find((s) => s.name === $('study-name').value) || studies[0];
}

// The form of the chosen study: one field per parameter, empty for its default.
function buildForm() {
  const s = current();
  if (!s) return;
  $('study-about').textContent = s.about + '.';
  const form = $('study-form');
  form.textContent = '';
  for (const p of s.params) {
    if (p.kind === 'fixed-system') continue;
    const lbl = el('label');
    lbl.append(document.createTextNode(p.name.replace(/_/g, ' ') + ' '));
    let input;
    if (p.kind === 'system' || p.kind === 'method') {
      input = el('select');
      const list = p.kind === 'system' ? lab.hello.systems : lab.hello.methods;
      fillOptions(input, [['', `default: ${p.default}`, p.help], ...list.map((x) => [x.name, x.name, x.description || x.title || x.name])]);
    } else if (p.kind === 'preset') {
      input = el('select');
      fillOptions(input, [['', p.default, p.help], ...p.choices.map((x) => [x, x, x])]);
    } else if (p.kind === 'flag') {
      input = el('input');
      input.type = 'checkbox';
    } else {
      input = el('input');
      input.type = 'text';
      input.inputMode = 'decimal';
      const unit = p.unit === 'time' ? 's' : p.unit;
      input.placeholder = `${p.default}${unit ? ' ' + unit : ''}`;
    }
    input.dataset.param = p.name;
    input.dataset.kind = p.kind;
    input.title = p.help;
    lbl.append(input);
    form.append(lbl);
  }
  const set = el('label');
  set.append(document.createTextNode('set '));
  const field = el('input');
  field.type = 'text';
  field.id = 'study-set';
  field.placeholder = 'e.g. damping=0.3, theta1=2';
  field.title = "The system's parameters and start state, NAME=VALUE, comma-separated (SI units, angles in rad)";
  set.append(field);
  form.append(set);
}

// The command: the fields given (empty ones take the study's defaults) and the settings.
function request() {
  const inputs = {};
  for (const input of $('study-form').querySelectorAll('[data-param]')) {
    if (input.dataset.kind === 'flag') {
      if (input.checked) inputs[input.dataset.param] = true;
      continue;
    }
    const text = input.value.trim();
    if (!text) continue;
    const kind = input.dataset.kind;
    // A number field that does not read as one goes as text: the server names it and says why.
    inputs[input.dataset.param] = kind === 'real' || kind === 'count' ? (Number.isFinite(Number(text)) ? Number(text) : text) : text;
  }
  const set = {};
  for (const item of $('study-set').value.split(',').map((x) => x.trim()).filter(Boolean)) {
    const [name, value] = item.split('=').map((x) => (x || '').trim());
    // A value that does not read as a number goes as text: the server names it.
    set[name] = Number.isFinite(Number(value)) && value !== '' ? Number(value) : value;
  }
  return { cmd: 'study', name: current().name, inputs, set };
}

export function onStudies(hello) {
  studies = hello.studies || [];
  fillOptions($('study-name'), studies.map((s) => [s.name, s.name, s.about]));
  buildForm();
}

export function onStudyResult(msg) {
  lab.study = msg;
  $('study-status').textContent = '';
  const out = $('study-result');
  out.textContent = '';
  for (const line of msg.summary) out.append(el('p', 'study-summary', line));
  const table = el('table', 'numbers');
  for (const n of msg.numbers) {
    const tr = el('tr');
    tr.append(el('th', null, n.about), el('td', null, `${fmt(n.value, 6)}${n.unit ? ' ' + n.unit : ''}`));
    table.append(tr);
  }
  out.append(table);
  // The tables short enough to show whole (a time series only goes to files).
  for (const t of msg.tables.filter((x) => x.shown)) {
    const rows = el('table', 'study-table');
    const head = el('tr');
    for (const c of t.columns) head.append(el('th', null, c.unit ? `${c.name} (${c.unit})` : c.name));
    rows.append(head);
    for (let i = 0; i < (t.columns[0] ? t.columns[0].values.length : 0); i++) {
      const tr = el('tr');
      // fmt shows a missing number (null) as a dash and text (a method, a note) as it is.
      for (const c of t.columns) tr.append(el('td', null, fmt(c.values[i], 6)));
      rows.append(tr);
    }
    out.append(rows);
  }
  for (const p of msg.plots) {
    const img = el('img', 'study-plot');
    img.alt = p.title;
    img.src = `data:image/png;base64,${p.png}`;
    out.append(img);
  }
}

export function onStudyRefused() {
  $('study-status').textContent = 'Refused: see the message above.';
}

export function initStudies() {
  $('study-name').addEventListener('change', buildForm);
  $('study-run').addEventListener('click', () => {
    $('study-status').textContent = 'Running…';
    send(request());
  });
}
