"""End to end in a real browser: Debian's headless Chromium driven by Playwright (no browser download).

Upload a real file, change an option and see the plot change, move a slider and see a new
trajectory, run a small fit and read the verdict, and a malformed file as an error in the page.
Skipped where Chromium or Playwright is missing, unless ``AFMFORCE_REQUIRE_E2E=1`` (``.ci/run``).
With ``AFMFORCE_SCREENSHOTS=DIR`` each view is saved as a PNG (docs/web-*.png).
"""

from __future__ import annotations

import io
import json
import os
import time
from contextlib import redirect_stdout
from pathlib import Path

import pytest

# the `page` fixture (headless Chromium on the live server): tests/web/conftest.py


def _shot(page, name: str) -> None:
    folder = os.environ.get("AFMFORCE_SCREENSHOTS")
    if folder:
        time.sleep(0.5)
        page.screenshot(path=str(Path(folder) / f"web-{name}.png"))


def _vdw_max(page) -> float:
    return page.evaluate("""() => {
        const t = document.getElementById('an-plot-force').data.find(d => d.name.startsWith('vdW fit'));
        return t ? Math.max(...t.x) : -1; }""")


def test_upload_a_real_file_and_change_an_option(page):
    from afmforce.datasets import path

    page.set_input_files("#an-files", str(path("asylum-air")))        # Asylum MFP-3D .ibw, real
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-plot-force').data", timeout=60_000)
    assert "asylum" in page.inner_text("#an-curve")
    before = _vdw_max(page)
    assert before > 20                                     # default fit window: 30 nm
    page.click("#an-options details:has([data-option='vdw.max_separation']) summary")
    box = page.locator("[data-option='vdw.max_separation'] input")
    box.fill("15")
    box.dispatch_event("change")
    page.wait_for_function("""() => {
        const t = document.getElementById('an-plot-force').data.find(d => d.name.startsWith('vdW fit'));
        return t && Math.max(...t.x) <= 15.0001; }""", timeout=30_000)
    assert _vdw_max(page) <= 15.0001 < before
    assert "diagnosis" in page.inner_text("#an-summary")
    _shot(page, "analyse")


def test_a_reload_restores_the_uploads_and_the_analysis(page):
    """Issue 33.3: a reload loses nothing: the session's uploads are listed, the last analysis is
    reopened with the option changed before (vdw.max_separation = 15 nm)."""
    page.reload()
    page.wait_for_selector("body[data-ready='1']", timeout=60_000)
    assert "asylum" in page.inner_text("#an-uploads")
    page.wait_for_function("document.getElementById('an-plot-force').data", timeout=60_000)
    assert "asylum" in page.inner_text("#an-curve")
    assert _vdw_max(page) <= 15.0001
    assert page.locator("[data-option='vdw.max_separation'] input").input_value() == "15"


def test_calibration_fields_show_the_used_values_and_the_models_reason(page):
    """Issue 33.4: k typed in the page is the k the analysis uses (shown under the field); the model
    dropdown holds the contact registry; a step that cannot run says why."""
    from afmforce.contact import INDENTATION_MODELS

    options = page.eval_on_selector_all("[data-option='indentation.model'] select option", "os => os.map(o => o.value)")
    assert options == list(INDENTATION_MODELS)
    used = page.locator("[data-probe='spring_constant'] .used")
    page.wait_for_function("document.querySelector(\"[data-probe='spring_constant'] .used\").textContent.includes('used')",
                           timeout=30_000)
    assert "N/m" in used.inner_text()
    box = page.locator("[data-probe='spring_constant'] input.val")
    box.fill("0.5")
    box.dispatch_event("change")
    page.wait_for_function("document.querySelector(\"[data-probe='spring_constant'] .used\").textContent.includes('used 0.5 N/m')",
                           timeout=30_000)
    reason = page.inner_text("[data-option='indentation.model'] .used")
    assert reason.startswith("not run: hard contact"), reason      # the real Asylum file: a hard contact
    assert "indentation (not run)" in page.inner_text("#an-summary")
    box.fill("")                                   # back to the file's value
    box.dispatch_event("change")
    page.wait_for_function("!document.querySelector(\"[data-probe='spring_constant'] .used\").textContent.includes('used 0.5 N/m')",
                           timeout=30_000)


