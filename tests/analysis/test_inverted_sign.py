"""A deflection signal stored with the other sign (falling as the tip presses on the sample).

Its compliance line falls, so its slope calibrates a negative sensitivity, which no detector has. The
analysis orients such a curve first (negates the signal, says so) and analyses it again: the sensitivity
from the slope is the positive one the virtual curve was made with, and every number equals that of the
curve stored the usual way. The library, the command line (`afmforce analyze --calibration fit`) and the
InvOLS calibration (`afmforce calibrate invols`, the same analysis) go through `analyze`; the web's face
is tested in tests/web/test_web_inverted_sign.py.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from afmforce.analysis.options import CalibrationOptions
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.synthetic import static_curve

#: The virtual curve's InvOLS [m/V] (the truth the slope must give back).
SENSITIVITY = 50e-9


@pytest.fixture(scope="module")
def curves():
    plain = static_curve(sensitivity=SENSITIVITY, noise=0.05e-9, seed=1)
    inverted = dataclasses.replace(plain, deflection_signal=-np.asarray(plain.deflection_signal))
    return plain, inverted


def _said(res) -> bool:
    return any("sign is inverted" in w and "negated" in w for w in res.warnings)


@pytest.mark.parametrize("source", ["fit", "auto"])
def test_inverted_curve_calibrates_the_positive_sensitivity(curves, source):
    """`calibration` fit (and auto, which fits without a file sensitivity): before, the inverted curve gave
    -49.9 nm/V (the inverted-sign warning beside it, nothing explaining the negative number)."""
    plain, inverted = curves
    opts = [CalibrationOptions(source=source)]
    ref, res = analyze(plain, options=opts), analyze(inverted, options=opts)
    assert res.calibration_source == "fit"
    assert res.sensitivity_fit > 0 and res.sensitivity_used > 0
    assert res.sensitivity_fit == pytest.approx(SENSITIVITY, rel=0.01)          # the truth
    assert res.sensitivity_fit == pytest.approx(ref.sensitivity_fit, rel=1e-9)  # the usual curve's
    assert res.pull_off_force == pytest.approx(ref.pull_off_force, rel=1e-9) and res.pull_off_force < 0
    assert res.jump_in_separation == pytest.approx(ref.jump_in_separation, rel=1e-6)
    assert _said(res) and not _said(ref)
    assert f"{res.sensitivity_fit * 1e9:.4g} nm/V" in next(w for w in res.warnings if "sign is inverted" in w)
    # the old ambiguous note (negate it yourself) is gone: the curve analysed is the oriented one
    assert not any("negate the deflection signal" in w for w in res.warnings)


def test_inverted_curve_with_the_files_sensitivity(curves):
    """With a sensitivity in the file (auto uses it): the forces of the usual curve, not their negatives."""
    plain, inverted = curves
    md = {**plain.metadata, "sensitivity": SENSITIVITY, "spring_constant": 0.21}
    ref = analyze(dataclasses.replace(plain, metadata=md))
    res = analyze(dataclasses.replace(inverted, metadata=md))
    assert res.calibration_source == ref.calibration_source == "metadata"
    assert res.sensitivity_fit > 0 and res.sensitivity_fit == pytest.approx(ref.sensitivity_fit, rel=1e-9)
    assert res.pull_off_force == pytest.approx(ref.pull_off_force, rel=1e-9)
    assert res.adhesion_force == pytest.approx(ref.adhesion_force, rel=1e-9) and res.adhesion_force < 0
    assert _said(res)


def test_cli_analyze_calibration_fit_orients_an_inverted_curve(curves, tmp_path, capsys):
    from afmforce.cli.main import main
    from afmforce.io.native.rawfile import write_raw

    _, inverted = curves
    path = write_raw(inverted, tmp_path / "inverted.txt")
    assert main(["analyze", str(path), "--calibration", "fit", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)["results"]["inverted.txt"]
    assert row["sensitivity_fit"] == row["sensitivity_used"] == pytest.approx(SENSITIVITY, rel=0.01)
    assert any("sign is inverted" in w for w in row["warnings"])


def test_a_rising_compliance_line_is_left_alone(curves):
    """The usual curve: no orientation, no note (every real file of tests/data and the corpus rises: their
    compliance slopes as read are all positive, checked when this was written)."""
    plain, _ = curves
    res = analyze(plain)
    assert not _said(res) and math.isfinite(res.sensitivity_fit) and res.sensitivity_fit > 0


def test_a_line_that_falls_within_its_noise_is_not_taken_for_an_inverted_sign():
    """NSFopen 1.1.18's FluidFM cell curve 1 (k 0.902 N/m): its "compliance line" falls by 1.0 x its own
    residual scale (-0.0013 N/m, 1/700 of k): a creeping contact, not a lever stored with the other sign.
    It is left as read (no negation, no note); the calibration gives no sensitivity from it."""
    import os
    from pathlib import Path

    from afmforce.analysis.pipeline import INVERTED_LINE_SIGMAS
    from afmforce.io import load

    path = Path(os.environ.get("AFMFORCE_REAL_DATA", "")) / "nsfopen-1.1.18_spec.nid"
    if not path.is_file():
        pytest.skip("nsfopen-1.1.18_spec.nid absent (pip download --no-deps NSFopen==1.1.18)")
    res = analyze(load(path)[1])
    line = res.details["compliance"].approach
    assert line.slope < 0 and -line.slope * (line.z_max - line.z_min) < INVERTED_LINE_SIGMAS * line.sigma
    assert not _said(res) and math.isnan(res.sensitivity_fit)
