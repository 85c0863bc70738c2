"""A jump into contact starts free and lands in attraction; a step in contact is a slip
(`afmforce.analysis.jumps.find_jump_in`, ``attractive_below``).

Real case: the Nanosurf FlexAFM 10 x 10 map of shared/data/real (2.72 N/m lever on a hard sample in
air). On 8 of its 100 approaches the contact split (the two-line boundary) lies after a curved onset,
and the largest step within 3 samples of it is a slip in contact (e.g. curve 13: 1.06 -> 0.45 nm of
deflection): taken for the jump, it "landed at +1.2 nN" and the whole curve was refused as physically
impossible. The jump is the step from the free baseline into the attraction before that contact; here
it is read from the raw approach without afmforce's analysis: the largest downward step among the 40
samples before the force first exceeds 5 nN above the baseline.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.io import load
from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

MAP = "nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid"


@pytest.mark.parametrize("n", [13, 39, 50])
def test_a_slip_in_contact_is_not_the_jump_in(n):
    curve = load(real_file(MAP))[n]
    assert curve.deflection_unit == "N"                       # the file stores the force
    f = np.asarray(curve.deflection_signal, float)[np.asarray(curve.segment) == 0]
    f = f - np.median(f[:200])                                 # the free baseline, far from the sample
    contact = int(np.flatnonzero(f > 5e-9)[0])
    lo = contact - 40
    s = lo + int(np.argmin(np.diff(f[lo:contact])))            # the largest downward step before contact
    landing = f[s + 1]
    assert landing < -0.5e-9                                   # a real jump, into attraction
    r = analyze(curve)
    assert "impossible" not in r.verdict, r.verdict
    # within the two baselines' difference (afmforce's is a drift line in time, this one a median)
    assert r.jump_in_force == pytest.approx(landing, abs=0.5e-9), (r.jump_in_force, landing)


def _slip_run(step: float, noise: float, seed: int = 0, jump: bool = True):
    """An approach sampled by hand: a free baseline (zero force), a jump at sample 19 to -2 nm (or none: the
    tip creeps in along the line from zero force), the compliance line rising ``step`` per sample through
    zero force, and 1 nm of slip 8 samples before the end. Returns (deflection, run, the slip's index)."""
    from types import SimpleNamespace

    n, slip = 80, 71
    d = np.zeros(n)
    d[20:] = (-2e-9 if jump else 0.0) + np.arange(n - 20) * step
    d[slip + 1:] -= 1e-9
    d += noise * np.random.default_rng(seed).standard_normal(n)
    run = SimpleNamespace(index=np.arange(n), split=slip + 1, has_compliance=True, saturated=np.zeros(n, bool))
    return d, run, slip


@pytest.mark.parametrize("step", [0.08e-9, 0.13e-9, 0.2e-9])
def test_the_jump_before_a_slip_is_found_across_the_zero_crossing(step):
    """The compliance line crosses zero force in steps of ``step``: samples within +-attractive_below
    (5 noises, 0.1 nm) lie between the attraction and the contact. Before, they stopped the walk back
    from the slip, and the slip (landing at +1.5 nm and more) was taken for the jump into contact."""
    from afmforce.analysis.jumps import find_jump_in

    noise = 0.02e-9
    d, run, slip = _slip_run(step, noise)
    ab = 5 * noise
    assert np.any(np.abs(d[20:slip]) <= ab)                    # the crossing has samples in the band
    z = np.arange(d.size) * 1e-9
    ji = find_jump_in(d, z, z, run, noise, 0.1, attractive_below=ab)
    assert ji.found and ji.index == 19                          # the step built at sample 19
    assert ji.deflection_after == pytest.approx(-2e-9, abs=5 * noise)


def test_a_crept_in_contact_keeps_its_slip():
    """No attraction before the line (the tip crept in from zero force): the long free branch within the
    band is no crossing, and the slip stays the largest step, judged as before."""
    from afmforce.analysis.jumps import find_jump_in

    noise = 0.02e-9
    d, run, slip = _slip_run(0.13e-9, noise, jump=False)
    z = np.arange(d.size) * 1e-9
    ji = find_jump_in(d, z, z, run, noise, 0.1, attractive_below=5 * noise)
    assert ji.index == slip and ji.deflection_after > 5 * noise
