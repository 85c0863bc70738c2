"""The inclined cantilever's geometry reaches the web as it reaches the command line, from one declaration.

Faces sweep 2026-11-29: ``afmforce analyze --theta0 --L0 --L1 --L2`` existed and ``POST /api/analyze`` took
``probe=theta0=...``, but the analyse view had no control for them (a tilted lever's k was never corrected on
the page). Now every field of :class:`afmforce.analysis.options.ProbeCalibration` is a control of the view
(``GET /api/schema`` ``calibration``, ``via: probe``) with the range and unit of
:data:`afmforce._fields.QUANTITIES` (tests/cli/test_faces_walk_declarations.py walks the flags).

Reference: the command line's answer on the same real file (``afmforce analyze FILE --json --theta0 -12deg``),
and eq 14 (``k = k0 / cos^2 theta0``) for the spring constant the analysis used."""

from __future__ import annotations

import functools
import io
import json
import math
from contextlib import redirect_stdout

import pytest

from afmforce._fields import QUANTITIES
from afmforce.cli.main import main
from realdata import real_file

#: A real Asylum MFP-3D curve in air (hard contact: k, adhesion, the compliance line).
REAL = "asylum-mfp3d_SiN-tip_air.ibw"
GEOMETRY = ("theta0", "L0", "L1", "L2")


@functools.lru_cache(maxsize=None)       # one run per flag set: the API and the page compare with the same
def _cli(path, *flags) -> dict:
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(path), "--json", "--serial", *flags]) == 0
    (res,) = json.loads(out.getvalue())["results"].values()
    return res


def _same(web: dict, cli: dict) -> None:
    """Every number of the web's result equals the command line's to 1e-12 (words exactly)."""
    assert set(web) >= set(cli) - {"source"}
    for key, want in cli.items():
        if key == "source":
            continue
        got = web[key]
        if isinstance(want, float) and isinstance(got, float):
            assert got == pytest.approx(want, rel=1e-12, abs=0.0), key
        elif not isinstance(want, (list, dict)):
            assert got == want, key


@pytest.fixture(scope="module")
def real():
    return real_file(REAL)


def test_the_schema_lists_the_geometry_with_the_declared_ranges(client):
    fields = {f["name"]: f for f in client.get("/api/schema").json()["calibration"] if f["via"] == "probe"}
    for name in GEOMETRY:
        spec = QUANTITIES[name]
        assert fields[name]["range"] == spec.range_text() and fields[name]["unit"] == spec.unit
        assert (fields[name]["lo"], fields[name]["hi"]) == (spec.lo, spec.hi)
    assert fields["theta0"]["shown"] == "deg" and fields["theta0"]["factor"] == pytest.approx(math.pi / 180)


def test_the_web_answer_with_a_tilt_equals_the_clis(client, real):
    plain = _cli(real)
    tilted = _cli(real, "--theta0", "-12deg")
    k0 = plain["spring_constant"]                                  # the file's own k, taken as the intrinsic k0
    assert tilted["spring_constant"] == pytest.approx(k0 / math.cos(math.radians(12)) ** 2, rel=1e-12)   # eq 14
    r = client.post("/api/analyze", files={"file": (real.name, real.read_bytes())}, data={"probe": "theta0=-12deg"})
    assert r.status_code == 200, r.text
    (web,) = r.json()["results"].values()
    _same(web, tilted)
    geometry = ("--theta0", "-12deg", "--L0", "200um", "--L1", "10um", "--L2", "5um")     # eq 13
    beam = _cli(real, *geometry)
    assert beam["spring_constant"] != pytest.approx(tilted["spring_constant"], rel=1e-6)
    r = client.post("/api/analyze", files={"file": (real.name, real.read_bytes())},
                    data={"probe": ["theta0=-12deg", "L0=200um", "L1=10um", "L2=5um"]})
    assert r.status_code == 200, r.text
    (web,) = r.json()["results"].values()
    _same(web, beam)


@pytest.mark.parametrize("text,name", [("theta0=95deg", "theta0"), ("L0=5mm", "L0"), ("L1=1um", None)])
def test_out_of_range_geometry_is_refused_naming_the_field(client, real, text, name):
    data = {"probe": [text] if name else ["L0=1um", text]}       # L1 1 um is not shorter than L0 1 um
    r = client.post("/api/analyze", files={"file": (real.name, real.read_bytes())}, data=data)
    assert r.status_code == 422, r.text
    message = r.json()["error"]["message"]
    assert (QUANTITIES[name].range_text() in message) if name else ("not shorter than the flexible beam" in message)


# ---- the page: the controls are listed and their values sent --------------------------------------------
# the `page` fixture: tests/web/conftest.py (headless Chromium on the live server)


def test_the_page_sends_theta0_and_shows_the_clis_answer(page, real):
    for name in GEOMETRY:
        spec = QUANTITIES[name]
        assert spec.range_text() in page.inner_text(f"[data-probe='{name}'] .range")
    assert page.inner_text("[data-probe='theta0'] .range").startswith("[deg]")
    page.set_input_files("#an-files", str(real))
    page.click("#an-run")
    page.wait_for_function("typeof AN !== 'undefined' && AN.payload && Object.keys(AN.payload.results).length",
                           timeout=120_000)
    with page.expect_request(lambda r: r.url.endswith("/api/analyze")) as sent:
        page.fill("[data-probe='theta0'] input.val", "-12")
        page.dispatch_event("[data-probe='theta0'] input.val", "change")
    body = sent.value.post_data or ""
    assert 'name="probe"\r\n\r\ntheta0=-12deg' in body, body[:600]
    want = _cli(real, "--theta0", "-12deg")
    page.wait_for_function(f"() => {{ const r = Object.values(AN.payload.results)[0]; "
                           f"return r && Math.abs(r.spring_constant - {want['spring_constant']!r}) < 1e-9; }}",
                           timeout=120_000)
    web = page.evaluate("Object.values(AN.payload.results)[0]")
    _same(web, want)
    assert "used" in page.inner_text("[data-probe='spring_constant'] .used")
    assert not page.errors
