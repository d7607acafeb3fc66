// The JSON API of pathfuse serve, and the packed-bits form of a grid.

export class ApiError extends Error {
  constructor(status, message) { super(message); this.status = status; }
}

async function answer(resp) {
  let data = null;
  try { data = await resp.json(); } catch (e) {
    if (isAbort(e)) throw e;  // aborted while the body was read
    if (resp.ok) throw new ApiError(resp.status, `HTTP ${resp.status}: the answer is not JSON`);
  }
  if (!resp.ok) {
    const msg = data && data.error ? data.error : `HTTP ${resp.status}`;
    throw new ApiError(resp.status, msg);
  }
  return data;
}

export async function getJSON(url, { signal } = {}) {
  return answer(await fetch(url, { signal }));
}

// signal: an AbortSignal; aborting it cancels the request (the server then stops its work)
export async function postJSON(url, body, { signal } = {}) {
  return answer(await fetch(url, {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body),
    signal,
  }));
}

export function isAbort(e) { return e && e.name === "AbortError"; }

export async function postFiles(url, files, fields = {}) {
  const form = new FormData();
  for (const f of files) form.append("file", f, f.name);
  for (const [k, v] of Object.entries(fields)) if (v !== "" && v != null) form.append(k, v);
  return answer(await fetch(url, { method: "POST", body: form }));
}

// base64 of numpy.packbits (big-endian bits, row-major, row 0 = bottom row) -> Uint8Array of 0/1
export function unpackBits(b64, n) {
  const bin = atob(b64);
  const out = new Uint8Array(n);
  for (let i = 0; i < n; i++) {
    out[i] = (bin.charCodeAt(i >> 3) >> (7 - (i & 7))) & 1;
  }
  return out;
}

export function packBits(cells) {
  const n = cells.length;
  const bytes = new Uint8Array((n + 7) >> 3);
  for (let i = 0; i < n; i++) if (cells[i]) bytes[i >> 3] |= 0x80 >> (i & 7);
  let s = "";
  const CH = 0x8000;
  for (let i = 0; i < bytes.length; i += CH) {
    s += String.fromCharCode.apply(null, bytes.subarray(i, i + CH));
  }
  return btoa(s);
}

function bytesOf(b64) {
  const bin = atob(b64);
  const u8 = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) u8[i] = bin.charCodeAt(i);
  return u8;
}

export function float32s(b64) { return new Float32Array(bytesOf(b64).buffer); }

// base64 of little-endian int32 (the closed set's expansion order)
export function int32s(b64) {
  const u8 = bytesOf(b64);
  const dv = new DataView(u8.buffer), out = new Int32Array(u8.length >> 2);
  for (let i = 0; i < out.length; i++) out[i] = dv.getInt32(4 * i, true);
  return out;
}
