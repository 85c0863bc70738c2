"""Which sensitivity a warning names, and a soft contact's slope that is not a sensitivity (docs/analysis.md,
"Which calibration").

* A sensitivity the user gave (``--sensitivity``, ``ProbeCalibration``) or a probe calibration file's
  (``--probe-calibration``) was called "the file's" in the slope's warning: the CLI hands it on as metadata too,
  without its origin. The warning now names it by its origin (``ProbeCalibration.origin``).
* On a soft contact the compliance slope is the sample's indentation and the lever's bending together: the
  virtual AFM's 5 kPa Hertz contact (truth 50 nm/V) gave "sens. fit" ~ 450 nm/V (9 x), printed in the table
  as a sensitivity beside the warning. It is reported undetermined (NaN, "-" in the table) and said why.
"""

from __future__ import annotations

import json
import math
import re
import sys
import warnings
from pathlib import Path

import pytest

from afmforce.analysis.options import ProbeCalibration
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.steps.calibration import SLOPE_FACTOR
from afmforce.cli.main import main
from afmforce.io import load
from realdata import DATA

sys.path.insert(0, str(Path(__file__).parent))
from test_baseline_climb_modulus import _virtual  # noqa: E402  (the virtual 5 kPa Hertz contact)

PATH = DATA / "bruker-nanoscope_synthetic.txt"     # a hard contact, DeflSens 45 nm/V in its header


def _sens() -> float:
    return float(re.search(r"\\@Sens\. DeflSens: V ([\d.]+) nm/V", PATH.read_text()).group(1)) * 1e-9


def _slope_warning(ws) -> str:
    (w,) = [w for w in ws if w.startswith(SLOPE_FACTOR)]
    return w


def test_a_given_sensitivity_is_named_as_the_users_in_python():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (c,) = load(PATH)
    r = analyze(c, probe=ProbeCalibration(sensitivity=0.5 * _sens()))
    w = _slope_warning(r.warnings)
    assert "2 x the one you gave (`sensitivity`)" in w and "yours is used" in w and "file's" not in w
    assert r.sensitivity_used == pytest.approx(0.5 * _sens(), rel=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = analyze(load(PATH, meta_override={"sensitivity": 0.5 * _sens()})[0])     # read as the file's
    assert "2 x the file's" in _slope_warning(r.warnings) and "the file's is used" in _slope_warning(r.warnings)


def _cli_warnings(capsys, *extra) -> list[str]:
    assert main(["analyze", str(PATH), "--json", *extra]) == 0
    (res,) = json.loads(capsys.readouterr().out)["results"].values()
    return res["warnings"]


def test_cli_sensitivity_and_calibration_file_are_named_by_their_origin(tmp_path, capsys):
    half = f"{0.5 * _sens() * 1e9:.6g}nm/V"
    w = _slope_warning(_cli_warnings(capsys, "--sensitivity", half))
    assert "the one you gave" in w and "yours is used" in w and "file's" not in w
    cal = tmp_path / "probe.json"
    cal.write_text(json.dumps({"afmforce_calibration": 1, "method": "test", "sensitivity": 0.5 * _sens(),
                               "units": {"sensitivity": "m/V"}}))
    w = _slope_warning(_cli_warnings(capsys, "--probe-calibration", str(cal)))
    assert "2 x the probe calibration file's" in w and "the calibration file's is used" in w
    w = _slope_warning(_cli_warnings(capsys, "--probe-calibration", str(cal), "--sensitivity", half))
    assert "the one you gave" in w             # typed over the file: the user's
    for extra, tag in ((("--probe-calibration", str(cal)), "(calibration)"), (("--sensitivity", half), "(user)"),
                       ((), "(file)")):
        assert main(["analyze", str(PATH), *extra]) == 0          # the table's "sens. used" cell says whose
        assert tag in capsys.readouterr().out.splitlines()[1]


def test_a_soft_contacts_slope_is_not_reported_as_a_sensitivity():
    """The virtual 5 kPa Hertz contact (truth 50 nm/V): the slope gave ~9 x; now NaN with the reason."""
    c = _virtual(-0.5)
    r = analyze(c)
    assert r.contact_kind == "soft"
    assert math.isnan(r.sensitivity_fit)
    assert r.sensitivity_used == pytest.approx(c.metadata["sensitivity"], rel=1e-12)
    assert not any(w.startswith(SLOPE_FACTOR) for w in r.warnings)
    (w,) = [w for w in r.warnings if "sensitivity from the compliance slope undetermined" in w]
    assert "the contact is soft" in w and "the file's is used" in w
    assert r.details["calibration"].sensitivity_fit > 5 * c.metadata["sensitivity"]   # the slope: not the lever's


def test_a_hard_contacts_slope_is_still_reported():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (c,) = load(PATH)
    r = analyze(c)
    assert r.contact_kind == "hard" and r.sensitivity_fit == pytest.approx(_sens(), rel=0.01)