def test_a_calibration_file_fills_the_fields(page, tmp_path):
    """Issue 34.4: calib.json (afmforce calibrate --out) fills k and f0, each marked "from calib.json",
    and the analysis uses them; a foreign file is refused in the page."""
    from afmforce.cli.main import main

    cal = tmp_path / "calib.json"
    with redirect_stdout(io.StringIO()):
        assert main(["calibrate", "--out", str(cal), "sader", "--length", "200um", "--width", "30um",
                     "--frequency", "30kHz", "--quality-factor", "2"]) == 0
    k = json.loads(cal.read_text())["spring_constant"]
    page.set_input_files("#an-calfile", str(cal))
    for name in ("spring_constant", "resonance_frequency"):
        page.wait_for_function(f"document.querySelector(\"[data-probe='{name}'] .from\")?.textContent === 'from calib.json'",
                               timeout=30_000)
    assert float(page.locator("[data-probe='spring_constant'] input.val").input_value()) == pytest.approx(k, rel=1e-5)
    page.wait_for_function(f"document.querySelector(\"[data-probe='spring_constant'] .used\").textContent.includes('used {k:.4g} N/m')",
                           timeout=30_000)
    foreign = tmp_path / "other.json"
    foreign.write_text('{"spring_constant": 0.1}')
    page.set_input_files("#an-calfile", str(foreign))
    page.wait_for_function("document.getElementById('an-calfile-error').textContent.includes('not an afmforce calibration file')",
                           timeout=30_000)
    for name in ("spring_constant", "resonance_frequency"):      # back to the file's values
        box = page.locator(f"[data-probe='{name}'] input.val")
        box.fill("")
        box.dispatch_event("change")
    assert page.inner_text("[data-probe='spring_constant'] .from") == ""


def test_the_modulus_fit_on_force_vs_indentation(page):
    """Issue 33.4: a cell (the shipped JPK curve) with its tip radius typed in the calibration field:
    E with its interval and the fitted curve drawn on force vs indentation, the numbers of the API."""
    page.select_option("#an-example", "jpk-cell")
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-curve').value.includes('jpk-cell')", timeout=60_000)
    reason = page.inner_text("[data-option='indentation.model'] .used")
    assert reason.startswith("not run") and "radius" in reason, reason      # no tip radius yet: says so
    box = page.locator("[data-option='indentation.tip_radius'] input.val")
    box.fill("5000")                                                           # nm: a 5 µm bead
    box.dispatch_event("change")
    page.wait_for_function("document.getElementById('an-plot-indentation').data", timeout=60_000)
    api = page.evaluate("""() => { const fd = new FormData(); fd.append('example', 'jpk-cell');
        fd.append('option', 'indentation.tip_radius=5um'); fd.append('arrays', 'true');
        fd.append('max_points', String(AN.payload.max_points));     // the screen's width, as the page asked
        return fetch('api/analyze', {method: 'POST', body: fd}).then(r => r.json()); }""")
    fit = next(iter(api["results"].values()))["details"]["indentation"]
    drawn = page.evaluate("document.getElementById('an-plot-indentation').data[1]")
    want = sorted(zip([d * 1e9 for d in fit["indentation"]], [(f - fit["baseline"]) * 1e9 for f in fit["fit_force"]]))
    assert drawn["x"] == pytest.approx([w[0] for w in want]) and drawn["y"] == pytest.approx([w[1] for w in want])
    title = page.evaluate("document.querySelector('#an-plot-indentation .g-gtitle text').textContent")
    assert f"{fit['youngs_modulus'] / 1e3:.4g} kPa" in title, title
    assert "E = " in page.inner_text("[data-option='indentation.model'] .used")
    box.fill("")
    box.dispatch_event("change")
    page.wait_for_function("document.getElementById('an-plot-indentation').classList.contains('hidden')", timeout=60_000)
    page.select_option("#an-example", "")


