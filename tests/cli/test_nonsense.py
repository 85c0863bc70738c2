"""Issue 31 item 6: nonsense refused before work, internal errors turned into clear ones.

Each case of the issue's list of hostile invocations, through the command line
(the work replaced by a function that raises, as in test_cli_ranges) and, where
the rule lives in the library, through Python too.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

from afmforce.cli.main import main
from afmforce.errors import ParameterError

from test_cli_ranges import _boom, refused  # noqa: F401

DATA = Path(__file__).parents[1] / "data"
CURVE = str(DATA / "asylum-mfp3d_SiN-tip_air.ibw")


@pytest.fixture
def no_work(monkeypatch):
    import afmforce.fit as fit
    import afmforce.sweep.files as files

    monkeypatch.setattr(fit, "fit_dynamic", _boom)
    monkeypatch.setattr(files, "plan_curves", _boom)
    monkeypatch.setattr(files, "analyze_files", _boom)


@pytest.mark.parametrize("argv, fragment", [
    (["analyze", CURVE, "--L0", "100um", "--L1", "200um"],
     "--L1 200 um is not shorter than the flexible beam --L0 100 um"),
    (["analyze", CURVE, "--meta", "spring_constant=1e9N/m"],
     "--meta spring_constant 1e9N/m is out of range: spring_constant, the spring constant k, must lie in "
     "[0.0001 N/m, 1000 N/m]"),
    (["fit", CURVE, "--jump-window", "-1ms"], "--jump-window -1ms is out of range: jump_window"),
    (["fit", CURVE, "--friction", "none", "--free", "xi"],
     "xi has no effect with the friction law 'none': the fit cannot determine it"),
    (["fit", CURVE, "--friction", "viscous", "--free", "zeta"], "choose friction 'load'"),
    (["analyze", CURVE, "--steps", ",,,"], "--steps ',,,': no step named"),
    (["analyze", CURVE, "--medium", "water"], "--medium water: the liquid analysis (drag, drainage, DLVO fit) "
                                              "needs the probe radius; give --radius"),
    (["analyze", CURVE, "--option", "liquid.medium=ethanol"], "needs the probe radius"),
])
def test_nonsense_is_refused_before_work(capsys, tmp_path, monkeypatch, no_work, argv, fragment):
    monkeypatch.chdir(tmp_path)
    assert fragment in refused(capsys, argv)


def test_a_radius_or_air_lets_the_medium_through(capsys, tmp_path, monkeypatch, no_work):
    """Refused only without a radius: with --radius (or --meta radius) or in air the analysis starts."""
    monkeypatch.chdir(tmp_path)
    for extra in (["--medium", "water", "--radius", "2.5um"], ["--medium", "water", "--meta", "radius=2.5um"],
                  ["--medium", "air"]):
        assert main(["analyze", CURVE, *extra]) == 1
        assert "unexpected WorkStarted" in capsys.readouterr().err


def test_the_library_refuses_a_free_parameter_the_friction_law_ignores():
    from afmforce.fit import fit_dynamic
    from afmforce.fit.params import check_free

    with pytest.raises(ParameterError, match="xi has no effect with the friction law 'none'"):
        fit_dynamic([], "beam", free=("xi",), fixed={"friction": "none"})
    assert check_free(["xi"], "beam", "viscous") == ("xi",) and check_free(["zeta"], "beam", "load") == ("zeta",)
    with pytest.raises(ParameterError, match="jump_window = -1 ms is out of range"):
        fit_dynamic([], "beam", jump_window=-1e-3)


def _not_utf8_copy(folder: Path) -> str:
    """A copy of a real curve under a name that is not UTF-8 (byte 0xff), as another system writes it."""
    name = os.fsencode(folder) + b"/curve-\xff.ibw"
    shutil.copyfile(CURVE, name)
    return os.fsdecode(name)


def test_a_file_name_that_is_not_utf8_is_analysed(capsys, tmp_path, monkeypatch):
    """Its undecodable byte is shown as \\xff in the tables and the JSON; the outputs are written."""
    path = _not_utf8_copy(tmp_path)
    assert main(["analyze", path]) == 0
    out, err = capsys.readouterr()
    assert "curve-\\xff.ibw" in out and "UnicodeEncodeError" not in err
    assert main(["analyze", path, "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert list(payload["results"]) == ["curve-\\xff.ibw"] and payload["failed"] == []
    assert main(["analyze", str(tmp_path), "--out", str(tmp_path / "out")]) == 0
    written = sorted(p.name for p in (tmp_path / "out").iterdir() if p.is_file())
    assert written == [os.fsdecode(b"curve-\xff.ibw.afmforce." + ext) for ext in (b"csv", b"json", b"png")]
    import pandas as pd

    summary = pd.read_parquet(next((tmp_path / "out").glob("batch-*/summary.parquet")))
    assert summary["name"].tolist() == ["curve-\\xff.ibw"]


def test_analyze_json_with_a_failed_file_has_an_error_object(capsys, tmp_path):
    bad = tmp_path / "bad.ibw"
    bad.write_bytes(b"not an igor wave at all")
    assert main(["analyze", str(bad), CURVE, "--json"]) == 1
    payload = json.loads(capsys.readouterr().out)
    assert list(payload["results"]) == ["asylum-mfp3d_SiN-tip_air.ibw"]       # the good file's result stays
    error = payload["error"]
    assert error["exit_status"] == 1 and error["type"]
    assert error["message"].startswith(f"1 of 2 file(s) or curve(s) failed; first {bad}: ")
    assert "not an Igor binary wave" in error["message"] and payload["failed"][0]["file"] == str(bad)


def test_version_json_is_json(capsys):
    from afmforce import __version__

    for argv in (["--version", "--json"], ["--json", "--version"]):
        assert main(argv) == 0
        assert json.loads(capsys.readouterr().out) == {"command": "afmforce", "exit_status": 0,
                                                       "version": __version__}
