"""Optical lever, interference fringes (period 2 pi Delta) and saturation.

Paper section 3.1: I(z) = I0 cos(z / Delta) in the zero-force regime, Delta set by the
wavelength and angle; derivation in afmforce.instrument.photodiode:
Delta = lambda / (4 pi cos alpha), so the period is lambda / (2 cos alpha) (335 nm at 670 nm).
"""

import math

import numpy as np
import pytest

from afmforce.errors import ParameterError
from afmforce.instrument import Instrument, Photodiode, fringe_length, get_preset

from afm_trajectories import ramp_trajectory


def test_fringe_length_formula():
    assert 2 * math.pi * fringe_length(670e-9) == pytest.approx(335e-9, rel=1e-12)
    assert 2 * math.pi * fringe_length(633e-9, math.radians(30)) == pytest.approx(633e-9 / (2 * math.cos(math.radians(30))))


@pytest.mark.parametrize("angle_deg", [0.0, 25.0])
def test_fringe_period_from_zero_crossings(angle_deg):
    pd = Photodiode(sensitivity=20e-9, interference_amplitude=0.1, wavelength=670e-9,
                    incidence_angle=math.radians(angle_deg), interference_phase=0.3)
    tr = ramp_trajectory([0.0, 3e-6], 10e-6, 1e5)  # zero force throughout
    raw = Instrument(photodiode=pd).record(tr)
    z, s = tr.piezo_position, raw.deflection_signal
    k = np.flatnonzero(np.sign(s[1:]) != np.sign(s[:-1]))
    crossings = z[k] - s[k] * (z[k + 1] - z[k]) / (s[k + 1] - s[k])
    period = 2 * np.mean(np.diff(crossings))
    assert period == pytest.approx(670e-9 / (2 * math.cos(math.radians(angle_deg))), rel=1e-4)


def test_paper_preset_fringes_in_the_zero_force_regime():
    # With noise and drift: detrend each run by a line (the paper's drift correction), then the
    # periodogram against the true position peaks at the fringe period.
    inst = get_preset("paper")
    tr = ramp_trajectory([0.0, -3e-6, 0.0], 2e-6, 4e3)
    raw = inst.record(tr, seed=5)
    z = tr.piezo_position
    periods = np.linspace(250e-9, 450e-9, 801)
    power = np.zeros_like(periods)
    for run in (0, 1):
        m = raw.segment == run
        t, s = raw.time[m], raw.deflection_signal[m]
        s = s - np.polyval(np.polyfit(t, s, 1), t)
        for i, P in enumerate(periods):
            power[i] += abs(np.sum(s * np.exp(2j * np.pi * z[m] / P))) ** 2
    best = periods[np.argmax(power)]
    assert best == pytest.approx(inst.photodiode.fringe_period, rel=0.005)
    assert inst.photodiode.fringe_period == pytest.approx(335e-9)


def test_optical_lever_sensitivity_and_offset():
    pd = Photodiode(sensitivity=25e-9, offset=0.4)
    tr = ramp_trajectory([-0.2e-6, 0.1e-6], 1e-6, 1e4, contact=0.0)
    raw = Instrument(photodiode=pd).record(tr)
    assert raw.deflection_unit == "V"
    assert np.allclose(raw.deflection_signal, 0.4 + tr.apparent_deflection / 25e-9, rtol=1e-14, atol=1e-14)
    assert raw.metadata["sensitivity"] == 25e-9


def test_saturation_at_the_top_of_constant_compliance():
    # Paper Fig 7: "the photodiode signal has saturated at the top of the constant compliance curves".
    inst = get_preset("paper")
    tr = ramp_trajectory([-0.5e-6, 0.5e-6, -0.5e-6], 5e-6, 5e3, contact=0.0)
    raw = inst.record(tr, seed=1)
    assert np.max(raw.deflection_signal) == pytest.approx(inst.photodiode.saturation, abs=inst.acquisition.lsb)
    top = tr.deflection > 0.2e-6
    assert np.all(np.abs(raw.deflection_signal[top] - 7.5) <= inst.acquisition.lsb)


@pytest.mark.parametrize("kw", [dict(sensitivity=-1e-9), dict(offset=0.1), dict(saturation=5.0),
                                dict(interference_amplitude=0.1), dict(sensitivity=1e-8, wavelength=-1.0),
                                dict(sensitivity=1e-8, incidence_angle=math.pi / 2),
                                dict(sensitivity=1e-8, saturation=-1.0)])
def test_bad_photodiode_parameters(kw):
    with pytest.raises(ParameterError):
        Photodiode(**kw)