def test_a_sandboxed_frame_cannot_write(page, live_server):
    """Issue 33.2: a sandboxed iframe (Origin: null) on a page can neither upload, analyse nor start a
    fit: its form posts get 403, and the session holds no more than before."""
    before = page.evaluate("fetch('api/session').then(r => r.json())")
    html = f"""<form id=a method=post enctype=multipart/form-data action="{live_server}api/analyze" target=_self>
      <input type=hidden name=example value=asylum-air><input type=file name=file></form>
      <script>document.getElementById('a').submit();</script>"""
    page.evaluate("""(html) => { const f = document.createElement('iframe');
        f.setAttribute('sandbox', 'allow-scripts allow-forms'); f.id = 'evil'; f.srcdoc = html;
        document.body.append(f); }""", html)
    deadline = time.monotonic() + 300
    frame = None
    while time.monotonic() < deadline:
        frame = next((f for f in page.frames if "/api/analyze" in f.url), None)
        if frame is not None and "error" in (frame.inner_text("body") or ""):
            break
        page.wait_for_timeout(200)        # lets Playwright see the frame's navigation (time.sleep would not)
    assert frame is not None, [f.url for f in page.frames]
    text = frame.inner_text("body")
    assert "forbidden" in text and "opaque origin" in text, text
    fit = """<form id=b method=post enctype=text/plain action="%sapi/fit" target=_self>
      <input type=hidden name='{"velocities":[1e-6,2e-6],"x":"' value='"}'></form>
      <script>document.getElementById('b').submit();</script>""" % live_server
    page.evaluate("(html) => { const f = document.getElementById('evil'); f.srcdoc = html; }", fit)
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline:
        frame = next((f for f in page.frames if "/api/fit" in f.url), None)
        if frame is not None and "error" in (frame.inner_text("body") or ""):
            break
        page.wait_for_timeout(200)        # lets Playwright see the frame's navigation (time.sleep would not)
    assert frame is not None and "forbidden" in frame.inner_text("body")
    after = page.evaluate("fetch('api/session').then(r => r.json())")
    assert after["files"] == before["files"] and len(after["jobs"]) == len(before["jobs"])
    page.evaluate("document.getElementById('evil').remove()")


def test_every_map_quantity_is_drawn_with_titled_axes(page):
    """Issue 33.4/33.5: a force map's every quantity can be drawn (a selector), each heat map with its
    axes titled in µm and its colour bar titled with the quantity and its unit; the adhesion marker
    of a curve sits on the curve."""
    data = Path(__file__).resolve().parents[1] / "data" / "afmforce-map_jpk-map2x2.h5"
    page.set_input_files("#an-files", str(data))
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-plot-map').data", timeout=60_000)
    values = page.eval_on_selector_all("#an-map-quantity option", "os => os.map(o => o.value)")
    assert len(values) >= 2
    labels = set()
    for v in values:
        page.select_option("#an-map-quantity", v)
        page.wait_for_timeout(200)
        titles = page.evaluate("""() => { const gd = document.getElementById('an-plot-map');
            const q = (s) => [...gd.querySelectorAll(s)].map(t => t.textContent.trim());
            return {x: q('.g-xtitle text'), y: q('.g-ytitle text'), bar: q('.colorbar .cbtitle text, .colorbar [class*=title] text'),
                    all: [...gd.querySelectorAll('text')].map(t => t.parentNode.getAttribute('class') + ':' + t.textContent)}; }""")
        assert titles["x"] == ["x [µm]"] and titles["y"] == ["y [µm]"], titles
        empty = page.evaluate("document.getElementById('an-plot-map').data[0].z.every(r => r.every(v => v === null))")
        if empty:       # a quantity no curve of the 2x2 extract gives: said so on the plot, with why (the note)
            assert any("no curve gave it" in t for t in titles["all"]), " | ".join(titles["all"])
            continue
        assert titles["bar"] and "[" in titles["bar"][0], " | ".join(titles["all"])
        labels.add(titles["bar"][0])
    assert len(labels) >= 2          # each quantity drawn, not the first again
    on_curve = page.evaluate("""() => { const gd = document.getElementById('an-plot-force');
        const m = gd.data.find(d => d.name.startsWith('adhesion')); if (!m) return null;
        const curve = gd.data.filter(d => d.name === 'retract')[0];
        return curve.x.some((x, i) => x === m.x[0] && curve.y[i] === m.y[0]); }""")
    assert on_curve is True


