"""In headless Chromium (as test_web_e2e.py): the modulus fit's range dragged on the plot and re-run
(issue 33.4), a click on a force-map pixel opening its curve (issue 35.6), the time axis of a file
without a time base, per-channel Asylum waves uploaded together (issue 33)."""

from __future__ import annotations

import io
import json
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

# the `page` fixture (headless Chromium on a live server): tests/web/conftest.py

DATA = Path(__file__).resolve().parents[1] / "data"


def _cli(path, *options) -> dict:
    """``afmforce analyze PATH --json --option ...``: the library through the CLI's parser."""
    from afmforce.cli.main import main

    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(path), "--json", *sum((["--option", o] for o in options), [])]) == 0
    return next(iter(json.loads(out.getvalue())["results"].values()))


def _closed_form_modulus(fit: dict) -> float:
    """E of the Hertz paraboloid F = b + 4/3 E/(1-nu^2) sqrt(R) delta^(3/2) by linear least squares over
    the fitted samples at the fitted contact point (E and b enter linearly: a closed form)."""
    d = np.asarray(fit["indentation"])
    F = np.asarray(fit["fit_force"]) + np.asarray(fit["residuals"])           # the data fitted
    phi = 4 / 3 / (1 - fit["poisson"] ** 2) * np.sqrt(fit["tip_radius"]) * np.clip(d, 0, None) ** 1.5
    scale = phi.max()
    E, _ = np.linalg.lstsq(np.column_stack([phi / scale, np.ones_like(phi)]), F, rcond=None)[0]
    return float(E / scale)


def _page_fit(page) -> dict:
    return page.evaluate("AN.payload.results[document.getElementById('an-curve').value].details.indentation")


def _handle_drag(page, to_nm: float, shape: int = 0) -> None:
    """A real mouse drag of a handle (the plot's shape ``shape``: 0 the fit limit, 1 the contact point) to
    ``to_nm`` on the x axis."""
    page.locator("#an-plot-indentation").scroll_into_view_if_needed()
    at = page.evaluate("""(k) => { const gd = document.getElementById('an-plot-indentation'), L = gd._fullLayout;
        const r = gd.getBoundingClientRect();
        return {x0: L.shapes[k].x0, left: r.left + L.xaxis._offset, top: r.top + L.yaxis._offset, h: L.yaxis._length,
                lo: L.xaxis.range[0], hi: L.xaxis.range[1], w: L.xaxis._length}; }""", shape)
    px = lambda nm: at["left"] + (nm - at["lo"]) / (at["hi"] - at["lo"]) * at["w"]   # noqa: E731 (a linear axis)
    y = at["top"] + at["h"] * 0.5
    page.mouse.move(px(at["x0"]), y)
    page.mouse.down()
    page.mouse.move(px(at["x0"]) + (px(to_nm) - px(at["x0"])) / 2, y, steps=5)
    page.mouse.move(px(to_nm), y, steps=5)
    page.mouse.up()


def _settled(page, drops: int) -> None:
    page.wait_for_function(f"(window.FIT_RANGE_DROPS || 0) >= {drops}", timeout=10_000)
    page.wait_for_function("!AN.busy && !AN.next && document.getElementById('status').textContent === ''",
                           timeout=120_000)


