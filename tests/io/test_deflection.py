"""The deflection-signal conversion is written once (afmforce.io.deflection.signal_factor): numbers
by Hooke's law and the InvOLS definition, and every user gives the same factor."""

import math

import numpy as np
import pytest

from afmforce.io.curve import RawCurve
from afmforce.io.deflection import signal_factor

SENS, K = 45e-9, 0.12   # m/V, N/m


@pytest.mark.parametrize("unit, deflection, force", [
    ("V", SENS, SENS * K),      # volts x InvOLS = metres; x k = newtons
    ("m", 1.0, K),
    ("N", 1.0 / K, 1.0),        # newtons / k = metres
])
def test_factors_are_invols_and_hooke(unit, deflection, force):
    assert signal_factor(unit, SENS, K) == pytest.approx(deflection, rel=1e-15)
    assert signal_factor(unit, SENS, K, to="force") == pytest.approx(force, rel=1e-15)
    # force = deflection x k whatever the unit (Hooke)
    assert signal_factor(unit, SENS, K, to="force") == pytest.approx(signal_factor(unit, SENS, K) * K, rel=1e-15)


@pytest.mark.parametrize("missing", [None, 0, 0.0, math.nan])
def test_unknown_calibration_is_nan(missing):
    assert math.isnan(signal_factor("V", missing, K))
    assert math.isnan(signal_factor("V", SENS, missing, to="force"))
    assert math.isnan(signal_factor("N", SENS, missing))
    assert signal_factor("m", missing, missing) == 1.0          # metres need nothing
    assert signal_factor("N", missing, missing, to="force") == 1.0
    with pytest.raises(ValueError):
        signal_factor("V", SENS, K, to="pressure")


@pytest.mark.parametrize("unit", ["V", "m", "N"])
def test_every_user_takes_the_one_factor(unit):
    """RawCurve's methods and the calibration step's metadata factor are the function's numbers."""
    from afmforce.analysis.compliance import _metadata_factor

    md = {"sensitivity": SENS, "spring_constant": K}
    curve = RawCurve(time=np.arange(3.0), piezo_nominal=np.zeros(3), deflection_signal=np.ones(3),
                     segment=np.zeros(3, dtype=int), deflection_unit=unit, metadata=md)
    assert curve.deflection_factor() == signal_factor(unit, SENS, K)
    assert curve.force_factor() == signal_factor(unit, SENS, K, to="force")
    assert _metadata_factor(unit, md) == signal_factor(unit, SENS, K)