def test_the_curves_of_a_map_in_one_table_histogram_and_csv(page, tmp_path):
    """Issue 33.4: the curves of the map above in one table (units in the header), a histogram of a
    chosen column and a CSV whose numbers are the API's, read back independently."""
    import csv

    page.wait_for_selector("#an-batch:not(.hidden)", timeout=30_000)
    rows = page.locator("#an-batch-table tr").count()
    assert rows == 1 + 4                                  # the four curves of the 2x2 extract
    page.select_option("#an-batch-col", "adhesion_force")
    page.wait_for_function("document.getElementById('an-batch-hist').data[0].x.length >= 1", timeout=10_000)
    titles = page.evaluate("""() => [...document.querySelectorAll('#an-batch-hist .g-xtitle text, #an-batch-hist .g-ytitle text')]
        .map(t => t.textContent)""")
    assert titles == ["adhesion_force [N]", "curves [count]"], titles
    with page.expect_download() as got:
        page.click("#an-batch-csv")
    path = tmp_path / "curves.csv"
    got.value.save_as(path)
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    table = list(csv.DictReader(lines))
    assert len(table) == 4 and "adhesion_force [N]" in table[0]
    fid = page.evaluate("AN.files[0].id")
    api = page.evaluate(f"""() => {{ const fd = new FormData(); fd.append('file_id', '{fid}');
        return fetch('api/analyze', {{method: 'POST', body: fd}}).then(r => r.json()); }}""")["results"]
    for row in table:
        want = api[row["curve"]]["adhesion_force"]
        assert (row["adhesion_force [N]"] == "" and want is None) or float(row["adhesion_force [N]"]) == want
    hist = page.evaluate("document.getElementById('an-batch-hist').data[0].x")
    assert sorted(hist) == sorted(float(r["adhesion_force [N]"]) for r in table if r["adhesion_force [N]"])


def test_malformed_file_is_an_error_in_the_page(page, live_server, tmp_path):
    bad = tmp_path / "broken.jpk-force"
    bad.write_bytes(b"PK\x03\x04 this is no zip archive")
    page.set_input_files("#an-files", str(bad))
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-error').textContent.includes('broken.jpk-force')",
                           timeout=30_000)
    assert page.evaluate("fetch('api/health').then(r => r.json()).then(j => j.status)") == "ok"


def test_move_a_slider_and_see_a_new_trajectory(page):
    page.click("button[data-view=simulate]")
    page.wait_for_function("Number(document.body.dataset.simCount || 0) >= 1", timeout=60_000)
    trace = "document.getElementById('sim-plot-defl').data[1].y.slice(0, 1500).join(',')"
    first = page.evaluate(trace)
    n = int(page.evaluate("document.body.dataset.simCount"))
    slider = page.locator("[data-slider='xi']")
    lo = float(slider.get_attribute("min"))
    slider.fill(str(lo))                                   # xi to the bottom of the slider
    page.wait_for_function(f"Number(document.body.dataset.simCount) > {n}", timeout=30_000)
    page.wait_for_function("!document.getElementById('sim-time').textContent.includes('…')", timeout=5_000)
    assert page.evaluate(trace) != first
    xi = float(page.locator(".field[data-name='xi'] input.val").input_value())
    expected = 10 ** lo if slider.get_attribute("data-log") == "1" else lo
    assert xi == pytest.approx(expected, rel=1e-4, abs=1e-12)        # the box follows the slider
    _shot(page, "simulate")


def test_run_a_small_fit_and_read_the_verdict(page):
    page.click("button[data-view=fit]")
    page.fill("#fit-speeds", "1, 4")
    page.uncheck("#fit-profile")
    page.click("#fit-run")
    page.wait_for_function("document.getElementById('fit-verdict').textContent.includes('friction')",
                           timeout=180_000)
    verdict = page.inner_text("#fit-verdict")
    assert verdict.startswith("friction detected"), verdict     # virtual curves made with xi = 0.005 kg/s
    assert "xi" in page.inner_text("#fit-table")
    assert page.evaluate("document.getElementById('fit-progress').value") == 1
    seen = page.evaluate("window.PROGRESS || []")          # stages pushed by the server (SSE)
    assert "fit: search" in seen and "fit: model comparison" in seen, seen
    _shot(page, "fit")
    assert not page.errors


def test_run_a_small_sweep_and_see_its_table(page):
    page.click("button[data-view=sweep]")
    page.fill("#sw-grid", "xi=0.003,0.03,0.3")
    page.fill("#sw-sets", "velocity=1um/s")
    page.select_option("#sw-executor", "serial")
    page.click("#sw-run")
    page.wait_for_function("document.querySelectorAll('#sw-table tr').length >= 4", timeout=120_000)
    head = page.inner_text("#sw-table tr:first-child")
    assert "xi" in head and "min_apparent_deflection" in head
    assert page.evaluate("document.getElementById('sw-plot').data[0].x.length") == 3
    assert "done" in page.inner_text("#sw-state")
    _shot(page, "sweep")


