// afmforce serve: the fit view's calibration of uploaded curves (issue 33): the spring constant k, the
// sensitivity (InvOLS) and the resonance frequency, typed or from a calibration file (afmforce
// calibrate --out), sent as the fit's metadata, exactly as `afmforce fit FILES --meta KEY=VALUE`
// (empty: each file's value). Loaded before app.js; uses its $, el, control and SCHEMA when called.
"use strict";
const FITCAL = { controls: [], keys: ["spring_constant", "sensitivity", "resonance_frequency"] };

function buildFitCalibration() {
  const box = $("fit-calibration"); box.replaceChildren(); FITCAL.controls = [];
  const labels = { spring_constant: "spring constant k", sensitivity: "sensitivity (InvOLS)", resonance_frequency: "resonance frequency" };
  for (const f of SCHEMA.calibration || []) {
    if (f.via !== "probe" || !FITCAL.keys.includes(f.name)) continue;
    const c = control(f, () => {}, { value: null });
    c.dataset.fitMeta = f.name;
    c.querySelector(".name").textContent = labels[f.name];
    box.append(c); FITCAL.controls.push({ f, box: c });
  }
}

// KEY=VALUE texts of the fields given (a value from the calibration file, untouched: its SI value, exactly)
function fitMetaTexts() {
  const out = [];
  for (const c of FITCAL.controls) {
    const v = c.box.get(), input = c.box.querySelector("input.val");
    if (v === null || v === "") continue;
    if (c.box.fromFile && input.value === c.box.fromFile.text) { out.push(`${c.f.name}=${c.box.fromFile.value}`); continue; }
    out.push(`${c.f.name}=${typeof v === "number" ? `${Number((v / c.f.factor).toPrecision(8))}${c.f.shown}` : v}`);
  }
  return out;
}

async function loadFitCalibrationFile(file) {   // fills k, InvOLS, f0; "from NAME" under each
  $("fit-calfile-error").textContent = "";
  const fd = new FormData(); fd.append("file", file);
  let r;
  try { r = await api("api/calibration", { method: "POST", body: fd }); } catch (e) { $("fit-calfile-error").textContent = e.message; return; }
  if (!Object.keys(r.values).length) { $("fit-calfile-error").textContent = `${r.source} holds no spring constant, sensitivity or resonance frequency`; return; }
  for (const c of FITCAL.controls) {
    if (!(c.f.name in r.values)) continue;
    const input = c.box.querySelector("input.val"), v = r.values[c.f.name];
    input.value = String(Number((v / c.f.factor).toPrecision(6)));
    c.box.fromFile = { value: v, text: input.value };
    let tag = c.box.querySelector(".from");
    if (!tag) { tag = el("div", { class: "from muted" }); c.box.append(tag); }
    tag.textContent = `from ${r.source}`;
    input.addEventListener("input", () => { if (input.value !== (c.box.fromFile || {}).text) tag.textContent = ""; });
  }
}
document.addEventListener("DOMContentLoaded", () => {
  $("fit-calfile").addEventListener("change", (e) => { if (e.target.files[0]) loadFitCalibrationFile(e.target.files[0]); e.target.value = ""; });
});
