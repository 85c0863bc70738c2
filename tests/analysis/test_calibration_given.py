"""The compliance-slope warning names whose sensitivity the forces use: the user's (``--sensitivity``,
``--probe-calibration``, the web's probe) or the file's.

Was: ``afmforce analyze jpk_cellhesion_spot3.jpk-force --probe-calibration calib.json`` (InvOLS 11.04
nm/V from a thermal calibration; the file's 70 nm/V) printed "sens. used 11.04 (user)" in its table
and, below it, "the compliance slope gives a calibration 12.6 x the file's ...: the file's is used"."""

from __future__ import annotations

from pathlib import Path

from afmforce.analysis.options import ProbeCalibration
from afmforce.analysis.pipeline import analyze
from afmforce.io import load

CURVE = Path(__file__).resolve().parents[1] / "data" / "jpk_cellhesion_spot3.jpk-force"


def _slope_warning(res) -> str:
    """The warning on the compliance slope: this curve's contact is soft, so it says the slope is no
    sensitivity (``steps.calibration.SOFT_SLOPE``) and names the one used."""
    (w,) = [w for w in res.warnings if w.startswith("sensitivity from the compliance slope undetermined")]
    return w


def test_a_given_sensitivity_is_named_as_given():
    curve = load(CURVE)[0]
    own = analyze(curve)
    given = analyze(curve, probe=ProbeCalibration(sensitivity=11.04e-9))
    assert own.sensitivity_used == curve.metadata["sensitivity"] and given.sensitivity_used == 11.04e-9
    assert "the file's is used" in _slope_warning(own)
    text = _slope_warning(given)
    assert "yours is used" in text and "file's" not in text


def test_a_given_sensitivity_rescales_a_curve_stored_in_newtons_as_its_reader_does():
    """The reference: the reader's own rescaling (``meta_override``), which the CLI and the web use."""
    s = 11.04e-9
    via_probe = analyze(load(CURVE)[0], probe=ProbeCalibration(sensitivity=s))
    via_reader = analyze(load(CURVE, meta_override={"sensitivity": s})[0], probe=ProbeCalibration(sensitivity=s))
    assert via_probe.sensitivity_used == via_reader.sensitivity_used == s
    for name in ("adhesion_force", "sensitivity_fit", "indentation"):
        a, b = ((p.details["calibration"].sensitivity_fit if name == "sensitivity_fit" else getattr(p, name))
                for p in (via_probe, via_reader))
        assert abs(a - b) <= 1e-9 * abs(b), (name, a, b)
    own = analyze(load(CURVE)[0])
    assert abs(via_probe.adhesion_force / own.adhesion_force - s / own.sensitivity_used) < 1e-6