PLOTS = ["an-plot-force", "an-plot-raw", "an-plot-time", "an-plot-compliance", "sim-plot-defl", "sw-plot"]


def test_every_drawn_axis_has_a_title_with_its_unit(page):
    """Issue 33.5: every rendered axis of every drawn plot carries a title (Plotly title objects,
    read from the SVG the browser drew), with its unit in square brackets."""
    drawn = page.evaluate("""(ids) => ids.map((id) => {
        const gd = document.getElementById(id);
        if (!gd || !gd.data || !gd.data.length) return [id, null];
        const q = (sel) => [...gd.querySelectorAll(sel)].map((t) => t.textContent.trim());
        return [id, {x: q('.g-xtitle text'), y: q('.g-ytitle text')}];
    })""", PLOTS + [d for d in page.evaluate(
        "[...document.querySelectorAll('.plot')].map(e => e.id).filter(Boolean)") if d not in PLOTS])
    seen = 0
    for pid, titles in drawn:
        if titles is None:
            continue
        seen += 1
        for axis in ("x", "y"):
            assert titles[axis] and all(titles[axis]), (pid, axis, titles)
            assert all("[" in t and "]" in t or "index" in t for t in titles[axis]), (pid, axis, titles)
    assert seen >= 4, drawn          # the analysis, the simulation and the sweep were drawn before


def test_no_legend_over_an_axis_title_and_no_title_clipped(page):
    """Issue 33.5: in every drawn plot, the rendered legend box overlaps no axis title, and every
    axis title lies inside its plot's drawing (not clipped)."""
    boxes = page.evaluate("""() => [...document.querySelectorAll('.plot')].filter(gd => gd.data && gd.data.length
        && gd.offsetParent !== null).map(gd => {
        const r = (e) => { const b = e.getBoundingClientRect(); return [b.left, b.top, b.right, b.bottom]; };
        return {id: gd.id, svg: r(gd.querySelector('.main-svg')), legend: [...gd.querySelectorAll('.legend')].map(r),
                titles: [...gd.querySelectorAll('.g-xtitle text, .g-ytitle text')].map(r)};
    })""")
    # plots of views that are hidden now are checked where they are shown: switch through the views
    for view in ("simulate", "sweep", "analyse"):
        page.click(f"button[data-view={view}]")
        page.wait_for_timeout(300)
        boxes += page.evaluate("""() => [...document.querySelectorAll('.view.active .plot')].filter(gd => gd.data
            && gd.data.length).map(gd => {
            const r = (e) => { const b = e.getBoundingClientRect(); return [b.left, b.top, b.right, b.bottom]; };
            return {id: gd.id, svg: r(gd.querySelector('.main-svg')), legend: [...gd.querySelectorAll('.legend')].map(r),
                    titles: [...gd.querySelectorAll('.g-xtitle text, .g-ytitle text')].map(r)};
        })""")
    overlap = lambda a, b: a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]   # noqa: E731
    checked = 0
    for plot in boxes:
        for t in plot["titles"]:
            checked += 1
            s = plot["svg"]
            assert s[0] - 1 <= t[0] and t[2] <= s[2] + 1 and s[1] - 1 <= t[1] and t[3] <= s[3] + 1, plot
            for legend in plot["legend"]:
                assert not overlap(legend, t), plot
    assert checked >= 8, boxes


