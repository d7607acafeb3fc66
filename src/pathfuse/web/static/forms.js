// Parameter forms generated from the registry's parameter metadata (GET /api/planners):
// one input per field, by kind (float, int, bool, choice, str), with its unit, bounds,
// default and help text.  Nothing here knows any planner by name.

// One colour per planner, in the registry's order (astar, astar-replan, apf, fusion, ref6,
// ref7, astar-smooth, thetastar, lazy-thetastar, shortest, dwa, mppi, jps).  Chosen so that any two
// differ by a CIEDE2000 distance of at least 12 for normal vision and for simulated
// protanopia, deuteranopia and tritanopia (Machado et al. 2009, severity 1), with a contrast
// of at least 2.2:1 on the white map; the browser test checks the colours the page shows.
// (No chromatic 13th colour keeps that distance; black does.)  A 14th planner (a plug-in)
// starts the colours again, drawn dashed.
export const PALETTE = ["#00568F", "#74C200", "#33BBEE", "#DC1867", "#9B8427", "#8F0056",
  "#5C5CFF", "#AE1313", "#27849B", "#777777", "#DE907C", "#0000F5", "#000000"];

function el(tag, attrs = {}, ...kids) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "text") e.textContent = v;
    else if (k in e && k !== "list") e[k] = v;
    else e.setAttribute(k, v);
  }
  for (const k of kids) if (k) e.append(k);
  return e;
}
export { el };

function numberInput(p) {
  const inp = el("input", { type: "number", step: p.kind === "int" ? "1" : "any" });
  const lo = p.ge ?? p.gt;
  if (lo != null) inp.min = lo;
  if (p.le != null) inp.max = p.le;
  if (p.default == null) inp.placeholder = "default";
  else inp.value = p.default;
  return inp;
}

// read a field's input: {ok, value, isDefault, error}
function readInput(p, inp) {
  if (p.kind === "bool") return { ok: true, value: inp.checked, isDefault: inp.checked === p.default };
  if (p.kind === "choice" || p.kind === "str") {
    return { ok: true, value: inp.value, isDefault: inp.value === p.default };
  }
  const raw = inp.value.trim();
  if (raw === "") {
    if (p.optional || p.default == null) return { ok: true, value: null, isDefault: p.default == null };
    return { ok: false, error: `${p.name}: must be ${p.accepts}` };
  }
  const v = Number(raw);
  if (!Number.isFinite(v) || (p.kind === "int" && !Number.isInteger(v))) {
    return { ok: false, error: `${p.name}: must be ${p.accepts}, got ${JSON.stringify(raw)}` };
  }
  return { ok: true, value: v, isDefault: v === p.default };
}

// the form of one planner; onChange() is called after every edit
export function plannerForm(planner, color, onChange) {
  const inputs = new Map();
  const check = el("input", { type: "checkbox", value: planner.name });
  check.dataset.planner = planner.name;
  const head = el("label", { className: "head" }, check,
    el("span", { className: "swatch", style: `background:${color}` }),
    el("b", { text: planner.name }),
    el("span", { className: "desc", text: planner.online ? "" : " (offline only)" }));
  const body = el("div");
  for (const p of planner.params) {
    let inp;
    if (p.kind === "bool") {
      inp = el("input", { type: "checkbox", checked: !!p.default });
    } else if (p.kind === "choice") {
      inp = el("select");
      for (const c of p.choices) inp.append(el("option", { value: c, text: c, selected: c === p.default }));
    } else if (p.kind === "str") {
      inp = el("input", { type: "text", value: p.default ?? "" });
    } else {
      inp = numberInput(p);
    }
    inp.name = `${planner.name}.${p.name}`;
    inp.title = `${p.help} (${p.accepts}; default ${p.default === null ? "derived" : p.default})`;
    inp.addEventListener("change", onChange);
    inputs.set(p.name, inp);
    const unit = p.unit ? ` [${p.unit}]` : "";
    body.append(el("div", { className: "param" },
      el("label", { text: p.name + unit }), inp,
      el("div", { className: "help", text: `${p.help} — ${p.accepts}` })));
  }
  const details = el("details", {}, el("summary", { text: `parameters (${planner.params.length})` }), body);
  const box = el("div", { className: "planner" }, head,
    el("div", { className: "desc", text: planner.description }), details);
  check.addEventListener("change", onChange);
  return {
    box, check, name: planner.name, planner,
    // the non-default values as a params dict; throws with the first bad field's message
    params() {
      const out = {};
      for (const p of planner.params) {
        const inp = inputs.get(p.name);
        const r = readInput(p, inp);
        inp.classList.toggle("bad", !r.ok);
        if (!r.ok) throw new Error(`${planner.name}.${r.error}`);
        if (!r.isDefault) out[p.name] = r.value;
      }
      return out;
    },
    // every field back to its default
    reset() {
      for (const p of planner.params) {
        const inp = inputs.get(p.name);
        if (inp.type === "checkbox") inp.checked = !!p.default;
        else inp.value = p.default ?? "";
        inp.classList.remove("bad");
      }
    },
    set(values) {
      for (const [k, v] of Object.entries(values || {})) {
        const inp = inputs.get(k);
        if (!inp) continue;
        if (inp.type === "checkbox") inp.checked = !!v; else inp.value = v ?? "";
      }
    },
    markBad(message) {
      for (const [k, inp] of inputs) inp.classList.toggle("bad", message.includes(`.${k}:`));
    },
  };
}
