"""Position detector: backlash vs speed (paper Figs 7C, 8) and the digitisation step.

Paper section 3.1: shifts of the inward run of +57, +33, +27 and ~0 nm at 17, 8.4, 6.6 and
0.4 um/s (+-10 nm); "the true position of the substrate on the inward run is about 0.05 um
greater than the position measured"; an 11-point running average removes the digitisation.
"""

import numpy as np
import pytest

from afmforce.errors import ParameterError
from afmforce.instrument import PAPER_BACKLASH, Instrument, PositionDetector, fit_backlash_law, get_preset

from afm_trajectories import ramp_trajectory


def test_fit_of_the_paper_points_gives_the_preset_law():
    speeds, widths = zip(*PAPER_BACKLASH)
    b_ref, p = fit_backlash_law(speeds, widths, reference_speed=10e-6)
    det = get_preset("paper").detector
    assert det.backlash_speed == 10e-6
    assert det.backlash == pytest.approx(b_ref, abs=0.05e-9)
    assert det.backlash_exponent == pytest.approx(p, abs=5e-4)


@pytest.mark.parametrize("speed, shift", PAPER_BACKLASH)
def test_paper_backlash_offset_vs_speed(speed, shift):
    # Record a zero-force cycle with the paper's detector; the offset of the measured position
    # between the runs (mean over the settled parts) is the shift that overlays them.
    det = get_preset("paper").detector
    travel = 1e-6
    fs = speed / 0.5e-9  # 0.5 nm per sample, as in the paper's Fig 9 runs
    tr = ramp_trajectory([0.0, travel, 0.0], speed, fs)
    raw = Instrument(detector=det).record(tr)
    err = raw.piezo_measured - tr.piezo_position
    z = tr.piezo_position
    settled = (z > 0.2 * travel) & (z < 0.8 * travel)
    inward = np.mean(err[settled & (raw.segment == 0)])
    outward = np.mean(err[settled & (raw.segment == 1)])
    measured_shift = outward - inward
    assert inward < 0 < outward or shift == 0  # the inward run reads low (paper, Fig 7B)
    assert measured_shift == pytest.approx(det.backlash_width(speed), abs=1e-9)
    assert measured_shift == pytest.approx(shift, abs=10e-9)  # the paper's +-10 nm


def test_backlash_is_a_dead_band_at_the_turn():
    det = PositionDetector(backlash=40e-9, backlash_exponent=0.0)
    tr = ramp_trajectory([0.0, 0.5e-6, 0.0], 1e-6, 1e5)
    reading = det.analog(tr.time, tr.piezo_position, tr.segment)
    k = int(np.argmax(tr.piezo_position))
    stuck = np.flatnonzero(reading == reading[k])
    travel_stuck = tr.piezo_position[k] - tr.piezo_position[stuck[-1]]
    assert travel_stuck == pytest.approx(40e-9, abs=0.02e-9)  # the full width b after the turn
    assert reading[k] == pytest.approx(tr.piezo_position[k] - 20e-9)


def test_digitisation_step_visible_and_removed_by_11_point_average():
    # Fig 7C: "an 11-point running average ... equivalent to linear interpolation between
    # successive digitization levels": with 11 samples per level the staircase averages out.
    q = 5e-9
    det = PositionDetector(step=q)
    v, fs = 1e-6, 1e-6 / (q / 11)
    tr = ramp_trajectory([0.0, 0.5e-6], v, fs)
    raw = Instrument(detector=det).record(tr)
    m, z = raw.piezo_measured, tr.piezo_position
    levels = m / q
    assert np.allclose(levels, np.round(levels), atol=1e-9)
    assert set(np.unique(np.round(np.diff(m) / q))) == {0.0, 1.0}
    err = m - z
    assert np.sqrt(np.mean(err**2)) == pytest.approx(q / np.sqrt(12), rel=0.05)
    smooth = np.convolve(m, np.ones(11) / 11, mode="valid")
    rms_after = np.sqrt(np.mean((smooth - z[5:-5]) ** 2))
    assert rms_after < 0.05 * q


def test_detector_noise_is_seeded():
    det = PositionDetector(noise=1e-9)
    tr = ramp_trajectory([0.0, 0.1e-6], 1e-6, 1e4)
    a = Instrument(detector=det).record(tr, seed=3).piezo_measured
    b = Instrument(detector=det).record(tr, seed=3).piezo_measured
    c = Instrument(detector=det).record(tr, seed=4).piezo_measured
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert np.std(a - tr.piezo_position) == pytest.approx(1e-9, rel=0.1)


@pytest.mark.parametrize("kw", [dict(gain=-1.0), dict(backlash=-1e-9), dict(step=-1e-9),
                                dict(backlash_speed=0.0), dict(noise=-1.0), dict(backlash_exponent=-1.0)])
def test_bad_detector_parameters(kw):
    with pytest.raises(ParameterError):
        PositionDetector(**kw)