def test_each_profiled_parameter_has_its_own_axis(page):
    """Issue 33.5: the profiles of two parameters are drawn in two panels, each x axis titled with its
    parameter and unit (they were one log axis spanning 15 decades). The result is shaped as the
    library writes it (FitResult.to_dict: profiles NAME -> {value, delta_chi2})."""
    page.click("button[data-view=fit]")
    r = {"verdict": "friction detected", "level": 0.95, "redchi": 1.0, "model_evaluations": 10, "wall_time": 1.0,
         "plots": [], "parameters": {
             "hamaker": {"value": 5e-19, "stderr": 1e-20, "unit": "J", "interval": [4.8e-19, 5.2e-19],
                         "interval_method": "profile"},
             "xi": {"value": 0.005, "stderr": 1e-4, "unit": "kg/s", "interval": [0.0048, 0.0052],
                    "interval_method": "profile"}},
         "profiles": {"hamaker": {"value": [4.8e-19, 5e-19, 5.2e-19], "delta_chi2": [4, 0, 4]},
                      "xi": {"value": [0.0048, 0.005, 0.0052], "delta_chi2": [4, 0, 4]}}}
    page.evaluate("(r) => drawFit(r)", r)
    titles = page.evaluate("""() => [...document.querySelectorAll('#fit-profiles .g-xtitle text, #fit-profiles [class^=g-x] text')]
        .map(t => t.textContent)""")
    assert "hamaker [J]" in titles and "xi [kg/s]" in titles, titles
    axes = page.evaluate("Object.keys(document.getElementById('fit-profiles')._fullLayout).filter(k => /^xaxis\\d*$/.test(k))")
    assert len(axes) == 2, axes


# every text box of a drawn plot, read from the DOM the browser laid out: the axes (each with its
# rendered title), the plot's title, the legend, the colour bar, the tick labels; boxes [l, t, r, b]
_BOXES = """(view) => [...document.querySelectorAll('#view-' + view + ' .plot')].filter(gd => gd.data && gd.data.length
    && gd._fullLayout && gd.offsetParent !== null).map(gd => {
    const r = (e) => { const b = e.getBoundingClientRect(); return [b.left, b.top, b.right, b.bottom]; };
    const seen = (e) => { const b = e.getBoundingClientRect(); return b.width > 0 && b.height > 0; };
    const L = gd._fullLayout;
    const axes = Object.keys(L).filter(k => /^[xy]axis\\d*$/.test(k) && L[k].visible !== false).map(k => {
        const t = gd.querySelector('.g-' + L[k]._id + 'title text');
        return {axis: gd.id + ':' + L[k]._id, text: t ? t.textContent.trim() : '', box: t && seen(t) ? r(t) : null};
    });
    const title = gd.querySelector('.g-gtitle text');
    return {id: gd.id, svg: r(gd.querySelector('.main-svg')), div: r(gd), axes,
            title: title && seen(title) ? {text: title.textContent, box: r(title)} : null,
            legend: [...gd.querySelectorAll('.legend')].filter(seen).map(r),
            colorbar: [...gd.querySelectorAll('.colorbar')].filter(seen).map(r),
            ticks: [...gd.querySelectorAll('.xtick text, .ytick text')].filter(seen).map(t => ({text: t.textContent, box: r(t)}))};
})"""


def _overlap(a, b, tol=1.0) -> bool:
    return a[0] + tol < b[2] and b[0] + tol < a[2] and a[1] + tol < b[3] and b[1] + tol < a[3]


def _inside(inner, outer, tol=1.0) -> bool:
    return (outer[0] - tol <= inner[0] and inner[2] <= outer[2] + tol and outer[1] - tol <= inner[1]
            and inner[3] <= outer[3] + tol)


def _layout_faults(plot) -> list[str]:
    """Empty or missing axis titles, boxes outside the drawing, and overlaps of titles, legend, colour
    bar and tick labels, in words."""
    faults = []
    named = []                                 # (what, box) of every box that must stand alone
    for ax in plot["axes"]:
        if not ax["text"] or ax["box"] is None:
            faults.append(f"{ax['axis']}: no axis title rendered")
        elif "[" not in ax["text"] and "index" not in ax["text"]:
            faults.append(f"{ax['axis']}: title {ax['text']!r} has no unit")
        else:
            named.append((f"{ax['axis']} title {ax['text']!r}", ax["box"]))
    if plot["title"] is not None:
        named.append((f"title {plot['title']['text']!r}", plot["title"]["box"]))
    named += [("legend", b) for b in plot["legend"]] + [("colour bar", b) for b in plot["colorbar"]]
    for what, box in named:
        if not _inside(box, plot["svg"]) or not _inside(box, plot["div"]):
            faults.append(f"{what} clipped: {box} outside {plot['svg']}")
    for i, (a, box_a) in enumerate(named):
        for b, box_b in named[i + 1:]:
            if _overlap(box_a, box_b):
                faults.append(f"{a} overlaps {b}")
        if "title" in a:
            for tick in plot["ticks"]:
                if _overlap(box_a, tick["box"]):
                    faults.append(f"{a} overlaps the tick label {tick['text']!r}")
    return [f"{plot['id']}: {f}" for f in faults]


