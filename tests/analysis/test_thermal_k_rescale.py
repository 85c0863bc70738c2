"""`calibration fit` rescales the file's thermal spring constant with the file's InvOLS, also where the user
gives a sensitivity: k_thermal = kB T / <d^2> with d in the file's InvOLS, so k_new = k_file (InvOLS_file /
InvOLS_fit)^2 (before: (the user's / fitted)^2: 0.0934 instead of 0.2101 N/m with 30 nm/V on a 45 nm/V file).
"""

from __future__ import annotations

import json
import warnings

import pytest

from afmforce.analysis.options import CalibrationOptions, ProbeCalibration
from afmforce.analysis.pipeline import analyze
from afmforce.cli.main import main
from afmforce.io import load
from realdata import DATA, bruker_synthetic_header

PATH = DATA / "bruker-nanoscope_synthetic.txt"
USER = 30e-9   # [m/V] a user's sensitivity, 2/3 of the file's 45 nm/V


def _check(k, fit, sens, k_file):
    assert fit == pytest.approx(sens, rel=0.01)                       # a hard contact: the slope agrees
    assert k == pytest.approx(k_file * (sens / fit) ** 2, rel=1e-12)   # the closed form, the file's InvOLS
    assert abs(k / (k_file * (USER / fit) ** 2) - 1) > 1.0              # not the user's (before: 0.0934 N/m)


def test_api_probe_sensitivity_rescales_with_the_files():
    sens, k_file = bruker_synthetic_header()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        curve = load(PATH)[0]
        res = analyze(curve, options=[CalibrationOptions(source="fit")], probe=ProbeCalibration(sensitivity=USER))
    _check(res.spring_constant, res.sensitivity_fit, sens, k_file)
    w = [x for x in res.warnings if "spring constant rescaled" in x]
    assert w and f"{sens * 1e9:.4g} -> {res.sensitivity_fit * 1e9:.4g} nm/V" in w[0]


def test_cli_sensitivity_rescales_with_the_files(tmp_path, capsys):
    """The CLI passes --sensitivity to the readers too; the file's own InvOLS must survive for the rescale."""
    sens, k_file = bruker_synthetic_header()
    assert main(["analyze", str(PATH), "--sensitivity", "30nm/V", "--calibration", "fit", "--json",
                 "--out", str(tmp_path / "o"), "--no-plot"]) == 0
    r = next(iter(json.loads(capsys.readouterr().out)["results"].values()))
    cal = r["details"]["calibration"]
    assert cal["sensitivity"] == pytest.approx(USER, rel=1e-12)          # the user's is the one given
    _check(r["spring_constant"], cal["sensitivity_fit"], sens, k_file)
