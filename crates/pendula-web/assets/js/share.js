// The share link: the URL fragment holds the last accepted configuration (PROTOCOL.md).
import { lab } from './state.js';

// The fragment holds the last accepted `share`; replaying it after hello reopens a shared or
// reloaded page where it was. Only configure's own fields go out: anything else is refused.
const CONFIGURE_FIELDS = ['system', 'params', 'state', 'method', 'dt', 'mode', 'methods', 'count', 'delta', 'speed', 'poincare'];

// Returns {share, problem}: the fields to send (or null), and what could not be read of a
// fragment that is there (or null), for the page to say rather than open the defaults silently.
export function shareFromHash() {
  if (location.hash.length < 2) return { share: null, problem: null };
  let text, obj;
  try {
    text = decodeURIComponent(location.hash.slice(1));
  } catch (_) {
    return { share: null, problem: 'it is not URL-encoded text' };
  }
  try {
    obj = JSON.parse(text);
  } catch (err) {
    return { share: null, problem: `it is not JSON (${err.message})` };
  }
  if (!obj || typeof obj !== 'object' || Array.isArray(obj)) {
    return { share: null, problem: 'it is not a JSON object of settings' };
  }
  const out = {};
  for (const k of CONFIGURE_FIELDS) if (k in obj) out[k] = obj[k];
  const unknown = Object.keys(obj).filter((k) => !CONFIGURE_FIELDS.includes(k));
  const problem = unknown.length
    ? `unknown ${unknown.length > 1 ? 'fields' : 'field'} ${unknown.slice(0, 5).map((k) => JSON.stringify(k).slice(0, 40)).join(', ')}${unknown.length > 5 ? ', …' : ''} (known: ${CONFIGURE_FIELDS.join(', ')})`
    : null;
  return { share: Object.keys(out).length ? out : null, problem };
}

export function shareUrl() {
  const share = lab.config ? lab.config.share : shareFromHash().share;
  const hash = share ? '#' + encodeURIComponent(JSON.stringify(share)) : '';
  return location.origin + location.pathname + location.search + hash;
}
