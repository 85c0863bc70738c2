"""The analyse view a lab works in (issue 33.4): calibration and probe fields, the model dropdown."""

from __future__ import annotations

import io
import json
from contextlib import redirect_stdout

import pytest

fastapi = pytest.importorskip("fastapi")


def test_calibration_fields_come_from_the_declarations(client):
    """k, InvOLS (nm/V), resonance frequency, radius from ProbeCalibration; the indentation model (a
    choice of the contact registry), tip radius, half angle and Poisson ratio from the step's options."""
    import dataclasses

    from afmforce.analysis.options import OPTIONS, ProbeCalibration
    from afmforce.contact import INDENTATION_MODELS

    cal = {f["key"]: f for f in client.get("/api/schema").json()["calibration"]}
    assert list(cal) == ["spring_constant", "sensitivity", "resonance_frequency", "radius", "theta0", "L0", "L1",
                         "L2", "indentation.model",
                         "indentation.tip_radius", "indentation.half_angle", "indentation.poisson"]
    probe = {f.name: f.metadata["spec"] for f in dataclasses.fields(ProbeCalibration)}
    for key in probe:       # every field of the probe record (the API's probe=), the lever's geometry too
        assert cal[key]["via"] == "probe" and cal[key]["range"] == probe[key].range_text()
    assert cal["sensitivity"]["shown"] == "nm/V" and cal["sensitivity"]["factor"] == pytest.approx(1e-9)
    model = cal["indentation.model"]
    assert model["kind"] == "choice" and model["choices"] == list(INDENTATION_MODELS)
    assert model["default"] == OPTIONS["indentation"]().model
    assert model["labels"]["hertz_cone"] == INDENTATION_MODELS["hertz_cone"].name
    assert model["models"]["hertz_cone"]["geometry"] == ["half_angle"]
    indentation = {f.name: f.metadata["spec"] for f in dataclasses.fields(OPTIONS["indentation"])
                   if f.metadata.get("spec") is not None}
    assert cal["indentation.poisson"]["range"] == indentation["poisson"].range_text()
    assert cal["indentation.half_angle"]["shown"] == "deg"


def test_calibration_given_in_the_page_is_what_the_cli_computes(client, tmp_path):
    """The page's probe fields give the same result as ``afmforce analyze --spring-constant ...``."""
    from afmforce.cli.main import main
    from afmforce.datasets import path

    src = path("asylum-air")
    local = tmp_path / src.name
    local.write_bytes(src.read_bytes())
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(local), "--json", "--spring-constant", "0.5N/m", "--sensitivity", "50nm/V",
                     "--resonance-frequency", "30kHz", "--option", "indentation.poisson=0.3"]) == 0
    cli = json.loads(out.getvalue())["results"][src.name]
    r = client.post("/api/analyze", files={"file": (src.name, src.read_bytes())},
                    data={"probe": ["spring_constant=0.5N/m", "sensitivity=50nm/V", "resonance_frequency=30kHz"],
                          "option": ["indentation.poisson=0.3"]})
    api = r.json()["results"][src.name]
    assert api["spring_constant"] == 0.5 and api["sensitivity_used"] == pytest.approx(50e-9, rel=1e-12)
    assert api["resonance_frequency"] == 30e3
    api.pop("source"), cli.pop("source")
    assert api == cli
    # a hard contact: the indentation step cannot run, and the result says why (shown in the page)
    assert "hard contact" in api["not_applicable"]["indentation"]
    bad = client.post("/api/analyze", data={"example": "asylum-air", "option": "indentation.model=nope"})
    assert bad.status_code == 422 and bad.json()["error"]["field"] == "option.indentation.model"


def test_the_modulus_fit_samples_obey_the_response_cap(client):
    """With ``arrays`` the modulus fit's samples are thinned like the curve's (the response's size
    cap); the fitted E is the one of the full fit."""
    full = client.post("/api/analyze", data={"example": "jpk-cell", "option": "indentation.tip_radius=5um"}).json()
    thin = client.post("/api/analyze", data={"example": "jpk-cell", "option": "indentation.tip_radius=5um",
                                             "arrays": "true", "max_points": "500"}).json()
    a, b = (next(iter(p["results"].values()))["details"]["indentation"] for p in (full, thin))
    assert len(a["indentation"]) > 500 >= len(b["indentation"]) == len(b["fit_force"]) == len(b["residuals"])
    assert b["youngs_modulus"] == a["youngs_modulus"] and b["indentation"][0] == a["indentation"][0]
    assert b["indentation"][-1] == a["indentation"][-1]


def _calibrate(tmp_path):
    """A probe calibration file as users make it: ``afmforce calibrate --out calib.json sader ...``."""
    from afmforce.cli.main import main

    out = tmp_path / "calib.json"
    with redirect_stdout(io.StringIO()):
        assert main(["calibrate", "--out", str(out), "sader", "--length", "200um", "--width", "30um",
                     "--frequency", "30kHz", "--quality-factor", "2"]) == 0
    return out