def test_drag_the_fit_range_and_the_modulus_is_refitted(page):  # noqa: F811
    """The cell of the shipped JPK curve, a 5 µm bead: the fit limit dragged to half its depth types
    indentation.max_indentation in its field and re-runs; the E that comes back is the library's
    with the same option (``afmforce analyze --option``), the closed-form least-squares E of the
    samples it fitted, those within the dragged limit of the whole run's contact point, and not the
    whole run's E. Dragged past
    the whole run's end, the option is cleared and the whole run's E comes back."""
    from afmforce.datasets import path

    page.select_option("#an-example", "jpk-cell")
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-curve').value.includes('jpk-cell')", timeout=60_000)
    box = page.locator("[data-option='indentation.tip_radius'] input.val")
    box.fill("5000")
    box.dispatch_event("change")
    page.wait_for_function("document.getElementById('an-plot-indentation').data", timeout=60_000)
    _settled(page, 0)
    whole = _page_fit(page)
    cli_whole = _cli(path("jpk-cell"), "indentation.tip_radius=5um")["details"]["indentation"]
    assert whole["youngs_modulus"] == pytest.approx(cli_whole["youngs_modulus"], rel=1e-12)
    deepest = whole["max_indentation"] * 1e9
    assert page.evaluate("document.getElementById('an-plot-indentation')._fullLayout.shapes[0].x0") == pytest.approx(deepest)

    _handle_drag(page, deepest / 2)
    _settled(page, 1)
    typed = page.locator("[data-option='indentation.max_indentation'] input.val").input_value()
    limit = float(typed)                                                  # nm, the field's unit
    span = page.evaluate("(() => { const r = document.getElementById('an-plot-indentation')._fullLayout.xaxis.range; return r[1] - r[0]; })()")
    assert limit == pytest.approx(deepest / 2, abs=0.03 * span)          # where the mouse let go
    got = _page_fit(page)
    cli = _cli(path("jpk-cell"), "indentation.tip_radius=5um", f"indentation.max_indentation={typed}nm")
    fit = cli["details"]["indentation"]
    assert got["youngs_modulus"] == pytest.approx(fit["youngs_modulus"], rel=1e-12)
    assert fit["youngs_modulus"] == pytest.approx(_closed_form_modulus(fit), rel=1e-6)
    # the range: the samples within the limit of the whole run's contact point (a fixed set), every one
    u_whole = cli_whole["contact_depth"] + np.asarray(cli_whole["indentation"])
    u_fit = fit["contact_depth"] + np.asarray(fit["indentation"])
    assert fit["n_points"] == int(np.sum(u_whole <= cli_whole["contact_depth"] + limit * 1e-9)) < u_whole.size
    assert u_fit.max() <= cli_whole["contact_depth"] + limit * 1e-9 * (1 + 1e-12)
    assert abs(got["youngs_modulus"] / whole["youngs_modulus"] - 1) > 1e-3
    title = page.evaluate("document.querySelector('#an-plot-indentation .g-gtitle text').textContent")
    e = got["youngs_modulus"]
    shown = f"{e / 1e3:.4g} kPa" if e >= 1e3 else f"{e:.4g} Pa"
    assert shown in title, title
    # the handle sits at the new limit, with room to drag it back to the whole run
    layout = page.evaluate("(() => { const L = document.getElementById('an-plot-indentation')._fullLayout; return {x: L.shapes[0].x0, hi: L.xaxis.range[1]}; })()")
    assert layout["x"] == pytest.approx(limit) and layout["hi"] > deepest

    _handle_drag(page, layout["hi"] - 0.01 * span)
    _settled(page, 2)
    assert page.locator("[data-option='indentation.max_indentation'] input.val").input_value() == ""
    assert _page_fit(page)["youngs_modulus"] == pytest.approx(whole["youngs_modulus"], rel=1e-12)
    box.fill("")
    box.dispatch_event("change")
    page.wait_for_function("document.getElementById('an-plot-indentation').classList.contains('hidden')", timeout=60_000)
    page.select_option("#an-example", "")
    assert not page.errors


