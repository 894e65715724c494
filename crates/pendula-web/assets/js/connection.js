// The connection to `pendula serve`: one WebSocket (PROTOCOL.md), commands out as JSON,
// the server's messages handed to the handlers connect() is given; reconnects, and says why
// when it cannot.
import { $ } from './util.js';
import { lab } from './state.js';
import { showError } from './messages.js';

// The access token printed by `pendula serve`, from the page's address.
export const token = new URLSearchParams(location.search).get('token');
const conn = { ws: null, retries: 0, everOpened: false };

function setStatus(text, cls) {
  const s = $('status');
  s.textContent = text;
  s.className = 'status' + (cls ? ' ' + cls : '');
}

export function send(obj) {
  if (!conn.ws || conn.ws.readyState !== WebSocket.OPEN) {
    showError('Not connected to the server: the command was not sent.');
    return false;
  }
  conn.ws.send(JSON.stringify(obj));
  return true;
}

// Opens the WebSocket; `handlers.text(msg)` gets each JSON message, `handlers.binary(a)` each
// binary one as a Float64Array.
export function connect(handlers) {
  if (!token) {
    setStatus('No access token in the address', 'bad');
    showError('This page needs the access token printed by `pendula serve`: open the full URL it prints (it ends in ?token=…).');
    return;
  }
  const proto = location.protocol === 'https:' ? 'wss' : 'ws';
  const ws = new WebSocket(`${proto}://${location.host}/ws?token=${encodeURIComponent(token)}`);
  ws.binaryType = 'arraybuffer';
  conn.ws = ws;
  lab.socketAttempts++;
  setStatus('connecting…');
  let opened = false;
  ws.onopen = () => {
    opened = true;
    conn.everOpened = true;
    conn.retries = 0;
    lab.connected = true;
    setStatus('connected', 'ok');
  };
  ws.onmessage = (ev) => {
    if (typeof ev.data === 'string') {
      let msg;
      try { msg = JSON.parse(ev.data); } catch (err) { showError('Unreadable message from the server: ' + err.message); return; }
      handlers.text(msg);
    } else {
      const buf = ev.data;
      if (buf.byteLength % 8 !== 0 || buf.byteLength < 8) return;
      handlers.binary(new Float64Array(buf));
    }
  };
  ws.onclose = async () => {
    lab.connected = false;
    conn.ws = null;
    let why = 'disconnected';
    if (!opened) {
      // The browser hides the HTTP status of a refused upgrade: ask the same address plainly.
      const refusal = await whyRefused();
      if (refusal.fatal) {
        lab.gaveUp = true;
        const token = /token/.test(refusal.message);
        setStatus(token ? 'refused: wrong access token' : 'refused by the server', 'bad');
        showError(`The server refused this page: ${refusal.message}. ` +
          (token ? 'Open the URL that `pendula serve` printed in its terminal, token included (…/?token=…); each start of the server makes a new token. ' : '') +
          'This page does not retry.');
        return;
      }
      why = refusal.message;
    }
    const delay = Math.min(10, 1 + conn.retries++ * 2);
    setStatus(`${why}: retrying in ${delay} s`, 'bad');
    setTimeout(() => connect(handlers), delay * 1000);
  };
}

// Why the WebSocket did not open, from a plain GET of its address (PROTOCOL.md): a wrong
// token (403) is fatal, as no retry can mend it; a full server (503) or no answer may pass.
async function whyRefused() {
  try {
    const r = await fetch(`/ws?token=${encodeURIComponent(token)}`, { cache: 'no-store' });
    const text = (await r.text()).trim().slice(0, 200);
    if (r.status === 403) return { fatal: true, message: text || 'HTTP 403' };
    if (r.status === 503) return { fatal: false, message: `the server is full: ${text}; close another lab page` };
    return { fatal: false, message: 'could not connect' };
  } catch (_) {
    return { fatal: false, message: 'the server does not answer (stopped?)' };
  }
}

// A change of configuration, the command most controls send (the run restarts).
export function configure(fields) { return send(Object.assign({ cmd: 'configure' }, fields)); }
