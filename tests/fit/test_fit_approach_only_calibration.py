"""An approach-only curve is calibrated with the file's sensitivity (`afmforce.fit.preprocess`):
``calibration`` "fit" (the compliance slope) is refused there, not ignored. Before, "fit" on such a
curve gave the file's sensitivity in silence, while the same word on a whole curve takes the slope."""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.errors import ParameterError
from afmforce.fit.preprocess import analysis_inputs
from afmforce.io.curve import RawCurve

SENS = 40e-9          # the file's sensitivity [m/V]
TRUE = 50e-9          # the lever's: the compliance slope gives this one


def _approach_only() -> RawCurve:
    n = 400
    z = np.linspace(-200e-9, 50e-9, n)                      # the base moves 250 nm towards the sample
    d = np.where(z > 0, z, 0.0)                             # free, then a rigid contact at z = 0
    d = d + 0.02e-9 * np.random.default_rng(1).standard_normal(n)
    return RawCurve(time=np.arange(n) * 1e-3, piezo_nominal=z, deflection_signal=d / TRUE,
                    segment=np.zeros(n, np.int8), deflection_unit="V",
                    metadata=dict(sensitivity=SENS, spring_constant=0.1, velocity=0.25e-6, sample_rate=1e3))


def test_fit_calibration_is_refused_on_an_approach_only_curve():
    curve = _approach_only()
    idx = np.arange(curve.time.size)
    auto = analysis_inputs(curve, "c", idx)                  # the file's sensitivity, as documented
    assert auto.factor == SENS and auto.source == "file"
    assert auto.slope == pytest.approx(SENS / TRUE, rel=0.02)   # the line with the file's: 0.8, not 1
    with pytest.raises(ParameterError, match="calibration 'fit'"):
        analysis_inputs(curve, "c", idx, calibration="fit")