def test_drag_the_contact_point_and_it_is_fixed_there(page):  # noqa: F811
    """The shipped JPK cell, a 5 µm bead: the contact-point line (δ = 0) dragged 25 nm to the left types
    indentation.contact_point (the tip depth there) in its field and re-runs; the fit that comes back
    is the library's with the same option, its contact point is the typed one (standard error 0), and
    E is the closed-form least squares of the samples at that contact point; cleared, the fitted
    contact point and the whole run's E come back."""
    from afmforce.datasets import path

    page.select_option("#an-example", "jpk-cell")
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-curve').value.includes('jpk-cell')", timeout=60_000)
    box = page.locator("[data-option='indentation.tip_radius'] input.val")
    box.fill("5000")
    box.dispatch_event("change")
    page.wait_for_function("document.getElementById('an-plot-indentation').data", timeout=60_000)
    drops = page.evaluate("window.FIT_RANGE_DROPS || 0")
    _settled(page, drops)
    whole = _page_fit(page)
    assert whole["contact_point_se"] > 0
    _handle_drag(page, -25.0, shape=1)
    _settled(page, drops + 1)
    field = page.locator("[data-option='indentation.contact_point'] input.val")
    typed = field.input_value()
    got = _page_fit(page)
    cli = _cli(path("jpk-cell"), "indentation.tip_radius=5um", f"indentation.contact_point={typed}nm")
    fit = cli["details"]["indentation"]
    span = page.evaluate("(() => { const r = document.getElementById('an-plot-indentation')._fullLayout.xaxis.range; return r[1] - r[0]; })()")
    assert float(typed) * 1e-9 - whole["contact_depth"] == pytest.approx(-25e-9, abs=0.03 * span * 1e-9)
    assert got["contact_depth"] == pytest.approx(float(typed) * 1e-9, rel=1e-12) == fit["contact_depth"]
    assert got["contact_point_se"] == 0.0 and fit["contact_point_se"] == 0.0
    assert got["youngs_modulus"] == pytest.approx(fit["youngs_modulus"], rel=1e-12)
    assert fit["youngs_modulus"] == pytest.approx(_closed_form_modulus(fit), rel=1e-9)
    assert abs(got["youngs_modulus"] / whole["youngs_modulus"] - 1) > 1e-3
    field.evaluate("(e) => { e.value = ''; e.dispatchEvent(new Event('change')); }")   # its section may be folded
    page.wait_for_function("document.getElementById('status').textContent === '' && !AN.busy && !AN.next", timeout=120_000)
    page.wait_for_function(f"AN.payload.results[document.getElementById('an-curve').value].details.indentation.contact_point_se > 0",
                           timeout=120_000)
    assert _page_fit(page)["youngs_modulus"] == pytest.approx(whole["youngs_modulus"], rel=1e-12)
    box.fill("")
    box.dispatch_event("change")
    page.wait_for_function("document.getElementById('an-plot-indentation').classList.contains('hidden')", timeout=60_000)
    page.select_option("#an-example", "")
    assert not page.errors


def test_a_click_on_a_map_pixel_opens_its_curve(page):  # noqa: F811
    """Issue 35.6: the 2x2 JPK map; a click on each pixel (a real mouse click where the pixel is
    drawn) opens that curve: the curve selector, the force plot's title and its data are the
    curve's, as the API gives it."""
    page.set_input_files("#an-files", str(DATA / "afmforce-map_jpk-map2x2.h5"))
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-plot-map').data", timeout=60_000)
    _settled(page, 0)
    page.locator("#an-plot-map").scroll_into_view_if_needed()
    pixels = page.evaluate("""() => { const gd = document.getElementById('an-plot-map'), L = gd._fullLayout, t = gd.data[0];
        const r = gd.getBoundingClientRect(), out = [];
        t.customdata.forEach((row, j) => row.forEach((name, i) => { if (name) out.push({name,
            x: r.left + L.xaxis._offset + L.xaxis.l2p(t.x ? t.x[i] : i), y: r.top + L.yaxis._offset + L.yaxis.l2p(t.y ? t.y[j] : j)}); }));
        return out; }""")
    assert len(pixels) == 4
    seen = set()
    for px in sorted(pixels, key=lambda p: p["name"], reverse=True):    # the last curve first: not the one shown
        page.mouse.click(px["x"], px["y"])
        page.wait_for_function("(n) => document.getElementById('an-curve').value === n", arg=px["name"], timeout=10_000)
        # the curve's arrays are fetched when it is first shown (a map sends the drawn curve's only)
        page.wait_for_function("(n) => { const t = document.querySelector('#an-plot-force .g-gtitle text'); "
                               "return t && t.textContent.endsWith(n); }", arg=px["name"], timeout=30_000)
        title = page.evaluate("document.querySelector('#an-plot-force .g-gtitle text').textContent")
        assert title.endswith(px["name"]), title
        drawn = page.evaluate("(() => { const d = document.getElementById('an-plot-force').data.find(t => t.name === 'approach'); return d.y.filter(v => v !== null); })()")
        res = page.evaluate("(n) => AN.payload.results[n]", px["name"])
        want = [f * 1e9 for f, s in zip(res["force"], res["segment"]) if s == 0 and f is not None]
        assert drawn == pytest.approx(want)
        seen.add(px["name"])
    assert len(seen) == 4


