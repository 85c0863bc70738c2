"""The web's analysis names a probe calibration file's values as the file's, and a ``meta`` value as the
user's, exactly as ``afmforce analyze --probe-calibration`` / ``--meta`` do (was: an uploaded calibration
file's values went in as typed ones, "the one you gave (`sensitivity`)", and its thermal k was never
rescaled under calibration fit). The curve: tests/data/bruker-nanoscope_synthetic.txt (true InvOLS 45 nm/V)."""

from __future__ import annotations

import io
import json
from contextlib import redirect_stdout

import pytest

from afmforce.calibration.record import write_calibration
from afmforce.cli.main import main
from realdata import DATA

fastapi = pytest.importorskip("fastapi")
PATH = DATA / "bruker-nanoscope_synthetic.txt"


def _cli(*flags: str) -> dict:
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(PATH), "--json", *flags]) == 0
    return json.loads(out.getvalue())["results"][PATH.name]


def _api(client, data: dict, cal=None) -> dict:
    files = {"file": (PATH.name, PATH.read_bytes())}
    if cal is not None:
        files["calibration"] = ("calib.json", cal.read_bytes())
    r = client.post("/api/analyze", files=files, data=data)
    assert r.status_code == 200, r.text
    return r.json()["results"][PATH.name]


def test_a_calibration_upload_is_named_and_rescaled_as_on_the_command_line(client, tmp_path):
    cal = write_calibration(tmp_path / "calib.json", "thermal", {"spring_constant": 0.84, "sensitivity": 22.5e-9},
                            {"spring_constant": "N/m", "sensitivity": "m/V"})
    for flags, data in ((["--probe-calibration", str(cal)], {}),
                        (["--probe-calibration", str(cal), "--calibration", "fit"], {"option": ["calibration.source=fit"]})):
        cli, api = _cli(*flags), _api(client, data, cal)
        assert api["warnings"] == cli["warnings"] and api["spring_constant"] == cli["spring_constant"]
        assert any("the probe calibration file's" in w for w in api["warnings"])
        assert not any("the one you gave" in w for w in api["warnings"])
    assert api["spring_constant"] == pytest.approx(0.84 * (22.5e-9 / api["sensitivity_fit"]) ** 2, rel=1e-9)
    # the page sends the calibration file for the values it left untouched only (calibration_keys)
    only_k = _api(client, {"calibration_keys": ["spring_constant"]}, cal)
    assert only_k["spring_constant"] == 0.84 and only_k["sensitivity"] == pytest.approx(45e-9, rel=1e-6)


def test_a_meta_sensitivity_is_named_as_the_users(client):
    api = _api(client, {"meta": ["sensitivity=22.5nm/V"]})
    (w,) = [w for w in api["warnings"] if w.startswith("the compliance slope gives a calibration")]
    assert "the one you gave as metadata (meta sensitivity)" in w and "yours is used" in w
    assert api["warnings"] == _cli("--meta", "sensitivity=22.5nm/V")["warnings"]
