// afmforce serve: the modulus fit's range dragged on the force-vs-indentation plot (issue 33.4).
// The handle is the option indentation.max_indentation (the analysis's own option, its control in the
// left column): dropping the handle types the value there and the analysis re-runs, as a typed value
// does. Loaded before app.js; uses its AN and $ when called.
"use strict";
const FIT_RANGE = { room: {} };   // per curve: the deepest indentation of the whole-run fit [nm] (room to drag back)

function fitRangeControl() {
  return (typeof AN === "undefined" ? [] : AN.controls).find((c) => c.step === "indentation" && c.f.name === "max_indentation");
}

// the layout parts of the force-vs-indentation plot: the draggable fit limit (the only shape: the
// plot's config lets shapes move) and the x range that leaves room to drag it back out
function fitRangeLayout(name, fit, x) {
  const c = fitRangeControl(), given = c ? c.box.get() : null;
  const deepest = Math.max(...x), shallowest = Math.min(...x);
  if (typeof given !== "number") FIT_RANGE.room[name] = deepest;    // the whole run: how deep it goes
  const limit = typeof given === "number" ? given * 1e9 : deepest;
  const room = Math.max(FIT_RANGE.room[name] || deepest, deepest, limit);
  const left = Math.max(Math.min(shallowest, 0), -room);   // as much baseline as indentation: the contact region in view
  const pad = 0.06 * (room - left) || 1;
  return {
    xrange: [left - pad, room + pad],
    shapes: [{ type: "line", xref: "x", yref: "paper", x0: limit, x1: limit, y0: 0, y1: 1, name: "fit range",
      line: { color: "#b00020", width: 4, dash: "dot" } }],
    annotations: [{ xref: "x", yref: "paper", x: limit, y: 0.98, xanchor: "right", yanchor: "top", showarrow: false,
      text: typeof given === "number" ? `fit to δ ≤ ${Number(limit.toPrecision(4))} nm ⇠ drag ⇢` : "whole run fitted ⇠ drag to limit",
      font: { size: 11, color: "#b00020" }, bgcolor: "rgba(255,255,255,0.8)" }],
  };
}

// the contact point (δ = 0) as a trace (its hover): fitted with E and the baseline, or given
// (indentation.contact_point, dragged: contactPointBind)
function contactPointTrace(fit, ys) {
  const lo = Math.min(...ys), hi = Math.max(...ys);
  const se = fit.contact_point_se !== null && isFinite(fit.contact_point_se) ? ` ± ${Number((fit.contact_point_se * 1e9).toPrecision(3))} nm` : "";
  const how = fit.contact_point_se === 0 ? "given" : "fitted";
  return { x: [0, 0], y: [lo, hi], mode: "lines", name: `contact point (${how}) ⇠ drag ⇢`, line: { color: "#555", dash: "dash", width: 1 },
    hovertemplate: `contact point, ${how}: z = ${Number((fit.contact_point * 1e9).toPrecision(6))} nm${se}<extra></extra>` };
}

// a dropped handle -> the option's value (SI -> its control's unit) and a re-run; dragged to the
// right end (past the whole run) -> the option cleared: the whole run again
function fitRangeBind(div) {
  optionHandleBind(div, "indentation", "max_indentation", () => FIT_RANGE.room[$("an-curve").value]);
}

// the handle of one option on a plot (its shape number ``index``): dropped, its x [nm] is typed in the
// option's field and the analysis re-runs (past clearAt(): the field emptied, the option's default
// again); value(nm): the option's value [SI] at x (default: a positive length, x itself)
function optionHandleBind(div, step, name, clearAt = () => undefined, index = 0,
  value = (nm) => Math.max(nm, 1e-3) * 1e-9, digits = 4) {
  // one listener per handle, bound again on each draw (a purged plot -- hidden -- has lost its listeners)
  const key = `_afmHandle${index}`;
  if (div[key] && div.removeListener) div.removeListener("plotly_relayout", div[key]);
  div.dataset[`handle${index}`] = `${step}.${name}`;
  div[key] = (ev) => {
    const x0 = ev[`shapes[${index}].x0`], x1 = ev[`shapes[${index}].x1`];
    if (x0 === undefined && x1 === undefined) return;
    const c = (typeof AN === "undefined" ? [] : AN.controls).find((x) => x.step === step && x.f.name === name); if (!c) return;
    const nm = (Number(x0 ?? x1) + Number(x1 ?? x0)) / 2, end = clearAt();
    const input = c.box.querySelector("input.val");
    if (end !== undefined && nm >= end) input.value = "";
    else input.value = String(Number((value(nm) / c.f.factor).toPrecision(digits)));
    window.FIT_RANGE_DROPS = (window.FIT_RANGE_DROPS || 0) + 1;
    input.dispatchEvent(new Event("change"));
  };
  div.on("plotly_relayout", div[key]);
}

// the contact point (δ = 0, the plot's shape 1) dragged: the option indentation.contact_point, the
// tip depth u = z - deflection, fixed there (the fit's contact depth plus the drop's δ); cleared in
// its field, the contact point is fitted again
function contactPointShape(fit) {
  const given = fit.contact_point_se === 0;
  return { type: "line", xref: "x", yref: "paper", x0: 0, x1: 0, y0: 0, y1: 1, name: "contact point",
    line: { color: given ? "#1f6feb" : "#555", width: 3, dash: "dash" } };
}
function contactPointBind(div) {
  const depth = () => { const r = ((AN.payload || {}).results || {})[$("an-curve").value];
    return (((r || {}).details || {}).indentation || {}).contact_depth; };
  optionHandleBind(div, "indentation", "contact_point", () => undefined, 1, (nm) => depth() + nm * 1e-9, 8);   // 8 digits: as the page sends options (1 pm at 10 um)
}

// the van der Waals fit's window on force vs separation: a handle for vdw.max_separation (hard
// contacts: the paper's eq 2 fitted up to it)
function vdwRangeLayout(res) {
  const v = ((res.details || {}).vdw) || {};
  const c = (typeof AN === "undefined" ? [] : AN.controls).find((x) => x.step === "vdw" && x.f.name === "max_separation");
  if (v.status !== "ok" || !c) return {};
  const given = c.box.get(), limit = (typeof given === "number" ? given : c.f.default) * 1e9;
  return { shapes: [{ type: "line", xref: "x", yref: "paper", x0: limit, x1: limit, y0: 0, y1: 1, name: "vdW fit range",
      line: { color: "#6a3d9a", width: 4, dash: "dot" } }],
    annotations: [{ xref: "x", yref: "paper", x: limit, y: 0.02, xanchor: "left", yanchor: "bottom", showarrow: false,
      text: `vdW fit to h ≤ ${Number(limit.toPrecision(4))} nm ⇠ drag ⇢`, font: { size: 11, color: "#6a3d9a" }, bgcolor: "rgba(255,255,255,0.8)" }] };
}
