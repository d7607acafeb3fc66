// The page's state in the URL (after #): JSON, deflated when the browser can, in base64url.
// "#z=..." is deflated, "#j=..." plain; both restore the same state.

function toB64url(bytes) {
  let s = "";
  for (let i = 0; i < bytes.length; i += 0x8000) {
    s += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  }
  return btoa(s).replace(/\+/g, "-").replace(/\//g, "_").replace(/=+$/, "");
}

function fromB64url(text) {
  const b = atob(text.replace(/-/g, "+").replace(/_/g, "/"));
  const out = new Uint8Array(b.length);
  for (let i = 0; i < b.length; i++) out[i] = b.charCodeAt(i);
  return out;
}

async function pipe(bytes, stream) {
  const out = new Response(new Blob([bytes]).stream().pipeThrough(stream));
  return new Uint8Array(await out.arrayBuffer());
}

export async function encodeState(obj) {
  const raw = new TextEncoder().encode(JSON.stringify(obj));
  if (typeof CompressionStream === "function") {
    return "z=" + toB64url(await pipe(raw, new CompressionStream("deflate-raw")));
  }
  return "j=" + toB64url(raw);
}

// the state of a hash ("#z=..." or "#j=..."), or null when there is none
export async function decodeState(hash) {
  const h = (hash || "").replace(/^#/, "");
  if (!h) return null;
  const kind = h.slice(0, 2), body = h.slice(2);
  if (kind !== "z=" && kind !== "j=") return null;
  if (kind === "z=" && typeof DecompressionStream !== "function") {
    throw new Error("this browser cannot read a compressed link (no DecompressionStream)");
  }
  let obj;
  try {
    const bytes = fromB64url(body);
    const raw = kind === "z=" ? await pipe(bytes, new DecompressionStream("deflate-raw")) : bytes;
    obj = JSON.parse(new TextDecoder().decode(raw));
  } catch (e) {
    throw new Error("this link is damaged: it does not unpack to the page's state");
  }
  if (!obj || typeof obj !== "object" || obj.v !== 1) throw new Error("not a pathfuse link (version)");
  return obj;
}