def test_a_file_without_a_time_base_is_drawn_against_the_sample_index(page):  # noqa: F811
    """AFM Workshop's CSV stores no time and no sample rate: the drift plot's x axis is the sample
    index, titled so (never "time t [s]"); a timed file keeps its time axis."""
    page.set_input_files("#an-files", str(DATA / "afm-workshop_single.csv"))
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-curve').value.includes('afm-workshop')", timeout=60_000)
    _settled(page, 0)
    xt = lambda: page.evaluate("document.querySelector('#an-plot-time .g-xtitle text').textContent")  # noqa: E731
    assert xt().startswith("sample index n [-]"), xt()
    x = page.evaluate("document.getElementById('an-plot-time').data[0].x.filter(v => v !== null)")
    # sample indices (thinned to the screen: each pixel column's extremes), from the first sample on
    assert x[0] == 0 and all(float(v).is_integer() for v in x) and all(b > a for a, b in zip(x, x[1:]))
    page.select_option("#an-example", "asylum-air")
    page.set_input_files("#an-files", [])
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-curve').value.includes('asylum')", timeout=60_000)
    _settled(page, 0)
    assert xt() == "time t [s]"
    page.select_option("#an-example", "")


def test_per_channel_asylum_waves_uploaded_together_in_the_page(page, tmp_path):  # noqa: F811
    """The two waves of one Asylum curve chosen together in the file box: both read (no error), each
    the pair's curve (the JSON of the API test, test_web_uploads.py)."""
    from test_web_uploads import PREFIX, split_channels

    waves = split_channels(tmp_path)
    page.set_input_files("#an-files", [str(p) for p in waves.values()])
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-curve').options.length === 2", timeout=60_000)
    _settled(page, 0)
    assert page.inner_text("#an-error") == ""
    names = page.eval_on_selector_all("#an-curve option", "os => os.map(o => o.value)")
    assert sorted(names) == sorted([f"{PREFIX}Defl.ibw", f"{PREFIX}ZSnsr.ibw"])
    a, b = (page.evaluate("(n) => AN.payload.results[n]", n) for n in names)
    assert a["contact_kind"] == b["contact_kind"] and a["adhesion_force"] == b["adhesion_force"]