def test_calibration_file_is_what_the_cli_computes(client, tmp_path):
    """An uploaded ``calib.json`` gives the JSON of ``afmforce analyze FILE --probe-calibration calib.json
    --json``; a typed value wins over the file's, as on the command line."""
    from afmforce.calibration.record import read_calibration
    from afmforce.cli.main import main
    from afmforce.datasets import path

    cal = _calibrate(tmp_path)
    written = json.loads(cal.read_text())
    src = path("asylum-air")
    local = tmp_path / src.name
    local.write_bytes(src.read_bytes())
    # what the page fills its fields with: the file's values, checked, SI
    refused = client.post("/api/calibration", files={"file": ("calib.json", cal.read_bytes())},
                          headers={"Origin": "null"})          # a sandboxed frame reads nothing either
    assert refused.status_code == 403
    r = client.post("/api/calibration", files={"file": ("calib.json", cal.read_bytes())})
    assert r.status_code == 200 and r.json()["source"] == "calib.json"
    assert r.json()["values"] == {"spring_constant": written["spring_constant"], "resonance_frequency": 30e3}
    assert r.json()["values"] == {k: v for k, v in read_calibration(cal).items() if k != "quality_factor"}
    for typed in ([], ["--sensitivity", "50nm/V"], ["--spring-constant", "0.5N/m"]):
        out = io.StringIO()
        with redirect_stdout(out):
            assert main(["analyze", str(local), "--json", "--probe-calibration", str(cal), *typed]) == 0
        cli = json.loads(out.getvalue())["results"][src.name]
        probe = [f"{typed[0][2:].replace('-', '_')}={typed[1]}"] if typed else []
        api = client.post("/api/analyze", files={"file": (src.name, src.read_bytes()),
                                                 "calibration": ("calib.json", cal.read_bytes())},
                          data={"probe": probe}).json()["results"][src.name]
        assert api["spring_constant"] == (0.5 if "0.5N/m" in typed else written["spring_constant"])
        assert api["resonance_frequency"] == 30e3
        api.pop("source"), cli.pop("source")
        assert api == cli


@pytest.mark.parametrize("body, field, words", [
    (b"not json", "calibration", "not a readable JSON"),
    (b'{"spring_constant": 0.1}', "calibration", "not an afmforce calibration file"),
    (b"[1, 2]", "calibration", "not an afmforce calibration file"),
    (b"\xff\xfe\x00binary", "calibration", "not UTF-8"),
    (b" " * 70_000, "calibration", "bytes is not a calibration file"),
    (b'{"afmforce_calibration": 1, "spring_constant": 5e3}', "calibration.spring_constant", "spring_constant"),
    (b'{"afmforce_calibration": 1, "sensitivity": -1e-8}', "calibration.sensitivity", "sensitivity"),
    (b'{"afmforce_calibration": 1, "spring_constant": NaN}', "calibration", "not a finite number"),
    (b'{"afmforce_calibration": 1, "resonance_frequency": 1e999}', "calibration", "not a finite number"),
    (b'{"afmforce_calibration": 1, "spring_constant": ' + b"9" * 400 + b"}", "calibration", "not a finite"),
])
def test_a_bad_or_foreign_calibration_file_is_refused(client, body, field, words):
    """422 naming the field (never 500), in the page's reader and in the analysis alike; nothing runs."""
    for url, files, data in (("/api/calibration", {"file": ("calib.json", body)}, {}),
                             ("/api/analyze", {"calibration": ("calib.json", body)}, {"example": "asylum-air"})):
        r = client.post(url, files=files, data=data)
        assert r.status_code == 422, (url, r.text)
        err = r.json()["error"]
        assert err["field"] == field and words in err["message"], err


def test_web_analysis_calibrates_as_the_cli_and_the_fit(client, tmp_path):
    """One calibration rule for every face: the page's analysis of the shipped Asylum curve uses the wave
    note's InvOLS and k (read with igor2), as `afmforce analyze` and the fit's preprocessing do; the option
    calibration.source=fit gives the CLI's `--calibration fit` numbers (the refit, k rescaled)."""
    import numpy as np

    from afmforce.cli.main import main
    from afmforce.datasets import path
    from afmforce.fit.preprocess import analysis_inputs
    from afmforce.io import load
    from realdata import wave_note

    src = path("asylum-air")
    note = wave_note(src)
    local = tmp_path / src.name
    local.write_bytes(src.read_bytes())
    curve = load(local)[0]
    fit_in = analysis_inputs(curve, src.name, np.flatnonzero(np.asarray(curve.segment) == 0))
    for extra, source in (((), "metadata"), (("--calibration", "fit"), "fit")):
        out = io.StringIO()
        with redirect_stdout(out):
            assert main(["analyze", str(local), "--json", *extra]) == 0
        cli = json.loads(out.getvalue())["results"][src.name]
        data = {"option": ["calibration.source=fit"]} if extra else {}
        api = client.post("/api/analyze", files={"file": (src.name, src.read_bytes())}, data=data).json()
        api = api["results"][src.name]
        assert api["calibration_source"] == cli["calibration_source"] == source
        for key in ("spring_constant", "sensitivity_used", "sensitivity_fit", "pull_off_force"):
            assert api[key] == cli[key], key
        if source == "metadata":
            assert api["spring_constant"] == pytest.approx(float(note["SpringConstant"]), rel=1e-12)
            assert api["sensitivity_used"] == pytest.approx(float(note["InvOLS"]), rel=1e-12)
            assert fit_in.spring_constant == api["spring_constant"] and fit_in.source == "file"
        else:
            assert api["sensitivity_used"] == api["sensitivity_fit"] > 2 * float(note["InvOLS"])
            k = float(note["SpringConstant"]) * (float(note["InvOLS"]) / api["sensitivity_fit"]) ** 2
            assert api["spring_constant"] == pytest.approx(k, rel=1e-9)
