"""A compliance slope that calibrates a contact nothing shows to be hard (docs/analysis.md, "Calibration").

Where no sensitivity is stored or given, the compliance slope calibrates the deflection. That is the lever's
sensitivity only on a hard contact. The virtual AFM's Hertz contacts (5 um sphere, 0.1 N/m lever, true
sensitivity 50 nm/V) with the sensitivity removed from the file were called "hard" with a slope 4-16 x the
lever's (every force that many times too large) and nothing said it (found on branch silent, 2026-11-29): the
2 kPa contact's curvature was read as a surface force before a straight line, the 20 kPa contact had too few
contact samples to see a curvature. Now a warning says the calibration is unverified. A contact with a jump-in
(the synthetic van der Waals curve) is calibrated as before, within 1 % of the truth, and says nothing.
"""

import dataclasses

import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.analysis.steps.kind import SLOPE_HARD_UNVERIFIED
from afmforce.analysis.synthetic import static_curve
from afmforce.instrument.soft_map import SoftMapConfig, soft_curve

SENS = 50e-9
UNVERIFIED = SLOPE_HARD_UNVERIFIED.split("(")[0]


def _without_sensitivity(c):
    md = {k: v for k, v in c.metadata.items() if k != "sensitivity"}
    return dataclasses.replace(c, metadata=md)


@pytest.mark.parametrize("modulus", [2e3, 20e3])
def test_a_soft_contact_calibrated_by_its_slope_is_said_unverified(modulus):
    c = soft_curve(SoftMapConfig(sensitivity=SENS), modulus, 0.0, 0.0, seed=1)
    r = analyze(_without_sensitivity(c))
    assert r.contact_kind == "hard"
    # the slope's sensitivity is the sample's and the lever's together: several times the lever's
    assert r.sensitivity_used > 3 * SENS
    said = [w for w in r.warnings if w.startswith(UNVERIFIED)]
    assert len(said) == 1 and f"{r.sensitivity_used * 1e9:.4g} nm/V" in said[0]
    # with the file's sensitivity the same curve is soft and says nothing of the kind
    r0 = analyze(c)
    assert r0.contact_kind == "soft"
    assert not any(w.startswith(UNVERIFIED) for w in r0.warnings)


def test_a_jump_in_contact_calibrated_by_its_slope_says_nothing():
    c = static_curve(sensitivity=SENS, noise=0.02e-9, seed=3)
    r = analyze(_without_sensitivity(c))
    assert r.contact_kind == "hard"
    assert r.sensitivity_used == pytest.approx(SENS, rel=0.01)
    assert not any(w.startswith(UNVERIFIED) for w in r.warnings)
