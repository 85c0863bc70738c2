"""Two silent wrong answers of the analysis, on virtual curves of known truth (docs/analysis.md, "The next curves").

* A piezo whose nominal position bends differently on the approach and on the retract
  (:func:`~afmforce.analysis.synthetic.static_curve`'s ``piezo_quadratic``: a quadratic bend of each run, no
  measured position). Before (the code of aab2883), with (0.02, -0.02): sensitivity 51.50 nm/V for 50, A R
  1.55 x the truth, the jump-in at 6.13 nm for 5.01, no warning; (0.0, -0.02) and (0.02, 0.0): A R 1.25 and
  1.27 x; (-0.02, 0.02): 0.60 x. The retract's line, bent over its 300 nm pull, set the zero of separation of
  the approach. Now the gap between the two lines at zero load (1.19 nm, 51 standard errors, for (0.02, -0.02);
  the intact curve on its nominal channel: 0.04 nm, 2) sends the zero to the approach's own line: A R within 3
  standard errors of the truth, the jump-in within 0.3 nm, and a warning giving the sensitivities the two lines'
  local slopes allow (the truth among them: the data cannot tell which).
* Interference fringes on the approach only: a retract cut short after its pull-off (less than a period of
  free baseline), or one without them. Before: "periodic baseline on one run only: not fringes; nothing
  changed", and at 15 nm deep (0.3 V) a sensitivity of 261 nm/V for 50 and an adhesion 5.4 x the truth. Now
  removed from the approach (the same numbers as fringes on both runs), the retract left as recorded, a warning.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from afmforce import forces
from afmforce.analysis.fringes import fit_fringes
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.steps.fringes import ALONE_RETRACT_FRACTION, approach_only
from afmforce.analysis.synthetic import static_curve
from afmforce.constants import HAMAKER, Z0

NOISE = 0.05e-9
PULL_OFF = forces.max_attraction_force(220e-9, HAMAKER, Z0)
DISAGREE = "compliance lines disagree where the tip meets the surface"
ALONE = "interference fringes on the approach only"


def _nominal_only(c):
    return dataclasses.replace(c, piezo_measured=None)


def _said(r, text):
    return [w for w in r.warnings if text in w]


# --- a piezo that bends differently on the two runs ------------------------------------------------------------

@pytest.mark.parametrize("bend", [(0.02, -0.02), (0.01, -0.01), (-0.02, 0.02), (0.0, -0.02), (0.02, 0.0)])
def test_bent_piezo_takes_the_zero_from_the_approach_and_says_so(bend):
    c = static_curve(noise=NOISE, piezo_quadratic=bend)
    assert c.piezo_measured is None
    r = analyze(c)
    (note,) = _said(r, DISAGREE)
    assert r.details["zero"].run == "approach"
    truth = c.truth["hamaker_radius"]
    assert abs(r.hamaker_radius - truth) < 3 * r.hamaker_radius_se
    j = c.truth["jump_in_index"]
    assert r.jump_in_separation == pytest.approx(c.truth["separation"][j], abs=0.3e-9)
    # the sensitivity the slope gave is not the lever's; the warning's range holds the truth and the fit
    lo, hi = map(float, re.search(r"sensitivities from ([0-9.]+) to ([0-9.]+) nm/V", note).groups())
    assert lo <= c.truth["sensitivity"] * 1e9 <= hi
    assert lo <= r.sensitivity_fit * 1e9 <= hi
    assert "the sensitivity fitted, and every force, are uncertain by that much" in note


def test_straight_nominal_position_is_not_flagged():
    """The intact curve read on its nominal channel (the same as the true position): the lines agree within
    their noise at zero load, the zero stays on the retract's line, every number as on the measured channel."""
    c = static_curve(noise=NOISE)
    measured, nominal = analyze(c), analyze(_nominal_only(c))
    assert nominal.position_channel == "nominal" and measured.position_channel == "measured"
    assert not _said(nominal, DISAGREE) and nominal.details["zero"].run == "retract"
    for name in ("sensitivity_used", "hamaker_radius", "jump_in_separation", "adhesion_force"):
        assert getattr(nominal, name) == getattr(measured, name), name


def test_measured_position_is_not_checked():
    """A sensor's position is taken as the distance (a disagreement of its runs is the contact's: friction):
    the bent curve given the bent position as its measured channel is analysed as before, no warning."""
    c = static_curve(noise=NOISE, piezo_quadratic=(0.02, -0.02))
    r = analyze(dataclasses.replace(c, piezo_measured=c.piezo_nominal))
    assert r.position_channel == "measured" and not _said(r, DISAGREE)
    assert r.details["zero"].run == "retract"


# --- fringes on the approach only ------------------------------------------------------------------------------

def _fringes_on_approach(amplitude, period=320e-9):
    """The hard curve over 1.2 um with fringes added to the approach only (its retract without any)."""
    c = static_curve(noise=NOISE, start=-1200e-9, end=-1200e-9)
    seg = np.asarray(c.segment)
    gap = c.truth["position"] - c.truth["deflection"]   # substrate-lever distance: constant in contact
    s = np.asarray(c.deflection_signal) + np.where(seg == 0, amplitude * np.cos(2 * math.pi * gap / period), 0.0)
    return dataclasses.replace(c, deflection_signal=s)


def _short_retract(amplitude):
    """Fringes on both runs, but the retract stops 120 nm after its pull-off: 0.26 of a period of baseline."""
    return static_curve(noise=NOISE, fringe_amplitude=amplitude, start=-1200e-9)


