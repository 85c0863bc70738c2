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
