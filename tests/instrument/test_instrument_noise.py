"""Drift (linear per run, recovered by a line fit in the zero-force regime, paper Fig 7),
seeded noise, sampling and the ADC."""

import numpy as np
import pytest

from afmforce.errors import ParameterError
from afmforce.instrument import Acquisition, Drift, Instrument, Noise, Photodiode, get_preset
from afmforce.instrument.noise import pink_noise

from afm_trajectories import ramp_trajectory

PD = Photodiode(sensitivity=20e-9)


@pytest.mark.parametrize("drift", [Drift(rates=(0.3, -0.2)), Drift(rate_rms=0.25)])
def test_drift_slope_recovered_by_a_line_fit_in_the_zero_force_region(drift):
    # Paper Fig 7: "a linear thermal drift correction has been applied separately on the two
    # runs, as measured in the zero force regime".
    inst = Instrument(photodiode=PD, drift=drift, noise=Noise(white=0.015))
    tr = ramp_trajectory([-1e-6, 0.2e-6, -1e-6], 2e-6, 2e3, contact=0.0)
    raw = inst.record(tr, seed=11)
    rates = raw.truth["drift_rates"]
    assert len(rates) == 2
    if drift.rates:
        assert rates == [0.3, -0.2]
    for run in (0, 1):
        free = (raw.segment == run) & (tr.deflection == 0)
        t, s = raw.time[free], raw.deflection_signal[free]
        slope, _ = np.polyfit(t, s, 1)
        stderr = 0.015 / np.sqrt(np.sum((t - t.mean()) ** 2))
        assert slope == pytest.approx(rates[run], abs=4 * stderr)
    assert np.allclose(np.diff(raw.truth["drift"][:5]), rates[0] * np.diff(raw.time[:5]))


def test_same_seed_same_output_different_seed_different():
    inst = get_preset("paper")
    tr = ramp_trajectory([-0.5e-6, 0.1e-6, -0.5e-6], 5e-6, 5e3, contact=0.0)
    a, b, c = inst.record(tr, seed=7), inst.record(tr, seed=7), inst.record(tr, seed=8)
    for name in ("time", "piezo_nominal", "piezo_measured", "deflection_signal", "segment"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes()
    assert not np.array_equal(a.deflection_signal, c.deflection_signal)
    unseeded = inst.record(tr)
    again = inst.record(tr, seed=unseeded.metadata["seed"])
    assert np.array_equal(unseeded.deflection_signal, again.deflection_signal)


def test_white_noise_rms():
    inst = Instrument(photodiode=PD, noise=Noise(white=0.01))
    tr = ramp_trajectory([0.0, 1e-6], 1e-6, 2e4)
    raw = inst.record(tr, seed=2)
    assert np.std(raw.deflection_signal) == pytest.approx(0.01, rel=0.03)


def test_pink_noise_has_a_one_over_f_spectrum():
    x = pink_noise(2**16, 1.0, np.random.default_rng(0))
    assert np.std(x) == pytest.approx(1.0, rel=1e-12)
    f = np.fft.rfftfreq(x.size)[1:]
    psd = np.abs(np.fft.rfft(x))[1:] ** 2
    slope = np.polyfit(np.log(f), np.log(psd), 1)[0]
    assert slope == pytest.approx(-1.0, abs=0.05)


def test_resampling_to_a_lower_sample_rate():
    tr = ramp_trajectory([0.0, 0.3e-6, 0.0], 1e-6, 1e4, contact=0.25e-6)
    raw = Instrument(acquisition=Acquisition(sample_rate=2.5e3)).record(tr)
    assert np.allclose(np.diff(raw.time), 1 / 2.5e3, rtol=1e-9)
    assert raw.time[-1] <= tr.time[-1] + 1e-12
    assert np.allclose(raw.truth["piezo_position"], np.interp(raw.time, tr.time, tr.piezo_position), atol=1e-18)
    assert np.array_equal(raw.segment, (raw.time > 0.3).astype(np.int8))
    assert raw.metadata["sample_rate"] == 2.5e3


def test_sample_rate_above_the_trajectory_is_refused():
    tr = ramp_trajectory([0.0, 0.1e-6], 1e-6, 1e3)
    with pytest.raises(ParameterError, match="above the trajectory"):
        Instrument(acquisition=Acquisition(sample_rate=5e3)).record(tr)


def test_adc_quantisation_and_clipping():
    acq = Acquisition(adc_bits=8, adc_range=1.0)
    lsb = 2 / 256
    assert acq.lsb == lsb
    v = np.linspace(-1.5, 1.5, 10001)
    q = acq.quantise(v)
    assert np.allclose(q / lsb, np.round(q / lsb))
    inside = np.abs(v) < 1 - lsb
    assert np.max(np.abs(q - v)[inside]) <= lsb / 2 + 1e-15
    assert q.min() == -1.0 and q.max() == 1.0 - lsb


@pytest.mark.parametrize("kw", [dict(adc_bits=0), dict(adc_bits=1.5), dict(adc_bits=64), dict(sample_rate=-1.0),
                                dict(adc_range=0.0)])
def test_bad_acquisition_parameters(kw):
    with pytest.raises(ParameterError):
        Acquisition(**kw)


def test_volt_artefacts_need_a_sensitivity():
    with pytest.raises(ParameterError, match="sensitivity"):
        Instrument(noise=Noise(white=0.01))
    with pytest.raises(ParameterError, match="sensitivity"):
        Instrument(acquisition=Acquisition(adc_bits=12))