def test_the_fit_view_takes_the_calibration(page, tmp_path):  # noqa: F811
    """The fit view has the analyse view's calibration: a calibration file (``afmforce calibrate
    --out``) fills k and f0 (marked "from calib.json"), a typed InvOLS joins them, and the fit of
    the uploaded curves is sent them as its metadata, read by the CLI's parser (``afmforce fit
    --meta``) to the file's exact values; the job starts (and is cancelled here)."""
    from afmforce.datasets import path
    from afmforce.io._meta import parse_meta_args
    from test_web_analyse_view import _calibrate

    cal = _calibrate(tmp_path)
    written = json.loads(cal.read_text())
    page.click("button[data-view=fit]")
    page.set_input_files("#fit-calfile", str(cal))
    page.wait_for_function("""() => { const t = document.querySelector("[data-fit-meta='spring_constant'] .from");
        return t && t.textContent === 'from calib.json'; }""", timeout=30_000)
    assert page.inner_text("[data-fit-meta='resonance_frequency'] .from") == "from calib.json"
    page.locator("[data-fit-meta='sensitivity'] input.val").fill("50")              # nm/V, the field's unit
    page.set_input_files("#fit-files", [str(path("asylum-air")), str(DATA / "asylum-mfp3d_SiN-tip_air.ibw")])
    page.uncheck("#fit-profile")
    page.uncheck("#fit-compare")
    with page.expect_response(lambda r: r.url.endswith("/api/fit"), timeout=120_000) as got:
        page.click("#fit-run")
    body = json.loads(got.value.request.post_data)
    assert len(body["file_ids"]) == 2
    meta = parse_meta_args(body["meta"])
    assert meta == {"spring_constant": written["spring_constant"], "sensitivity": pytest.approx(50e-9, rel=1e-12),
                    "resonance_frequency": 30e3}
    assert got.value.status == 202
    page.click("#fit-cancel")
    page.wait_for_function("['cancelled', 'done', 'failed'].some(s => document.getElementById('fit-state').textContent.startsWith(s))",
                           timeout=60_000)
    page.click("button[data-view=analyse]")
    assert not page.errors


def test_drag_the_vdw_fit_window(page):  # noqa: F811
    """A hard contact (the shipped MFP-3D curve): the van der Waals fit's window, vdw.max_separation
    (30 nm by default), dragged on force vs separation; A R that comes back is the library's with
    the dragged value, the fit drawn within it."""
    from afmforce.datasets import path

    page.select_option("#an-example", "asylum-air")
    page.set_input_files("#an-files", [])
    page.click("#an-run")
    page.wait_for_function("document.getElementById('an-curve').value.includes('asylum')", timeout=60_000)
    _settled(page, 0)
    drops = page.evaluate("window.FIT_RANGE_DROPS || 0")
    page.locator("#an-plot-force").scroll_into_view_if_needed()
    at = page.evaluate("""() => { const gd = document.getElementById('an-plot-force'), L = gd._fullLayout;
        const r = gd.getBoundingClientRect();
        return {x0: L.shapes[0].x0, left: r.left + L.xaxis._offset, top: r.top + L.yaxis._offset, h: L.yaxis._length,
                lo: L.xaxis.range[0], hi: L.xaxis.range[1], w: L.xaxis._length}; }""")
    assert at["x0"] == pytest.approx(30.0)                                 # the option's default, nm
    px = at["left"] + (at["x0"] - at["lo"]) / (at["hi"] - at["lo"]) * at["w"]
    y = at["top"] + at["h"] * 0.3
    page.mouse.move(px, y)
    page.mouse.down()
    page.mouse.move(px + 20, y, steps=5)
    page.mouse.move(px + 40, y, steps=5)
    page.mouse.up()
    _settled(page, drops + 1)
    typed = page.locator("[data-option='vdw.max_separation'] input.val").input_value()
    want = at["x0"] + 40 / at["w"] * (at["hi"] - at["lo"])
    assert float(typed) == pytest.approx(want, rel=0.05)
    cli = _cli(path("asylum-air"), f"vdw.max_separation={typed}nm")
    got = page.evaluate("AN.payload.results[document.getElementById('an-curve').value]")
    assert got["hamaker_radius"] == pytest.approx(cli["hamaker_radius"], rel=1e-12)
    assert got["details"]["vdw"]["separation_max"] <= float(typed) * 1e-9 * (1 + 1e-12)
    default = _cli(path("asylum-air"))
    assert got["hamaker_radius"] != default["hamaker_radius"]
    page.evaluate("""() => { const i = document.querySelector("[data-option='vdw.max_separation'] input.val");
        i.value = ''; i.dispatchEvent(new Event('change')); }""")                # back to the default
    _settled(page, 0)
    assert page.evaluate("AN.payload.results[document.getElementById('an-curve').value].hamaker_radius") == default["hamaker_radius"]
    page.select_option("#an-example", "")
    assert not page.errors