@pytest.mark.parametrize("amplitude", [0.02, 0.3])
@pytest.mark.parametrize("make", [_fringes_on_approach, _short_retract])
def test_fringes_on_the_approach_only_are_removed(make, amplitude):
    """1 and 15 nm deep (0.02, 0.3 V at 50 nm/V). The sensitivity within 0.5 %; the approach's baseline clean to
    a few noise sigmas; the jump-in at the truth's sample; the adhesion within 1 % where the retract is clean,
    within the fringes' amplitude (k x sensitivity x amplitude) where it carries their unfitted part."""
    c = make(amplitude)
    r = analyze(c)
    assert r.sensitivity_used == pytest.approx(c.truth["sensitivity"], rel=0.005)
    assert r.details["fringes"].approach.amplitude == pytest.approx(amplitude, rel=0.01)
    (note,) = _said(r, ALONE)
    seg = np.asarray(c.segment)
    j = c.truth["jump_in_index"]
    free = np.flatnonzero(seg == 0)[: j - 200]              # the approach's baseline, up to 50 nm before the jump
    err = r.deflection[free] - c.truth["deflection"][free]
    assert float(np.std(err)) < 3 * NOISE and abs(float(np.median(err))) < 3 * NOISE
    assert r.details["jumps"].jump_in.index in (j, j + 1)
    if make is _fringes_on_approach:
        assert "the retract left as recorded" in note
        assert r.adhesion_force == pytest.approx(PULL_OFF, rel=0.01)
    else:
        assert "too short to show them" in note
        k, sens = c.truth["spring_constant"], c.truth["sensitivity"]
        assert abs(r.adhesion_force - PULL_OFF) <= k * sens * amplitude


def test_same_numbers_as_fringes_on_both_runs():
    """On the approach only or on both runs, 15 nm deep: the same sensitivity and adhesion to 0.1 %."""
    both = analyze(static_curve(noise=NOISE, fringe_amplitude=0.3, start=-1200e-9, end=-1200e-9))
    alone = analyze(_fringes_on_approach(0.3))
    assert alone.sensitivity_used == pytest.approx(both.sensitivity_used, rel=1e-3)
    assert alone.adhesion_force == pytest.approx(both.adhesion_force, rel=1e-3)


def test_a_retract_showing_the_period_keeps_the_curve_as_recorded():
    """:func:`approach_only` on baselines: a retract 2 periods long holding the approach's fringes (a fit that
    did not take them: chirped, wandering) is no approach-only case; a clean one, or one too short, is."""
    rng = np.random.default_rng(3)
    period, amp = 320e-9, 0.3
    z = np.linspace(-1200e-9, -100e-9, 4000)
    fa = fit_fringes(z, amp * np.cos(2 * math.pi * z / period) + 0.001 * rng.standard_normal(z.size))
    assert fa.found and fa.amplitude == pytest.approx(amp, rel=0.01)
    zr = np.linspace(-900e-9, -260e-9, 2000)
    noise = 0.001 * rng.standard_normal(zr.size)
    held, _ = approach_only(fa, zr, 0.5 * amp * np.cos(2 * math.pi * zr / period) + noise, None)
    clean, _ = approach_only(fa, zr, noise, None)
    short, _ = approach_only(fa, zr[-300:], noise[-300:], None)
    assert held is None
    assert clean is not None and "holds" in clean
    assert short is not None and "too short to show them" in short
    faint, _ = approach_only(fa, zr, 0.5 * ALONE_RETRACT_FRACTION * amp * np.cos(2 * math.pi * zr / period) + noise,
                             None)
    assert faint is not None


def _line_run(kind, start, z, s):
    """A run whose every sample lies on its compliance line (a RunRegions over indices start..)."""
    from afmforce.analysis.regions import RunRegions

    n = z.size
    yes, no = np.ones(n, bool), np.zeros(n, bool)
    return RunRegions(kind=kind, index=np.arange(start, start + n), split=0, contact=yes, zero_force=no,
                      compliance=yes, saturated=no, noise=0.0, has_compliance=True, note="", reason="")


def test_gap_of_two_lines_is_their_offset_at_zero_load():
    """Closed form: two straight lines of the same slope, the retract's ``delta`` further along z, are ``delta``
    apart at zero load, with no bend; one line for both runs is no gap; a line that does not move gives none."""
    from afmforce.analysis.position_bend import position_bend

    rng = np.random.default_rng(5)
    sens, delta, n = 50e-9, 0.8e-9, 400
    z = np.linspace(-2e-9, 30e-9, n)
    noise = lambda: 0.002 * rng.standard_normal(n)      # noqa: E731  (0.1 nm at 50 nm/V)
    za, zr = z, z[::-1]
    s = np.concatenate([za / sens + noise(), (zr - delta) / sens + noise()])
    zz = np.concatenate([za, zr])
    b = position_bend(zz, s, _line_run("approach", 0, za, s[:n]), _line_run("retract", n, zr, s[n:]))
    assert b.gap == pytest.approx(delta, abs=3 * b.gap_se) and b.gap_se < 0.05e-9
    assert abs(b.approach) < 0.01 and abs(b.retract) < 0.01 and b.detected
    lo, hi = b.slopes
    assert lo < 1 / sens < hi
    s0 = np.concatenate([za / sens + noise(), zr / sens + noise()])
    same = position_bend(zz, s0, _line_run("approach", 0, za, s0[:n]), _line_run("retract", n, zr, s0[n:]))
    assert abs(same.gap) < 4 * same.gap_se and not same.detected
    flat = np.full(n, 1e-9)
    assert position_bend(np.concatenate([flat, zr]), s0, _line_run("approach", 0, flat, s0[:n]),
                         _line_run("retract", n, zr, s0[n:])) is None