def test_every_view_every_axis_titled_and_no_text_box_overlaps(page):
    """Issue 33.5: on each view (analyse with a force map, simulate, fit, sweep), every rendered
    axis of every drawn plot has a title with its unit, and no title, legend, colour bar or tick
    label overlaps another or is clipped (bounding boxes laid out by Chromium). The analyse view
    is drawn again with the 2x2 map (its heat map, table histogram, force, raw, drift and
    compliance plots); the fit view with the small fit's data and the two-parameter profiles."""
    page.click("button[data-view=analyse]")
    data = Path(__file__).resolve().parents[1] / "data" / "afmforce-map_jpk-map2x2.h5"
    page.set_input_files("#an-files", str(data))
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-plot-map').data && document.getElementById('an-batch-hist').data"
                           " && document.getElementById('an-plot-force').data", timeout=60_000)
    page.wait_for_timeout(300)
    # the fit view: the small fit's result (data and model per curve, from the server), with the
    # profiles of two parameters as the library writes them (FitResult.to_dict)
    page.evaluate("""async () => {
        const jobs = await (await fetch('api/jobs')).json();
        const job = jobs.find(j => j.kind === 'fit' && j.state === 'done');
        const r = (await (await fetch('api/jobs/' + job.id)).json()).result;
        r.profiles = {hamaker: {value: [4.8e-19, 5e-19, 5.2e-19], delta_chi2: [4, 0, 4]},
                      xi: {value: [0.0048, 0.005, 0.0052], delta_chi2: [4, 0, 4]}};
        drawFit(r); }""")
    plots, faults = {}, []
    for view in ("analyse", "simulate", "fit", "sweep"):
        page.click(f"button[data-view={view}]")
        page.wait_for_timeout(400)                 # the resize after a tab switch
        for plot in page.evaluate(_BOXES, view):
            plots[plot["id"]] = plot
            faults += _layout_faults(plot)
    must = {"an-plot-force", "an-plot-raw", "an-plot-map", "an-batch-hist", "sim-plot-defl", "sim-plot-force",
            "fit-plot", "fit-profiles", "sw-plot"}
    assert not faults, "\n".join(faults)
    assert must <= set(plots), sorted(plots)
    assert sum(len(p["axes"]) for p in plots.values()) >= 2 * len(must)
    summary = page.evaluate("[...document.querySelectorAll('#an-summary td')].map(t => t.textContent)")
    repeats = [t for t in summary if ": " in t and t.split(": ", 1)[0] == t.split(": ", 1)[1]]
    assert not repeats, repeats                    # no "not assessed: not assessed"


def test_another_curve_of_a_map_gets_its_arrays_when_shown(page):
    """Issue 33.7: a map's re-run sends the arrays of the curve drawn only; another curve chosen
    gets its own (asked for then) and is drawn, the same numbers as the whole map's analysis."""
    page.click("button[data-view=analyse]")
    names = page.eval_on_selector_all("#an-curve option", "os => os.map(o => o.value)")
    sent = page.evaluate("AN.payload.arrays_for")
    assert len(names) == 4 and len(sent) == 1
    other = next(n for n in names if n not in sent)
    assert page.evaluate(f"AN.payload.results[{json.dumps(other)}].separation === undefined")
    page.select_option("#an-curve", other)
    page.wait_for_function(f"document.querySelector('#an-plot-force .g-gtitle') && "
                           f"document.querySelector('#an-plot-force .g-gtitle').textContent.includes({json.dumps(other)})",
                           timeout=30_000)
    drawn = page.evaluate(f"AN.payload.results[{json.dumps(other)}]")
    fid = page.evaluate("AN.files[0].id")
    api = page.evaluate(f"""() => {{ const fd = new FormData(); fd.append('file_id', '{fid}'); fd.append('arrays', 'true');
        fd.append('max_points', String(AN.payload.max_points));
        return fetch('api/analyze', {{method: 'POST', body: fd}}).then(r => r.json()); }}""")["results"][other]
    assert len(drawn["separation"]) > 10 and drawn["force"] == api["force"]
    assert drawn["adhesion_force"] == api["adhesion_force"]
