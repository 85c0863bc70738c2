// afmforce serve: the page. Plain JavaScript + Plotly.js (served by the server; no network).
"use strict";
const $ = (id) => document.getElementById(id);
const el = (tag, attrs = {}, ...kids) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) { if (k === "text") e.textContent = v; else e.setAttribute(k, v); }
  kids.forEach((k) => e.append(k));
  return e;
};
// Plotly.js is loaded once the page is ready (or when a plot is first drawn, if sooner): every
// drawing entry point awaits it
let PLOTLY = null;
function plotlyLoaded() {
  if (window.Plotly) return Promise.resolve();
  PLOTLY = PLOTLY || new Promise((done, fail) => {
    const tag = el("script", { src: "static/plotly.min.js", id: "plotly-js" });
    tag.addEventListener("load", () => { guardLayouts(); done(); }, { once: true });
    tag.addEventListener("error", () => { PLOTLY = null; fail(new Error("Plotly.js did not load")); }, { once: true });
    document.head.append(tag);
  });
  return PLOTLY;
}
// every plot's layout, checked in one place before Plotly draws it (issue 33.5; a browser test reads the
// boxes): a title wrapped to the plot's width (the top margin grows with its lines), axes whose
// titles make room for their tick labels (automargin), colour bars inside the drawing
function guardLayout(gd, data, layout) {
  const div = typeof gd === "string" ? document.getElementById(gd) : gd;
  const out = { ...layout, margin: { ...(layout.margin || {}) } };
  const t = out.title && (typeof out.title === "string" ? { text: out.title } : out.title);
  if (t && t.text) {
    const per = Math.max(24, Math.floor(((div && div.clientWidth) || 600) / 8.5) - 4);
    const lines = wrapText(String(t.text), per);
    out.title = { ...t, text: lines.join("<br>"), font: { size: 14, ...(t.font || {}) } };
    out.margin.t = Math.max(out.margin.t || 0, 22 + 18 * lines.length);
  }
  for (const k of Object.keys(out)) if (/^[xy]axis\d*$/.test(k)) out[k] = { automargin: true, ...out[k] };
  // a colour bar's title runs along it: wrapped to the bar's length (a long quantity name overran the plot)
  const tall = Math.max(120, (((div && div.clientHeight) || 360) - (out.margin.t || 0) - (out.margin.b || 50)) * 0.85);
  const bars = (data || []).map((tr) => {
    if (!tr || !tr.colorbar) return tr;
    const cb = { len: 0.9, y: 0.5, yanchor: "middle", ...tr.colorbar };
    if (cb.title && cb.title.text) cb.title = { ...cb.title, text: wrapText(String(cb.title.text), Math.max(12, Math.floor(tall / 7.5))).join("<br>") };
    return { ...tr, colorbar: cb };
  });
  return [bars, out];
}
function wrapText(text, per) {   // lines of at most ``per`` characters, broken after a comma, colon or
  // dash or before a bracket (a number keeps its unit); a part still too long is broken at spaces
  const parts = [];
  for (const part of text.split(/(?<=[,:;—])\s+|\s+(?=[(\[—])/)) {
    if (part.length <= per) { parts.push(part); continue; }
    let line = "";
    for (const w of part.split(" ")) {
      if (line && (line + " " + w).length > per) { parts.push(line); line = w; } else line = line ? line + " " + w : w;
    }
    if (line) parts.push(line);
  }
  const lines = [];
  let line = "";
  for (const p of parts) {
    if (line && (line + " " + p).length > per) { lines.push(line); line = p; } else line = line ? line + " " + p : p;
  }
  if (line) lines.push(line);
  return lines;
}
function guardLayouts() {   // Plotly.react and Plotly.newPlot pass through guardLayout
  for (const name of ["react", "newPlot"]) {
    const draw = Plotly[name];
    Plotly[name] = (gd, data, layout, config) => { const [d, l] = guardLayout(gd, data, layout || {}); return draw(gd, d, l, config); };
  }
}
const SCHEMA = { simulation: [], analysis: {}, fit: [], examples: [], instrument_presets: [] };
// the legend outside the plot on the right (Plotly widens the margin for it): never over an axis title
const LAYOUT = { margin: { l: 70, r: 20, t: 40, b: 50 }, hovermode: "closest",
  legend: { orientation: "v", x: 1.02, xanchor: "left", y: 1, yanchor: "top", font: { size: 11 } } };
const CONFIG = { responsive: true, displaylogo: false, toImageButtonOptions: { format: "png", scale: 2 } };
const U = { m: [1e9, "nm"], N: [1e9, "nN"], s: [1, "s"], V: [1, "V"] };
const sc = (arr, f) => (arr || []).map((v) => (v === null ? null : v * f));
const fmt = (v, unit) => {
  if (v === null || v === undefined || (typeof v === "number" && !isFinite(v))) return "–";
  if (typeof v !== "number") return String(v);
  const p = { m: [[1e-6, "um", 1e6], [1e-9, "nm", 1e9], [0, "pm", 1e12]], N: [[1e-6, "uN", 1e6], [1e-9, "nN", 1e9], [0, "pN", 1e12]] }[unit];
  if (p && v !== 0) { for (const [lim, u, f] of p) if (Math.abs(v) >= lim) return `${(v * f).toPrecision(4)} ${u}`; }
  return `${Number(v.toPrecision(4))} ${unit || ""}`.trim();
};
// every refusal of the server is {"error": {"type", "message", "field"}} (docs/web.md)
function errorText(body, r) {
  const e = body && body.error;
  if (e && typeof e === "object") return e.message || e.type || r.statusText;
  return (typeof e === "string" && e) || `${r.status} ${r.statusText}`;
}
async function api(path, opts = {}) {
  const r = await fetch(path, opts);
  const text = await r.text();
  let body; try { body = JSON.parse(text); } catch { body = { error: { message: `${r.status} ${r.statusText}` } }; }
  if (!r.ok) { const err = new Error(errorText(body, r)); err.field = body.error && body.error.field; throw err; }
  return body;
}
function table(rows, head) {
  const t = el("table");
  if (head) t.append(el("tr", {}, ...head.map((h) => el("th", { text: h }))));
  rows.forEach((r) => t.append(el("tr", {}, ...r.map((c) => el("td", { text: c })))));
  return t;
}
function download(name, blob) {
  const a = el("a", { href: URL.createObjectURL(blob), download: name });
  document.body.append(a); a.click(); a.remove();
}

// ---- tabs -----------------------------------------------------------------------------------
document.querySelectorAll(".tab").forEach((b) => b.addEventListener("click", () => {
  document.querySelectorAll(".tab").forEach((x) => x.classList.toggle("active", x === b));
  document.querySelectorAll(".view").forEach((v) => v.classList.toggle("active", v.id === "view-" + b.dataset.view));
  window.dispatchEvent(new Event("resize"));
  if (b.dataset.view === "simulate" && !SIM.done) simulate();
  if (b.dataset.view === "sweep") listJobs();
}));

// ---- a control of one field (number with unit and range, choice, flag) ------------------------
function control(f, onChange, { slider = false, value = f.default } = {}) {
  const box = el("div", { class: "field", "data-name": f.name });
  const head = el("div", {}, el("span", { class: "name", text: f.name }), " ",
    el("span", { class: "range", text: f.shown ? `[${f.shown}] ${f.range || ""}` : "" }));
  box.append(head);
  if (f.help) box.title = f.help;
  let get;
  if (f.kind === "choice" || (f.choices && f.choices.length && f.kind !== "number")) {
    const s = el("select", { "data-field": f.name });
    (f.choices.length ? f.choices : [f.default]).forEach((c) => s.append(el("option", { value: c, text: (f.labels && f.labels[c]) ? `${f.labels[c]} (${c})` : c })));
    s.value = value ?? ""; s.addEventListener("change", onChange); box.append(s);
    get = () => s.value;
  } else if (f.kind === "flag") {
    const c = el("input", { type: "checkbox", "data-field": f.name }); c.checked = !!value;
    c.addEventListener("change", onChange); box.append(c); get = () => c.checked;
  } else {
    const num = el("input", { type: "text", class: "val", "data-field": f.name });
    const show = (si) => (si === null || si === undefined ? "" : typeof si === "string" ? si : String(Number((si / f.factor).toPrecision(6))));
    num.value = show(value);
    if (f.choices && f.choices.length) num.title = `a number or ${f.choices.join(", ")}`;
    box.append(num);
    get = () => {
      const t = num.value.trim();
      if (t === "") return null;
      return isFinite(Number(t)) ? Number(t) * f.factor : t;   // a word the option accepts (auto)
    };
    num.addEventListener("change", onChange);
    if (slider && f.lo !== null && f.hi !== null) {
      const lo = f.log ? Math.log10(Math.max(f.lo, f.hi * 1e-9) || 1e-30) : f.lo, hi = f.log ? Math.log10(f.hi) : f.hi;
      let vlo = lo, vhi = hi;   // a useful window: a decade around the default
      if (typeof f.default === "number" && f.default !== 0) {
        if (f.log) { vlo = Math.max(lo, Math.log10(Math.abs(f.default)) - 1.5); vhi = Math.min(hi, Math.log10(Math.abs(f.default)) + 1.5); }
        else { const w = Math.abs(f.default) * 3; vlo = Math.max(lo, f.default - w); vhi = Math.min(hi, f.default + w); }
      }
      const r = el("input", { type: "range", min: vlo, max: vhi, step: (vhi - vlo) / 200, "data-slider": f.name, "data-log": f.log ? "1" : "0" });
      const toSlider = (si) => (f.log ? Math.log10(Math.abs(si)) : si);
      if (typeof value === "number" && value !== 0) r.value = toSlider(value);
      r.addEventListener("input", () => { const si = f.log ? 10 ** Number(r.value) : Number(r.value); num.value = show(si); onChange(); });
      box.append(r);
    }
  }
  box.get = get;
  return box;
}

// ---- Analyse ----------------------------------------------------------------------------------
const AN = { payload: null, files: [], examples: [], controls: [], busy: false, next: null };
function optionTexts() {
  const out = [];
  for (const c of AN.controls) {
    const v = c.box.get();
    if (v === null || v === c.f.default || (typeof v === "number" && typeof c.f.default === "number" && Math.abs(v - c.f.default) <= 1e-12 * Math.abs(c.f.default))) continue;
    const shown = typeof v === "number" ? `${Number((v / c.f.factor).toPrecision(8))}${c.f.shown === "deg" ? "deg" : c.f.shown}` : String(v);
    out.push(`${c.step}.${c.f.name}=${shown}`);
  }
  return out;
}
async function analyse(upload) {
  if (AN.busy) { AN.next = upload || AN.next === "upload" ? "upload" : "rerun"; return; }   // the latest wins, an upload is never dropped
  AN.busy = true; $("an-error").textContent = ""; $("status").textContent = "analysing…";
  const fd = new FormData();
  if (upload) { for (const f of $("an-files").files) fd.append("file", f); }
  else AN.files.forEach((f) => fd.append("file_id", f.id));
  AN.examples.forEach((e) => fd.append("example", e));
  optionTexts().forEach((o) => fd.append("option", o));
  probeForm(fd);
  settingsForm(fd);
  fd.append("arrays", "true");
  plotRequest(fd);
  try {
    const t0 = performance.now();
    const p = await api("api/analyze", { method: "POST", body: fd });
    AN.fetched = performance.now();
    await plotlyLoaded();
    if (upload) { AN.files = p.files; listUploads(); }
    AN.payload = p;
    $("an-time").textContent = `${((performance.now() - t0) / 1000).toFixed(2)} s, server ${p.wall_time.toFixed(2)} s`;
    const names = Object.keys(p.results);
    const sel = $("an-curve"), keep = sel.value;
    sel.innerHTML = ""; names.forEach((n) => sel.append(el("option", { value: n, text: n })));
    if (names.includes(keep)) sel.value = keep;
    if (AN.restoreCurve && names.includes(AN.restoreCurve)) { sel.value = AN.restoreCurve; AN.restoreCurve = null; }
    if (p.failed.length) $("an-error").textContent = p.failed.map((f) => (f.error.startsWith(f.file) ? f.error : `${f.file}${f.curve !== undefined ? "#" + f.curve : ""}: ${f.error}`)).join("\n");
    drawMaps(p.maps || []);
    drawBatch();
    if (names.length) drawCurve(); else ["an-plot-force", "an-plot-raw", "an-plot-time", "an-plot-compliance"].forEach((i) => Plotly.purge(i));
    await recordAnalyseLatency(t0, p);
  } catch (e) { $("an-error").textContent = e.message; }
  saveAnalyse();
  AN.busy = false; $("status").textContent = "";
  if (AN.next) { const up = AN.next === "upload"; AN.next = null; analyse(up); }
}
// what the plots need: samples for the screen's width (each pixel column's min and max, thinned by the
// server), the arrays of the curve shown only (another curve's are asked for when it is shown)
function plotRequest(fd, curve) {
  const w = ($("an-plot-force").clientWidth || 700);
  fd.append("max_points", String(Math.max(400, Math.min(4000, 2 * Math.round(w)))));
  fd.append("curve", curve !== undefined ? curve : AN.restoreCurve || $("an-curve").value || "");
}
async function loadCurveArrays(name) {   // a curve of a batch or map drawn for the first time
  if (AN.loading === name) return;
  AN.loading = name;
  const fd = new FormData();
  AN.files.forEach((f) => fd.append("file_id", f.id));
  AN.examples.forEach((e) => fd.append("example", e));
  optionTexts().forEach((o) => fd.append("option", o));
  probeForm(fd);
  settingsForm(fd);
  fd.append("arrays", "true");
  plotRequest(fd, name);
  try {
    const p = await api("api/analyze", { method: "POST", body: fd });
    for (const n of p.arrays_for || []) {
      if (AN.payload.results[n] && p.results[n]) AN.payload.results[n] = p.results[n];
      if (p.raw && p.raw[n]) (AN.payload.raw = AN.payload.raw || {})[n] = p.raw[n];
    }
  } catch (e) { $("an-error").textContent = e.message; }
  AN.loading = null;
  if ($("an-curve").value === name && AN.payload.results[name] && AN.payload.results[name].separation) drawCurve();
}
// a plot redrawn only when what it shows changed (a calibration leaves the raw signal as it was)
function changed(id, key) {
  const div = $(id);
  if (div.drawnKey === key && div.data) return false;
  div.drawnKey = key;
  return true;
}
function rawKey(name, raw, d) {
  const n = raw ? raw.signal.length : 0;
  return JSON.stringify([name, n, raw && raw.signal[0], raw && raw.signal[n >> 1], raw && raw.signal[n - 1], raw && raw.time[n - 1], d.drift || null, d.compliance || null]);
}
// the time from the change to the painted plots, in parts (benchmarks/bench_web.py reads them)
async function recordAnalyseLatency(t0, p) {
  const drawn = performance.now();
  await new Promise((done) => requestAnimationFrame(() => setTimeout(done, 0)));   // painted
  const now = performance.now();
  (window.AN_LATENCY = window.AN_LATENCY || []).push(now - t0);
  (window.AN_PARTS = window.AN_PARTS || []).push([p.wall_time * 1e3, AN.fetched - t0, drawn - AN.fetched, now - drawn]);
  document.body.dataset.anCount = String(Number(document.body.dataset.anCount || 0) + 1);
}
// ---- the session: uploads kept on the server, the page restored after a reload -----------------------
const SAVED = "afmforce.analyse";
function saveAnalyse() {   // what to reopen after a reload: the uploads shown, the options changed, the curve
  try {
    const changed = new Set(optionTexts().map((o) => o.split("=")[0]));
    const options = {};
    for (const c of AN.controls) {
      const key = `${c.step}.${c.f.name}`;
      const input = c.box.querySelector("input.val, select, input[type=checkbox]");
      if (changed.has(key) && input) options[key] = input.type === "checkbox" ? input.checked : input.value;
    }
    const probe = {};
    for (const c of AN.probe || []) { const input = c.box.querySelector("input.val"); if (input && input.value.trim()) probe[c.f.name] = input.value; }
    const settings = {};
    for (const c of AN.settings || []) { const v = c.box.get(); if (v !== null && v !== c.f.default) settings[c.f.name] = v; }
    localStorage.setItem(SAVED, JSON.stringify({ files: AN.files.map((f) => f.id), examples: AN.examples, options, probe, settings, curve: $("an-curve").value }));
  } catch { /* storage off: nothing restored */ }
}
async function listUploads() {
  const s = await api("api/session");
  const box = $("an-uploads"); box.replaceChildren();
  if (s.expires) $("an-kept").textContent = `Kept on this server until ${new Date(s.expires * 1000).toLocaleString()} (${Math.round(s.ttl / 3600)} h after your last use).`;
  const chosen = new Set(AN.files.map((f) => f.id));
  for (const f of s.files) {
    const c = el("input", { type: "checkbox", "data-upload": f.id }); c.checked = chosen.has(f.id);
    c.addEventListener("change", () => {
      const ids = [...box.querySelectorAll("input[data-upload]:checked")].map((x) => x.dataset.upload);
      AN.files = s.files.filter((x) => ids.includes(x.id)); AN.examples = [];
      if (AN.files.length) analyse(false);
    });
    const del = el("button", { class: "small", title: "remove from the server", text: "×" });
    del.addEventListener("click", async () => { await api(`api/files/${f.id}`, { method: "DELETE" }); AN.files = AN.files.filter((x) => x.id !== f.id); listUploads(); });
    box.append(el("div", { class: "upload" }, el("label", {}, c, ` ${f.name} `, el("span", { class: "muted", text: `${(f.size / 1e3).toFixed(0)} kB` })), del));
  }
  return s;
}
async function restoreAnalyse() {
  const s = await listUploads();
  let saved; try { saved = JSON.parse(localStorage.getItem(SAVED) || "null"); } catch { saved = null; }
  if (!saved) return;
  const have = new Set(s.files.map((f) => f.id));
  AN.files = s.files.filter((f) => (saved.files || []).includes(f.id));
  AN.examples = (saved.examples || []).filter((e) => SCHEMA.examples.some((x) => x.name === e));
  for (const [key, v] of Object.entries(saved.options || {})) {
    const input = document.querySelector(`[data-option="${CSS.escape(key)}"] input.val, [data-option="${CSS.escape(key)}"] select, [data-option="${CSS.escape(key)}"] input[type=checkbox]`);
    if (!input) continue;
    if (input.type === "checkbox") input.checked = !!v; else input.value = v;
  }
  for (const [name, v] of Object.entries(saved.settings || {})) {
    const input = document.querySelector(`[data-setting="${CSS.escape(name)}"] select`); if (input) input.value = v;
  }
  for (const [name, v] of Object.entries(saved.probe || {})) {
    const input = document.querySelector(`[data-probe="${CSS.escape(name)}"] input.val`); if (input) input.value = v;
  }
  if (!AN.files.length && !AN.examples.length) return;
  for (const f of AN.files) { const c = document.querySelector(`input[data-upload="${f.id}"]`); if (c) c.checked = true; }
  if (saved.curve) AN.restoreCurve = saved.curve;
  await analyse(false);
  if (have.size) $("status").textContent = "restored your last analysis";
}
function drawCurve() {
  const name = $("an-curve").value, res = AN.payload.results[name], raw = (AN.payload.raw || {})[name];
  if (!res) return;
  if (!res.separation) { loadCurveArrays(name); return; }
  const seg = res.segment || [], parts = [[0, "approach", "#2f6db5"], [1, "retract", "#d0632b"], [2, "dwell", "#888"]];
  const pick = (arr, k) => arr.map((v, i) => (seg[i] === k ? v : null));
  const f = [];
  for (const [k, label, color] of parts) {
    if (!seg.includes(k)) continue;
    f.push({ x: sc(pick(res.separation, k), 1e9), y: sc(pick(res.force, k), 1e9), name: label, mode: "lines", line: { color },
      hovertemplate: "h = %{x:.3f} nm<br>F = %{y:.4f} nN<extra>" + label + "</extra>" });
  }
  const d = res.details || {}, marks = [];
  const j = (d.jumps || {}).jump_in; if (j && j.found !== false && res.jump_in_separation !== null)
    marks.push({ x: [res.jump_in_separation * 1e9], y: [res.jump_in_force * 1e9], name: "jump-in", mode: "markers", marker: { size: 11, symbol: "triangle-down", color: "#1a7f37" }, hovertemplate: "jump-in<br>h = %{x:.3f} nm<br>F = %{y:.4f} nN<extra></extra>" });
  const adhesionAt = () => {   // the separation of the retract sample at the adhesion force (the marker sits on the curve)
    let best = null, gap = Infinity;
    (res.force || []).forEach((F, i) => { if (seg[i] === 1 && F !== null && res.separation[i] !== null && Math.abs(F - res.adhesion_force) < gap) { gap = Math.abs(F - res.adhesion_force); best = i; } });
    return best;
  };
  const iAdh = res.adhesion_force !== null ? adhesionAt() : null;
  if (iAdh !== null)   // the deepest retract point, drawn where it lies on the curve
    marks.push({ x: [res.separation[iAdh] * 1e9], y: [res.force[iAdh] * 1e9], name: `adhesion ${fmt(res.adhesion_force, "N")}`, mode: "markers", marker: { size: 10, symbol: "diamond", color: "#b00020" }, hovertemplate: `adhesion ${fmt(res.adhesion_force, "N")}<br>h = %{x:.2f} nm (${fmt(res.adhesion_distance, "m")} from contact)<extra></extra>` });
  if (res.pull_off_force !== null) marks.push({ x: [0], y: [res.pull_off_force * 1e9], name: `pull-off ${fmt(res.pull_off_force, "N")}`, mode: "markers", marker: { size: 11, symbol: "x", color: "#b00020" }, hovertemplate: "pull-off F = %{y:.4f} nN<extra></extra>" });
  const v = d.vdw || {};
  if (v.status === "ok" && v.hamaker_radius) {
    const xs = [], ys = [];
    for (let h = v.separation_min; h <= v.separation_max; h += (v.separation_max - v.separation_min) / 100) {
      xs.push(h * 1e9); ys.push((-v.hamaker_radius / (6 * h * h) + (v.force_offset || 0) + (v.force_slope || 0) * h) * 1e9);
    }
    marks.push({ x: xs, y: ys, name: `vdW fit A R = ${fmt(v.hamaker_radius, "")} J m`, mode: "lines", line: { dash: "dash", color: "#6a3d9a" }, hovertemplate: "fit: F = %{y:.4f} nN at %{x:.2f} nm<extra></extra>" });
  }
  Plotly.react("an-plot-force", f.concat(marks), { ...LAYOUT, title: { text: `Force vs separation — ${name}` }, xaxis: { title: { text: "separation h [nm]" } }, yaxis: { title: { text: "force F [nN]" } }, ...vdwRangeLayout(res) }, { ...CONFIG, edits: { shapePosition: true } });
  optionHandleBind($("an-plot-force"), "vdw", "max_separation");   // drag.js: the vdW fit's window, dragged
  const rawChanged = changed("an-plot-raw", rawKey(name, raw, d));
  if (raw && rawChanged) {
    const u = raw.unit || "";
    const [fs, us] = U[u] || [1, u];
    const rt = [];
    for (const [k, label, color] of parts) {
      if (!raw.segment.includes(k)) continue;
      rt.push({ x: sc(raw.piezo.map((z, i) => (raw.segment[i] === k ? z : null)), 1e9), y: sc(raw.signal.map((s, i) => (raw.segment[i] === k ? s : null)), fs), name: label, mode: "lines", line: { color }, hovertemplate: `z = %{x:.2f} nm<br>signal = %{y:.4g} ${us}<extra>${label}</extra>` });
    }
    Plotly.react("an-plot-raw", rt, { ...LAYOUT, title: { text: "Raw signal vs piezo position" }, xaxis: { title: { text: "piezo position z [nm]" } }, yaxis: { title: { text: `deflection signal [${us}]` } } }, CONFIG);
  }
  if (rawChanged) drawDrift(raw, d, parts);
  drawIndentation(res);
  const rows = [["contact", res.contact_kind_reason && String(res.contact_kind_reason).startsWith(res.contact_kind) ? res.contact_kind_reason : `${res.contact_kind}: ${res.contact_kind_reason}`], ["adhesion", res.adhesion_verdict || "–"],
    ["jump-in", `${fmt(res.jump_in_separation, "m")}, ${fmt(res.jump_in_force, "N")}`], ["pull-off", fmt(res.pull_off_force, "N")],
    // null with its bound given: the analysis left it undetermined (afmforce.analysis.plausibility.undetermined)
    ["inward shift", res.shift === null && res.shift_drift !== null && res.shift_drift !== undefined ? `undetermined (±${fmt(res.shift_drift, "m")}: the drift lines' bound exceeds the shift)` : fmt(res.shift, "m") + (res.shift_drift !== null && res.shift_drift !== undefined ? ` (±${fmt(res.shift_drift, "m")})` : "")],
    ["A R", `${fmt(res.hamaker_radius, "")} J m`], ["oscillation", res.oscillation_verdict || "–"], ["friction", res.friction_verdict && String(res.friction_verdict).startsWith(res.friction) ? res.friction_verdict : `${res.friction}: ${res.friction_verdict}`],
    ["diagnosis", res.verdict || "–"]];
  if (res.youngs_modulus !== null && res.youngs_modulus !== undefined)
    rows.push(["Young's modulus E", `${fmtPa(res.youngs_modulus)}` + (res.youngs_modulus_low === 0 && (res.youngs_modulus_high === null || res.youngs_modulus_high === undefined) ? " (undetermined: the 95 % interval reaches 0, no upper bound)" : res.youngs_modulus_low !== null && res.youngs_modulus_high !== null ? ` (interval ${fmtPa(res.youngs_modulus_low)} – ${fmtPa(res.youngs_modulus_high)})` : "") + (res.indentation_model ? `, ${res.indentation_model}` : "")]);
  for (const [step, why] of Object.entries(res.not_applicable || {})) rows.push([`${step} (not run)`, why]);
  res.warnings.forEach((w) => rows.push(["warning", w]));
  showUsed(res);
  $("an-summary").replaceChildren(table(rows));
  drawEvidence(res, d);
}
function drawEvidence(res, d) {   // each step's result record, every number in an engineering unit (SI on hover)
  const box = $("an-details"); box.replaceChildren(el("h2", { text: "Every step's evidence" }));
  for (const [step, vals] of Object.entries(d)) {
    const units = (res.details_units || {})[step] || {};
    const r = Object.entries(vals || {}).filter(([, x]) => typeof x !== "object" || x === null).map(([k, x]) => [k, ...engineering(x, units[k] || "")]);
    const t = table(r.map((row) => row.slice(0, 3)), ["field", "value", "unit"]);
    t.querySelectorAll("tr").forEach((tr, i) => { if (i && r[i - 1][3]) tr.title = r[i - 1][3]; });
    const det = el("details", {}, el("summary", { text: step + (res.not_applicable && res.not_applicable[step] ? " (not applicable)" : "") }), t);
    box.append(det);
  }
}
// a value in SI and its unit -> [value, unit, SI text] in the unit a lab reads (29680000 V/m is
// 0.02968 V/nm, 3.1e-8 m/V is 31 nm/V, 4.2e-20 J is 42 zJ); the SI value is kept for the hover
const ENGINEERING = {
  "m": [[1e-3, "mm", 1e3], [1e-6, "µm", 1e6], [1e-9, "nm", 1e9], [0, "pm", 1e12]],
  "N": [[1e-3, "mN", 1e3], [1e-6, "µN", 1e6], [1e-9, "nN", 1e9], [0, "pN", 1e12]],
  "s": [[1, "s", 1], [1e-3, "ms", 1e3], [0, "µs", 1e6]],
  "Hz": [[1e6, "MHz", 1e-6], [1e3, "kHz", 1e-3], [0, "Hz", 1]],
  "Pa": [[1e9, "GPa", 1e-9], [1e6, "MPa", 1e-6], [1e3, "kPa", 1e-3], [0, "Pa", 1]],
  "J": [[1e-18, "aJ", 1e18], [0, "zJ", 1e21]],
  "m/V": [[0, "nm/V", 1e9]], "V/m": [[0, "V/nm", 1e-9]], "N/V": [[0, "nN/V", 1e9]],
  "m/s": [[1e-3, "mm/s", 1e3], [1e-6, "µm/s", 1e6], [0, "nm/s", 1e9]],
  "J/m^2": [[0, "mJ/m²", 1e3]], "N/m^2": [[0, "Pa", 1]],
};
function engineering(x, unit) {
  if (x === null || x === undefined) return ["–", unit, ""];
  if (typeof x !== "number") return [String(x), unit, ""];
  if (!isFinite(x)) return [String(x), unit, ""];
  const ways = ENGINEERING[unit];
  if (ways && x !== 0) for (const [lim, u, f] of ways) if (Math.abs(x) >= lim) return [String(Number((x * f).toPrecision(4))), u, `${x} ${unit}`];
  const shown = Math.abs(x) !== 0 && (Math.abs(x) < 1e-3 || Math.abs(x) >= 1e5) ? x.toExponential(3) : String(Number(x.toPrecision(5)));
  return [shown, unit, shown === String(x) ? "" : `${x} ${unit}`];
}
function drawDrift(raw, d, parts) {   // the drift step: raw signal against time, its baselines; then the compliance lines
  const dr = d.drift, co = d.compliance;
  if (!raw) return;
  const [fs, us] = U[raw.unit] || [1, raw.unit];
  const start = (k) => raw.time[raw.segment.indexOf(k)];
  const base = (t, k) => (!dr ? 0 : k === 1 ? dr.offset_retract + dr.slope_retract * (t - start(1)) : dr.offset_approach + dr.slope_approach * (t - start(0)));
  const tt = [];
  for (const [k, label, color] of parts) {
    if (!raw.segment.includes(k)) continue;
    const t = raw.time.map((x, i) => (raw.segment[i] === k ? x : null));
    tt.push({ x: t, y: sc(raw.signal.map((x, i) => (raw.segment[i] === k ? x : null)), fs), name: label, mode: "lines", line: { color }, hovertemplate: `${timeAxis(raw).hover}<br>%{y:.4g} ${us}<extra>${label}</extra>` });
    if (dr && k !== 2) tt.push({ x: t, y: sc(t.map((x) => (x === null ? null : base(x, k))), fs), name: `${label} baseline`, mode: "lines", line: { color, dash: "dash" }, hovertemplate: `baseline %{y:.4g} ${us}<extra>${label}</extra>` });
  }
  Plotly.react("an-plot-time", tt, { ...LAYOUT, title: { text: `Drift: raw signal and baselines (${dr ? dr.retract_line + " retract line" : "no drift step"})` }, xaxis: { title: { text: timeAxis(raw).title } }, yaxis: { title: { text: `deflection signal [${us}]` } } }, CONFIG);
  if (!co || !co.approach) { Plotly.purge("an-plot-compliance"); return; }
  const ct = [], lo = Math.min(co.approach.z_min, (co.retract || co.approach).z_min), hi = Math.max(co.approach.z_max, (co.retract || co.approach).z_max), w = (hi - lo) * 2;
  for (const [k, label, color] of parts) {
    if (k === 2 || !raw.segment.includes(k)) continue;
    const keep = raw.piezo.map((z, i) => raw.segment[i] === k && z >= lo - w && z <= hi + w);
    ct.push({ x: sc(raw.piezo.map((z, i) => (keep[i] ? z : null)), 1e9), y: sc(raw.signal.map((x, i) => (keep[i] ? x - base(raw.time[i], k) : null)), fs), name: label, mode: "markers", marker: { size: 3, color }, hovertemplate: `z = %{x:.2f} nm<br>%{y:.4g} ${us}<extra>${label}</extra>` });
    const line = k === 1 ? co.retract : co.approach;
    if (line) ct.push({ x: [line.z_min * 1e9, line.z_max * 1e9], y: [(line.intercept + line.slope * line.z_min) * fs, (line.intercept + line.slope * line.z_max) * fs], name: `${label} compliance, slope ${slopeText(line.slope, raw.unit)}`, mode: "lines", line: { color, width: 3, dash: "dot" } });
  }
  Plotly.react("an-plot-compliance", ct, { ...LAYOUT, title: { text: "Compliance: drift-corrected signal near contact" }, xaxis: { title: { text: "piezo position z [nm]" } }, yaxis: { title: { text: `signal − baseline [${us}]` } } }, CONFIG);
}
// ---- every curve of a batch or map: one table (SI, units in the header), a histogram, CSV ----------
const BATCH_COLUMNS = ["contact_kind", "adhesion_force", "pull_off_force", "jump_in_separation", "hamaker_radius",
  "youngs_modulus", "youngs_modulus_se", "work_of_adhesion", "spring_constant", "sensitivity_used", "resonance_frequency", "velocity"];
function batchRows() {
  const names = Object.keys(AN.payload.results), units = {};
  for (const n of names) Object.assign(units, AN.payload.results[n].units || {});
  return { names, units, rows: names.map((n) => BATCH_COLUMNS.map((c) => { const v = AN.payload.results[n][c]; return v === undefined ? null : v; })) };
}
function drawBatch() {
  const box = $("an-batch"), n = Object.keys((AN.payload || {}).results || {}).length;
  box.classList.toggle("hidden", n < 2); if (n < 2) return;
  $("an-batch-n").textContent = `${n} curves`;
  const { names, units, rows } = batchRows();
  const head = ["curve", ...BATCH_COLUMNS.map((c) => (units[c] ? `${c} [${units[c]}]` : c))];
  $("an-batch-table").replaceChildren(table(rows.map((r, i) => [names[i], ...r.map((v) => (v === null ? "–" : typeof v === "number" ? Number(v.toPrecision(5)) : String(v)))]), head));
  $("an-batch-table").querySelectorAll("tr").forEach((tr, i) => { if (i) { tr.style.cursor = "pointer"; tr.onclick = () => { $("an-curve").value = names[i - 1]; drawCurve(); }; } });
  const sel = $("an-batch-col"), keep = sel.value; sel.replaceChildren();
  BATCH_COLUMNS.forEach((c, j) => { if (rows.some((r) => typeof r[j] === "number")) sel.append(el("option", { value: c, text: units[c] ? `${c} [${units[c]}]` : c })); });
  sel.value = [...sel.options].some((o) => o.value === keep) ? keep : (sel.options[0] || {}).value;
  drawHistogram();
}
function drawHistogram() {
  const c = $("an-batch-col").value; if (!c) return;
  const { rows, units } = batchRows(), j = BATCH_COLUMNS.indexOf(c);
  const xs = rows.map((r) => r[j]).filter((v) => typeof v === "number" && isFinite(v));
  Plotly.react("an-batch-hist", [{ type: "histogram", x: xs, name: c }], { ...LAYOUT, title: { text: `${c}: ${xs.length} curves` },
    xaxis: { title: { text: `${c} [${units[c] || "-"}]` } }, yaxis: { title: { text: "curves [count]" } } }, CONFIG);
}
$("an-batch-col").addEventListener("change", drawHistogram);
$("an-batch-csv").addEventListener("click", () => {
  const { names, units, rows } = batchRows();
  const q = (v) => (v === null ? "" : typeof v === "string" && /[",\n]/.test(v) ? `"${v.replace(/"/g, '""')}"` : v);
  const lines = ["# afmforce: every curve analysed (SI units)", ["curve", ...BATCH_COLUMNS.map((c) => (units[c] ? `${c} [${units[c]}]` : c))].map(q).join(",")];
  rows.forEach((r, i) => lines.push([names[i], ...r].map(q).join(",")));
  download("afmforce-curves.csv", new Blob([lines.join("\n") + "\n"], { type: "text/csv" }));
});
function drawIndentation(res) {   // force above the baseline vs indentation: the data and the fitted model, E in the legend
  const div = $("an-plot-indentation"), fit = (res.details || {}).indentation;
  if (!fit || !Array.isArray(fit.indentation) || !fit.indentation.length) { div.classList.add("hidden"); Plotly.purge(div); return; }
  div.classList.remove("hidden");
  const x = fit.indentation.map((v) => v * 1e9), data = fit.fit_force.map((F, i) => (F + fit.residuals[i] - fit.baseline) * 1e9);
  const order = x.map((_, i) => i).sort((a, b) => x[a] - x[b]);
  let label = fit.youngs_modulus_low === 0 && (fit.youngs_modulus_high === null || fit.youngs_modulus_high === undefined) ? `E undetermined (${fmtPa(fit.youngs_modulus)}, interval [0, open])` : `E = ${fmtPa(fit.youngs_modulus)} [${fmtPa(fit.youngs_modulus_low)}, ${fmtPa(fit.youngs_modulus_high)}]`;
  if (fit.work_of_adhesion !== null && fit.work_of_adhesion !== undefined) label += `, w = ${Number((fit.work_of_adhesion * 1e3).toPrecision(3))} mJ/m²`;
  const range = fitRangeLayout($("an-curve").value, fit, x);   // drag.js: the fit limit, dragged
  Plotly.react(div, [
    { x, y: data, name: `${fit.run} (data)`, mode: "markers", marker: { size: 3, color: "#777" }, hovertemplate: "δ = %{x:.2f} nm<br>F = %{y:.4f} nN<extra>data</extra>" },
    { x: order.map((i) => x[i]), y: order.map((i) => (fit.fit_force[i] - fit.baseline) * 1e9), name: `fit: ${fit.model}`, mode: "lines", line: { color: "#b00020", width: 2 }, hovertemplate: "model: F = %{y:.4f} nN at δ = %{x:.2f} nm<extra></extra>" },
    contactPointTrace(fit, data)],
  { ...LAYOUT, title: { text: `Indentation: ${label}` + (fit.warnings && fit.warnings.length ? ` (${fit.warnings.length} warning${fit.warnings.length > 1 ? "s" : ""})` : "") },
    xaxis: { title: { text: "indentation δ [nm]" }, range: range.xrange, autorange: false }, yaxis: { title: { text: "force above the baseline [nN]" } },
    shapes: [...range.shapes, contactPointShape(fit)], annotations: range.annotations }, { ...CONFIG, edits: { shapePosition: true } });
  fitRangeBind(div);
  contactPointBind(div);   // drag.js: the contact point, dragged (indentation.contact_point)
}
function timeAxis(raw) {   // a file without a time base (no sample rate): its "time" is the sample index
  return raw.time_base === false ? { title: "sample index n [-] (the file has no time base)", hover: "sample %{x:.0f}" }
    : { title: "time t [s]", hover: "t = %{x:.4f} s" };
}
function slopeText(slope, unit) {   // a compliance slope per nm (29680000 V/m reads 0.02968 V/nm)
  return unit === "N" ? `${Number(slope.toPrecision(4))} N/m` : `${Number((slope * 1e-9).toPrecision(4))} ${unit}/nm`;
}
function drawMaps(maps) {
  const div = $("an-plot-map");
  if (!maps.length) { div.classList.add("hidden"); $("an-map-quantity").classList.add("hidden"); return; }
  div.classList.remove("hidden");
  const sel = $("an-map-quantity"), keep = sel.value;   // every map quantity of every map file
  sel.classList.remove("hidden"); sel.replaceChildren();
  maps.forEach((x, i) => sel.append(el("option", { value: String(i), text: `${x.file}: ${x.label} [${x.unit === "N" ? "nN" : x.unit === "m" ? "nm" : x.unit || "-"}]` })));
  sel.value = keep && Number(keep) < maps.length ? keep : "0";
  sel.onchange = () => drawMaps(maps);
  const m = maps[Number(sel.value)], f = m.unit === "N" ? 1e9 : m.unit === "m" ? 1e9 : 1, u = m.unit === "N" ? "nN" : m.unit === "m" ? "nm" : m.unit;
  if (m.layout === "points") return drawMapPoints(div, m, f, u);
  const z = m.z.map((row) => row.map((v) => (v === null ? null : v * f)));
  Plotly.react(div, [{ type: "heatmap", z, x: m.x_um || undefined, y: m.y_um || undefined, customdata: m.curves, colorbar: { title: { text: `${m.label} [${u || "-"}]`, side: "right" } },
    hovertemplate: `x = %{x} ${m.axes === "um" ? "µm" : ""}<br>y = %{y} ${m.axes === "um" ? "µm" : ""}<br>${m.quantity} = %{z:.4g} ${u}<br>%{customdata}<extra>click: open</extra>` }],
  { ...LAYOUT, title: { text: `${m.file}: ${m.label}` },
    annotations: z.some((row) => row.some((v) => v !== null)) ? [] : [{ text: wrapText(m.note || `no curve of this map gives a ${m.label}`, 48).join("<br>"), showarrow: false, xref: "paper", yref: "paper", x: 0.5, y: 0.5 }], xaxis: { title: { text: m.axes === "um" ? "x [µm]" : "x (column index)" }, scaleanchor: "y" }, yaxis: { title: { text: m.axes === "um" ? "y [µm]" : "y (row index)" } } }, CONFIG);
  div.removeAllListeners && div.removeAllListeners("plotly_click");
  div.on("plotly_click", (ev) => { const n = ev.points[0].customdata; if (n && AN.payload.results[n]) { $("an-curve").value = n; drawCurve(); } });
}
function drawMapPoints(div, m, f, u) {   // a map whose positions form no grid: a scatter at them (the CLI's PNG)
  const z = m.z.map((v) => (v === null ? null : v * f)), ok = z.map((v) => v !== null);
  const pick = (arr, keep) => arr.filter((_, i) => ok[i] === keep);
  const traces = [{ type: "scatter", mode: "markers", x: pick(m.x_um, true), y: pick(m.y_um, true), customdata: pick(m.curves, true),
    marker: { size: 12, color: pick(z, true), colorscale: "Viridis", showscale: true, colorbar: { title: { text: `${m.label} [${u || "-"}]`, side: "right" } } },
    name: m.label, hovertemplate: `x = %{x:.3f} µm<br>y = %{y:.3f} µm<br>${m.quantity} = %{marker.color:.4g} ${u}<br>%{customdata}<extra>click: open</extra>` }];
  if (ok.some((x) => !x)) traces.push({ type: "scatter", mode: "markers", x: pick(m.x_um, false), y: pick(m.y_um, false), customdata: pick(m.curves, false),
    marker: { size: 12, color: "#bbb", symbol: "x" }, name: "no value", hovertemplate: "x = %{x:.3f} µm<br>y = %{y:.3f} µm<br>no value<br>%{customdata}<extra>click: open</extra>" });
  const notes = [{ text: wrapText(`points at the recorded positions: ${m.why || "no grid"}`, 60).join("<br>"), showarrow: false, xref: "paper", yref: "paper", x: 0, y: 1.08, xanchor: "left" }];
  if (!ok.some((x) => x)) notes.push({ text: wrapText(m.note || `no curve of this map gives a ${m.label}`, 48).join("<br>"), showarrow: false, xref: "paper", yref: "paper", x: 0.5, y: 0.5 });
  Plotly.react(div, traces, { ...LAYOUT, title: { text: `${m.file}: ${m.label}` }, showlegend: false, annotations: notes,
    xaxis: { title: { text: "x [µm]" }, scaleanchor: "y" }, yaxis: { title: { text: "y [µm]" } } }, CONFIG);
  div.removeAllListeners && div.removeAllListeners("plotly_click");
  div.on("plotly_click", (ev) => { const n = ev.points[0].customdata; if (n && AN.payload.results[n]) { $("an-curve").value = n; drawCurve(); } });
}
// ---- calibration and probe: k, InvOLS, resonance frequency, radius (probe); model, tip, sample (indentation) ----
const shownValue = (v, f) => (typeof v === "number" && isFinite(v) ? `${Number((v / f.factor).toPrecision(4))} ${f.shown}`.trim() : v === null || v === undefined ? "–" : String(v));
function probeTexts(fromFile = null) {   // fromFile (a list): the untouched calibration file's names go there
  const out = [];
  for (const c of AN.probe || []) {
    const v = c.box.get();
    if (v === null || v === "") continue;
    const from = c.box.fromFile;   // a value from the calibration file, untouched: its SI value, exactly
    if (from && c.box.querySelector("input.val").value === from.text) { if (!fromFile) out.push(`${c.f.name}=${from.value}`); else fromFile.push(c.f.name); continue; }
    out.push(`${c.f.name}=${typeof v === "number" ? `${Number((v / c.f.factor).toPrecision(8))}${c.f.shown}` : v}`);
  }
  return out;
}
function buildCalibration() {
  const box = $("an-calibration"); box.replaceChildren(); AN.probe = [];
  const rerun = () => { if (AN.files.length || AN.examples.length) analyse(false); };
  for (const f of SCHEMA.calibration || []) {
    let c;
    if (f.via === "option") {       // the step's own control, moved here (one control, one value)
      const own = AN.controls.find((x) => `${x.step}.${x.f.name}` === f.key);
      if (!own) continue;
      c = own.box;
    } else {
      c = control(f, rerun, { value: null });
      c.dataset.probe = f.name; AN.probe.push({ f, box: c });
    }
    c.dataset.shows = f.shows.join(",");
    c.querySelector(".name").textContent = { spring_constant: "spring constant k", sensitivity: "sensitivity (InvOLS)", resonance_frequency: "resonance frequency", radius: "sphere radius R (vdW, adhesion)", theta0: "inclination θ0 (k tilt-corrected, eq 13/14)", L0: "beam length L0", L1: "rigid base L1", L2: "rigid probe L2", "indentation.model": "indentation model", "indentation.tip_radius": "tip radius", "indentation.half_angle": "tip half angle", "indentation.poisson": "Poisson ratio of the sample" }[f.key] || f.name;
    c.append(el("div", { class: "used muted" }));
    box.append(c);
  }
}
function probeForm(fd) {   // the typed probe values, and the calibration file for its untouched ones (named as its in the warnings)
  const fromFile = [];
  probeTexts(AN.calfile ? fromFile : null).forEach((o) => fd.append("probe", o));
  if (fromFile.length) { fd.append("calibration", AN.calfile); fromFile.forEach((n) => fd.append("calibration_keys", n)); }
}
async function loadCalibrationFile(file) {   // fills k, InvOLS, f0 from the file; "from calib.json" under each
  $("an-calfile-error").textContent = "";
  const fd = new FormData(); fd.append("file", file);
  let r;
  try { r = await api("api/calibration", { method: "POST", body: fd }); } catch (e) { $("an-calfile-error").textContent = e.message; return; }
  const names = Object.keys(r.values);
  AN.calfile = file;
  if (!names.length) { $("an-calfile-error").textContent = `${r.source} holds no spring constant, sensitivity or resonance frequency`; return; }
  for (const c of AN.probe || []) {
    if (!(c.f.name in r.values)) continue;
    const input = c.box.querySelector("input.val"), v = r.values[c.f.name];
    input.value = String(Number((v / c.f.factor).toPrecision(6)));
    c.box.fromFile = { value: v, text: input.value };
    let tag = c.box.querySelector(".from");
    if (!tag) { tag = el("div", { class: "from muted" }); c.box.querySelector(".used").before(tag); }
    tag.textContent = `from ${r.source}`;
    input.addEventListener("input", () => { if (input.value !== (c.box.fromFile || {}).text) tag.textContent = ""; });
  }
  if (AN.files.length || AN.examples.length) analyse(false);
}
function showUsed(res) {   // beside each calibration field: the value the analysis used (and the file's)
  for (const box of document.querySelectorAll("#an-calibration .field")) {
    const out = box.querySelector(".used"); if (!out) continue;
    const f = (SCHEMA.calibration || []).find((x) => box.dataset.shows !== undefined && (x.key === box.dataset.option || x.name === box.dataset.probe)) || {};
    const keys = (box.dataset.shows || "").split(",").filter(Boolean);
    let text = "";
    if (keys[0] === "indentation_model") {
      const why = (res.not_applicable || {}).indentation;
      text = why ? `not run: ${why}` : res.youngs_modulus !== null && res.youngs_modulus !== undefined ? `E = ${fmtPa(res.youngs_modulus)}` : "";
    } else if (keys.length === 2) text = `given or file's ${shownValue(res[keys[0]], f)} · used ${shownValue(res[keys[1]], f)}`;
    else if (keys.length === 1) text = `used ${shownValue(res[keys[0]], f)}`;
    out.textContent = text;
    out.classList.toggle("error", text.startsWith("not run"));
  }
}
function fmtPa(v) {
  if (v === null || v === undefined || !isFinite(v)) return "–";
  for (const [f, u] of [[1e9, "GPa"], [1e6, "MPa"], [1e3, "kPa"], [1, "Pa"]]) if (Math.abs(v) >= f) return `${(v / f).toPrecision(4)} ${u}`;
  return `${v.toPrecision(4)} Pa`;
}
function buildSettings() {   // the analysis's word settings (channel): GET /api/schema analysis_settings, as afmforce analyze --channel
  const box = $("an-settings"); box.replaceChildren(); AN.settings = [];
  for (const f of SCHEMA.analysis_settings || []) {
    const c = control(f, () => { if (AN.files.length || AN.examples.length) analyse(false); });
    c.dataset.setting = f.name; box.append(c); AN.settings.push({ f, box: c });
  }
}
function settingsForm(fd) { for (const c of AN.settings || []) { const v = c.box.get(); if (v !== null && v !== c.f.default) fd.append(c.f.name, v); } }
function buildOptions() {
  const box = $("an-options"); box.replaceChildren(); AN.controls = [];
  for (const [step, fields] of Object.entries(SCHEMA.analysis)) {
    const det = el("details", {}, el("summary", { text: step }));
    for (const f of fields) {
      const c = control(f, () => { if (AN.files.length || AN.examples.length) analyse(false); });
      c.dataset.option = `${step}.${f.name}`;
      det.append(c); AN.controls.push({ step, f, box: c });
    }
    box.append(det);
  }
}
$("an-run").addEventListener("click", () => {
  AN.examples = $("an-example").value ? [$("an-example").value] : [];
  if (!$("an-files").files.length && !AN.examples.length) { $("an-error").textContent = "choose a file or an example"; return; }
  AN.files = []; analyse(true);
});
$("an-curve").addEventListener("change", drawCurve);
$("an-json").addEventListener("click", () => AN.payload && download("afmforce-analysis.json", new Blob([JSON.stringify(AN.payload, null, 2)], { type: "application/json" })));
$("an-csv").addEventListener("click", () => {
  const n = $("an-curve").value, r = AN.payload && AN.payload.results[n]; if (!r) return;
  const lines = [`# afmforce force-vs-separation table; source: ${n}`, "segment,time [s],position [m],separation [m],deflection [m],force [N]"];
  r.time.forEach((t, i) => lines.push([r.segment[i], t, r.position[i], r.separation[i], r.deflection[i], r.force[i]].map((v) => (v === null ? "" : v)).join(",")));
  download(n + ".afmforce.csv", new Blob([lines.join("\n") + "\n"], { type: "text/csv" }));
});
$("an-png").addEventListener("click", () => Plotly.downloadImage("an-plot-force", { format: "png", filename: $("an-curve").value + ".afmforce", scale: 2 }));

// ---- Simulate ---------------------------------------------------------------------------------
const SIM = { controls: [], busy: false, again: false, last: null, ref: null, done: false };
function simConfig() {
  const model = SIM.controls.find((c) => c.f.name === "model").box.get();
  const cfg = {};
  for (const c of SIM.controls) {
    if (!c.f.models.includes(model)) continue;
    const v = c.box.get();
    if (v !== null && v !== "" && v !== c.f.default) cfg[c.f.name] = v;
  }
  cfg.model = model;
  return cfg;
}
async function simulate() {
  if (SIM.busy) { SIM.again = true; return; }
  SIM.busy = true; SIM.done = true;
  const t0 = performance.now();
  try {
    const r = await api("api/simulate?max_points=600&columns=piezo_position,deflection,apparent_deflection,separation,normal_force", { method: "POST", headers: { "content-type": "application/json" }, body: JSON.stringify(simConfig()) });
    await plotlyLoaded();
    const t1 = performance.now();
    SIM.last = r; $("sim-error").textContent = "";
    drawSim();
    const t2 = performance.now();
    await new Promise((done) => requestAnimationFrame(() => setTimeout(done, 0)));   // painted
    (window.SIM_LATENCY = window.SIM_LATENCY || []).push(performance.now() - t0);
    (window.SIM_PARTS = window.SIM_PARTS || []).push([r.wall_time * 1e3, t1 - t0, t2 - t1, performance.now() - t2]);
    $("sim-time").textContent = `${r.n_samples} samples; ${(performance.now() - t0).toFixed(0)} ms to redraw (server ${(r.wall_time * 1000).toFixed(0)} ms)`;
    document.body.dataset.simCount = String(Number(document.body.dataset.simCount || 0) + 1);
  } catch (e) { $("sim-error").textContent = e.message; }
  SIM.busy = false;
  if (SIM.again) { SIM.again = false; simulate(); }
}
function simTraces(r, tag, dash) {
  const c = r.columns, z = sc(c.piezo_position, 1e9);
  return [
    [{ x: z, y: sc(c.deflection, 1e9), name: `actual ${tag}`, mode: "lines", line: { dash, color: "#2f6db5" }, hovertemplate: "z = %{x:.2f} nm<br>deflection = %{y:.4f} nm<extra>actual " + tag + "</extra>" },
     { x: z, y: sc(c.apparent_deflection, 1e9), name: `apparent ${tag}`, mode: "lines", line: { dash, color: "#d0632b" }, hovertemplate: "z = %{x:.2f} nm<br>apparent = %{y:.4f} nm<extra>apparent " + tag + "</extra>" }],
    [{ x: sc(c.separation, 1e9), y: sc(c.normal_force, 1e9), name: `force ${tag}`, mode: "lines", line: { dash, color: "#1a7f37" }, hovertemplate: "h = %{x:.3f} nm<br>F = %{y:.4f} nN<extra>" + tag + "</extra>" }],
  ];
}
function box(traces, key) {   // the data's range, padded: a fixed range spares Plotly its autorange (3x faster)
  let lo = Infinity, hi = -Infinity;
  for (const t of traces) for (const v of t[key]) if (v !== null) { if (v < lo) lo = v; if (v > hi) hi = v; }
  if (!isFinite(lo) || !isFinite(hi)) return { autorange: true };
  const pad = (hi - lo) * 0.05 || Math.abs(hi) * 0.05 || 1;
  return { range: [lo - pad, hi + pad], autorange: false };
}
function drawSim() {
  const r = SIM.last, a = simTraces(r, "A", "solid"), s = r.summary;
  let t1 = a[0], t2 = a[1];
  if (SIM.ref) { const b = simTraces(SIM.ref, "B", "dot"); t1 = t1.concat(b[0]); t2 = t2.concat(b[1]); }
  const ev = [];
  if (s.jump_in && s.jump_in.piezo_position !== null) ev.push({ x: [s.jump_in.piezo_position * 1e9], y: [0], name: "jump-in", mode: "markers", marker: { size: 11, symbol: "triangle-down", color: "#6a3d9a" }, hovertemplate: "jump-in at z = %{x:.2f} nm<extra></extra>" });
  if (s.pull_off && s.pull_off.piezo_position !== null) ev.push({ x: [s.pull_off.piezo_position * 1e9], y: [0], name: "pull-off", mode: "markers", marker: { size: 11, symbol: "x", color: "#b00020" }, hovertemplate: "pull-off at z = %{x:.2f} nm<extra></extra>" });
  Plotly.react("sim-plot-defl", t1.concat(ev), { ...LAYOUT, title: { text: "Apparent vs actual deflection" }, xaxis: { title: { text: "piezo position z [nm]" }, ...box(t1, "x") }, yaxis: { title: { text: "deflection [nm]" }, ...box(t1, "y") } }, CONFIG);
  Plotly.react("sim-plot-force", t2, { ...LAYOUT, title: { text: "Force vs separation" }, xaxis: { title: { text: "separation h [nm]" }, ...box(t2, "x") }, yaxis: { title: { text: "normal force [nN]" }, ...box(t2, "y") } }, CONFIG);
  const rowOf = (x) => x && [fmt(x.summary.jump_in.separation, "m"), fmt(x.summary.jump_in.piezo_position, "m"), fmt(x.summary.pull_off.force, "N"), fmt(x.summary.min_apparent_deflection, "m"), fmt(x.summary.spike_height, "m"), fmt(x.summary.hysteresis_offset, "m"), `${x.summary.solver.status}, ${x.summary.solver.steps} steps`];
  const heads = ["jump-in separation", "jump-in z", "pull-off force", "min apparent deflection", "spike", "compliance offset", "solver"];
  const rows = heads.map((h, i) => [h, rowOf(r)[i]].concat(SIM.ref ? [rowOf(SIM.ref)[i]] : []));
  $("sim-summary").replaceChildren(table(rows, ["event", "run A"].concat(SIM.ref ? ["run B"] : [])));
}
function buildSim() {
  const box = $("sim-controls"); box.replaceChildren(); SIM.controls = [];
  let part = "";
  for (const f of SCHEMA.simulation) {
    if (f.part !== part) { part = f.part; box.append(el("div", { class: "group", text: part })); }
    const c = control(f, () => { if (f.name === "model") showModel(); simulate(); }, { slider: true });
    c.dataset.models = f.models.join(",");
    box.append(c); SIM.controls.push({ f, box: c });
  }
  showModel();
  SCHEMA.instrument_presets.forEach((p) => $("sim-preset").append(el("option", { value: p, text: p })));
  $("sim-preset").value = SCHEMA.instrument_presets.includes("typical") ? "typical" : SCHEMA.instrument_presets[0];
}
function showModel() {
  const model = SIM.controls.find((c) => c.f.name === "model").box.get();
  SIM.controls.forEach((c) => c.box.classList.toggle("hidden", !c.f.models.includes(model)));
}
$("sim-keep").addEventListener("click", () => { SIM.ref = SIM.last; drawSim(); });
$("sim-clear").addEventListener("click", () => { SIM.ref = null; drawSim(); });
$("sim-raw").addEventListener("click", async () => {
  const r = await fetch(`api/simulate/raw?preset=${$("sim-preset").value}`, { method: "POST", headers: { "content-type": "application/json" }, body: JSON.stringify(simConfig()) });
  if (!r.ok) { let b = {}; try { b = await r.json(); } catch { /* not JSON */ } $("sim-error").textContent = errorText(b, r); return; }
  download(`virtual-${$("sim-preset").value}.raw`, await r.blob());
});

// ---- jobs (fit, sweep) ------------------------------------------------------------------------
function follow(id, prefix, onEnd) {
  const es = new EventSource(`api/jobs/${id}/events`);
  $(prefix + "-cancel").disabled = false;
  es.addEventListener("progress", (e) => {
    const d = JSON.parse(e.data), p = d.progress || {};
    if (p.what) (window.PROGRESS = window.PROGRESS || []).push(`${prefix}: ${p.what}`);
    if (p.fraction !== undefined && p.fraction !== null) $(prefix + "-progress").value = p.fraction;
    $(prefix + "-state").textContent = `${d.state}${p.what ? ": " + p.what : ""}${p.total ? ` (${p.done}/${p.total} ${p.unit})` : ""}`;
  });
  es.addEventListener("end", async (e) => {
    await plotlyLoaded();
    es.close(); const job = JSON.parse(e.data);
    $(prefix + "-cancel").disabled = true; $(prefix + "-progress").value = job.state === "done" ? 1 : $(prefix + "-progress").value;
    $(prefix + "-state").textContent = job.state + (job.resumed ? ` (resumed ${job.resumed}x)` : "");
    if (job.error) $(prefix + "-error").textContent = job.error;
    if (job.result) onEnd(job.result);
    listJobs();
  });
  $(prefix + "-cancel").onclick = () => api(`api/jobs/${id}/cancel`, { method: "POST" });
}

// ---- Fit --------------------------------------------------------------------------------------
$("fit-run").addEventListener("click", async () => {
  $("fit-error").textContent = ""; $("fit-verdict").textContent = ""; $("fit-progress").value = 0;
  try {
    let ids = [];
    const files = $("fit-files").files;
    if (files.length) {  // upload them first (an analysis also checks they read)
      const fd = new FormData(); for (const f of files) fd.append("file", f);
      ids = (await api("api/analyze", { method: "POST", body: fd })).files.map((f) => f.id);
    }
    const free = [...document.querySelectorAll("#fit-free input:checked")].map((c) => c.value);
    // a plain number is in the field's unit; anything else goes as typed (a value with units, or a
    // mistake the server names): never NaN, which JSON.stringify would turn into null
    const val = (t, f) => { t = String(t).trim(); return t !== "" && isFinite(Number(t)) ? Number(t) * f : t; };
    const seed = $("fit-seed").value.trim();
    const body = { file_ids: ids, meta: ids.length ? fitMetaTexts() : [], free, seed: /^\d+$/.test(seed) ? Number(seed) : seed, compare: $("fit-compare").checked, profile: $("fit-profile").checked,
      velocities: ids.length ? [] : $("fit-speeds").value.split(",").map((v) => val(v, 1e-6)),
      truth: ids.length ? {} : { xi: val($("fit-xi").value, 1), hamaker: val($("fit-hamaker").value, 1e-21) } };
    const job = await api("api/fit", { method: "POST", headers: { "content-type": "application/json" }, body: JSON.stringify(body) });
    $("fit-state").textContent = "started";
    follow(job.id, "fit", drawFit);
  } catch (e) { $("fit-error").textContent = e.message; }
});
function drawFit(r) {
  $("fit-verdict").textContent = r.verdict;
  const rows = Object.entries(r.parameters).map(([n, p]) => [n, `${Number(p.value.toPrecision(4))} ${p.unit}`, `± ${Number(p.stderr.toPrecision(3))}`, `[${p.interval.map((x) => (x === null ? "open" : Number(x.toPrecision(4)))).join(", ")}] (${p.interval_method})`]);
  $("fit-table").replaceChildren(table(rows, ["parameter", "value", "std. error", `${r.level * 100}% interval`]), el("p", { class: "muted", text: `reduced chi-square ${r.redchi.toFixed(3)}; ${r.model_evaluations} model evaluations in ${r.wall_time.toFixed(1)} s` }));
  const tr = [];
  r.plots.forEach((p, i) => {
    tr.push({ x: sc(p.position, 1e9), y: sc(p.data, 1e9), name: `${p.name} data`, mode: "markers", marker: { size: 3 }, hovertemplate: "z = %{x:.2f} nm<br>%{y:.4f} nm<extra>data</extra>" });
    if (p.model) tr.push({ x: sc(p.position, 1e9), y: sc(p.model, 1e9), name: `${p.name} model`, mode: "lines", hovertemplate: "z = %{x:.2f} nm<br>%{y:.4f} nm<extra>model</extra>" });
  });
  Plotly.react("fit-plot", tr, { ...LAYOUT, title: { text: "Data and fitted model" }, xaxis: { title: { text: "piezo position z − shift [nm]" } }, yaxis: { title: { text: "apparent deflection [nm]" } } }, CONFIG);
  // one panel per profiled parameter, each with its own axis in its unit (two parameters never share
  // one log axis spanning many decades)
  const prof = Object.entries(r.profiles || {});
  const pr = prof.map(([n, p], i) => ({ x: p.value || p.values || [], y: p.delta_chi2 || p.chi2 || [], name: n, mode: "lines+markers",
    xaxis: i ? `x${i + 1}` : "x", yaxis: i ? `y${i + 1}` : "y", showlegend: false }));
  if (pr.length) {
    const layout = { ...LAYOUT, title: { text: "Profile likelihoods" }, grid: { rows: 1, columns: pr.length, pattern: "independent" } };
    prof.forEach(([n], i) => {
      const xs = pr[i].x.filter((v) => typeof v === "number" && v > 0), unit = ((r.parameters || {})[n] || {}).unit || (SCHEMA.fit.find((p) => p.name === n) || {}).unit || "-";
      const log = xs.length === pr[i].x.length && xs.length > 1 && Math.max(...xs) / Math.min(...xs) > 100;
      layout[i ? `xaxis${i + 1}` : "xaxis"] = { title: { text: `${n} [${unit}]` }, type: log ? "log" : "linear" };
      layout[i ? `yaxis${i + 1}` : "yaxis"] = { title: { text: "Δχ² [-]" } };
    });
    Plotly.react("fit-profiles", pr, layout, CONFIG);
  }
}

// ---- Sweep ------------------------------------------------------------------------------------
const SW = { result: null };
$("sw-run").addEventListener("click", async () => {
  $("sw-error").textContent = ""; $("sw-progress").value = 0;
  const lines = (id) => $(id).value.split("\n").map((s) => s.trim()).filter(Boolean);
  try {
    const job = await api("api/sweep", { method: "POST", headers: { "content-type": "application/json" }, body: JSON.stringify({ grid: lines("sw-grid"), sets: lines("sw-sets"), executor: $("sw-executor").value }) });
    follow(job.id, "sw", drawSweep); listJobs();
  } catch (e) { $("sw-error").textContent = e.message; }
});
async function listJobs() {
  const jobs = await api("api/jobs");
  $("sw-jobs").replaceChildren(table(jobs.map((j) => [j.kind, j.state + (j.resumed ? ` (resumed)` : ""), new Date(j.created * 1000).toLocaleTimeString()]), ["job", "state", "started"]));
  const rows = $("sw-jobs").querySelectorAll("tr");
  jobs.forEach((j, i) => { rows[i + 1].style.cursor = "pointer"; rows[i + 1].onclick = async () => { const full = await api(`api/jobs/${j.id}`); await plotlyLoaded(); if (full.result) (j.kind === "fit" ? drawFit : drawSweep)(full.result); else if (full.state === "running") follow(j.id, j.kind === "fit" ? "fit" : "sw", j.kind === "fit" ? drawFit : drawSweep); }; });
}
function drawSweep(r) {
  SW.result = r;
  const numeric = r.columns.filter((c, i) => !r.parameters.includes(c) && r.rows.some((row) => typeof row[i] === "number"));
  const sel = $("sw-metric"), keep = sel.value; sel.innerHTML = "";
  numeric.forEach((c) => sel.append(el("option", { value: c, text: `${c} [${r.units[c] || "-"}]` })));
  sel.value = numeric.includes(keep) ? keep : (numeric.includes("min_apparent_deflection") ? "min_apparent_deflection" : numeric[0]);
  drawSweepPlot();
  const shown = r.rows.slice(0, 200);
  $("sw-table").replaceChildren(el("p", { class: "muted", text: `${r.n_runs} runs (${r.n_failed} failed); ${r.chunks_run} chunks run, ${r.chunks_skipped} resumed from the store` }),
    table(shown.map((row) => row.map((v) => (typeof v === "number" ? Number(v.toPrecision(5)) : v ?? "–"))), r.columns.map((c) => (r.units[c] ? `${c} [${r.units[c]}]` : c))));
}
function drawSweepPlot() {
  const r = SW.result, m = $("sw-metric").value; if (!r || !m) return;
  const ci = r.columns.indexOf(m), p = r.parameters, i0 = r.columns.indexOf(p[0]);
  let traces;
  if (p.length >= 2) {
    const i1 = r.columns.indexOf(p[1]), groups = {};
    r.rows.forEach((row) => { (groups[row[i1]] = groups[row[i1]] || []).push(row); });
    traces = Object.entries(groups).map(([g, rows]) => ({ x: rows.map((w) => w[i0]), y: rows.map((w) => w[ci]), name: `${p[1]} = ${Number(Number(g).toPrecision(3))} ${r.units[p[1]] || ""}`, mode: "lines+markers" }));
  } else traces = [{ x: r.rows.map((w) => w[i0]), y: r.rows.map((w) => w[ci]), mode: "lines+markers", name: m }];
  Plotly.react("sw-plot", traces, { ...LAYOUT, title: { text: m }, xaxis: { title: { text: `${p[0]} [${r.units[p[0]] || "-"}]` }, type: "log" }, yaxis: { title: { text: `${m} [${r.units[m] || "-"}]` } } }, CONFIG);
}
$("sw-metric").addEventListener("change", drawSweepPlot);
$("an-calfile").addEventListener("change", (e) => { if (e.target.files[0]) loadCalibrationFile(e.target.files[0]); e.target.value = ""; });

// ---- start ------------------------------------------------------------------------------------
(async () => {
  try {
    Object.assign(SCHEMA, await api("api/schema"));
    SCHEMA.examples.forEach((e) => $("an-example").append(el("option", { value: e.name, text: `${e.name}: ${e.description}` })));
    buildOptions(); buildSettings(); buildCalibration(); buildFitCalibration(); buildSim();
    SCHEMA.fit.forEach((p) => $("fit-free").append(el("label", {}, Object.assign(el("input", { type: "checkbox", value: p.name }), { checked: SCHEMA.fit_defaults.free.includes(p.name) }), ` ${p.name} [${p.unit}]`)));
    $("fit-profile").checked = SCHEMA.fit_defaults.profile; $("fit-compare").checked = SCHEMA.fit_defaults.compare;   // afmforce fit's
    await restoreAnalyse().catch((e) => { $("an-error").textContent = e.message; });
    document.body.dataset.ready = "1";
    window.READY_MS = performance.now();   // page load to interactive (benchmarks/bench_web.py)
    setTimeout(() => plotlyLoaded().catch((e) => { $("status").textContent = e.message; }), 0);
  } catch (e) { $("status").textContent = "cannot reach the server: " + e.message; }
})();
