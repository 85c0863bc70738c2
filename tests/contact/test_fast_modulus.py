"""fast_modulus (a QI pixel's modulus without the other pipeline steps) and the pipeline step on a
synthetic indentation curve of known modulus (the tip deflects as it indents: z = c + delta + F/k)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis.indentation import fast_modulus
from afmforce.analysis.options import IndentationOptions
from afmforce.contact.models import hertz_cone, hertz_paraboloid
from afmforce.errors import AnalysisError
from afmforce.io.curve import RawCurve

K, SENS = 0.05, 40e-9  # N/m, m/V


def _curve(law, E, n=300, offset_volts=0.3, noise=2e-12, seed=0):
    rng = np.random.default_rng(seed)
    delta = np.linspace(-3e-6, 1.2e-6, n)
    F = law(delta, E)
    z_app = 5e-6 + delta + F / K  # z grows towards the probe; the contact at z = 5 um
    F = F + rng.normal(0, noise, n)
    volts = F / K / SENS + offset_volts
    z = np.concatenate((z_app, z_app[::-1]))
    sig = np.concatenate((volts, volts[::-1]))
    seg = np.repeat(np.array([0, 1], dtype=np.int8), n)
    t = np.arange(2 * n) * 1e-3
    return RawCurve(time=t, piezo_nominal=z, deflection_signal=sig, segment=seg, deflection_unit="V",
                    metadata={"spring_constant": K, "sensitivity": SENS})


@pytest.mark.parametrize("model, law, opts", [
    ("hertz_paraboloid", lambda d, E: hertz_paraboloid(d, E, 5e-6, 0.5), {"tip_radius": 5e-6}),
    ("hertz_cone", lambda d, E: hertz_cone(d, E, math.radians(20), 0.5), {"half_angle": math.radians(20)}),
])
def test_fast_modulus_recovers_E_and_the_contact_point(model, law, opts):
    res = fast_modulus(_curve(law, 3e3), IndentationOptions(model=model, **opts))
    assert abs(res.youngs_modulus / 3e3 - 1) < 0.01
    assert res.youngs_modulus_low < 3e3 < res.youngs_modulus_high or abs(res.youngs_modulus / 3e3 - 1) < 2e-3
    assert abs(res.contact_point - 5e-6) < 5e-9  # piezo position at contact [m]
    assert res.residuals.size == res.n_points and abs(np.std(res.residuals) - 2e-12) < 1e-12


def test_pipeline_step_agrees_with_fast_path_on_a_clean_curve():
    from afmforce.analysis.pipeline import analyze

    curve = _curve(lambda d, E: hertz_paraboloid(d, E, 5e-6, 0.5), 3e3, noise=5e-12)
    opts = IndentationOptions(tip_radius=5e-6)
    res = analyze(curve, steps=["indentation"], options=[opts])
    assert res.contact_kind == "soft"
    assert abs(res.youngs_modulus / fast_modulus(curve, opts).youngs_modulus - 1) < 0.02
    assert abs(res.youngs_modulus / 3e3 - 1) < 0.03


def test_fast_modulus_needs_calibration():
    curve = _curve(lambda d, E: hertz_paraboloid(d, E, 5e-6, 0.5), 3e3)
    bare = RawCurve(curve.time, curve.piezo_nominal, curve.deflection_signal, curve.segment, deflection_unit="V",
                    metadata={"spring_constant": K})
    with pytest.raises(AnalysisError, match="sensitivity"):
        fast_modulus(bare, IndentationOptions(tip_radius=5e-6))
