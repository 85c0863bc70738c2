"""The fit's jump-in is the analysis's (`afmforce.fit.preprocess`): a step in contact is a slip, not the
jump. On 8 of the 100 approaches of the Nanosurf FlexAFM map (shared/data/real; 2.72 N/m lever on a hard
sample in air) the largest step next to the contact split is a slip in contact; the analysis's jumps
step takes the step into the attraction before it, and the fit took the slip, 6-8 samples later (its
first contact sample after the jump was inside the contact). The jump is read here from the raw
approach without afmforce: the largest downward step among the 40 samples before the force first
exceeds 5 nN above the free baseline (as tests/analysis/test_jump_in_slip.py)."""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.fit.preprocess import analysis_inputs
from afmforce.io import load
from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

MAP = "nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid"


@pytest.mark.parametrize("n", [13, 50])
def test_the_fit_leaves_out_the_jump_not_a_slip(n):
    curve = load(real_file(MAP))[n]
    idx = np.flatnonzero(np.asarray(curve.segment) == 0)
    f = np.asarray(curve.deflection_signal, float)[idx]
    f = f - np.median(f[:200])
    contact = int(np.flatnonzero(f > 5e-9)[0])
    s = contact - 40 + int(np.argmin(np.diff(f[contact - 40: contact])))
    assert f[s + 1] < -0.5e-9                                   # a real jump, into attraction
    inp = analysis_inputs(curve, f"#{n}", idx)
    assert inp.jump_found and inp.jump == s + 1                 # the first sample after it
