"""A fringe fit whose position map turns back is not fringes (issue 32, item 3: every real file).

Curve 229 of the real v9.2 force volume (shared/data/real) has a slow wobble on its approach baseline
that a cubic map u(x) = x + a2 x^2 + a3 x^3 with a2 = -0.225, a3 = -0.652 "explained" (36 % of the
variance, 1.17 periods); du/dx = 1 + 2 a2 x + 3 a3 x^2 is -1.41 at x = 1, so the remapped approach ran
from +255 nm to -2237 nm while the piezo went 2 nm -> 2000 nm: the soft contact point then fell
before the first sample and the whole curve failed. A piezo moves one way while its drive does.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis.fringes import monotonic_map, position_map, FringeRun
from afmforce.analysis.pipeline import analyze
from afmforce.io import load
from realdata import real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)


@pytest.mark.parametrize("c1, a2, a3, increasing", [
    (1.0, 0.0, 0.0, True),
    (1.0, 0.05, 0.02, True),  # a few per cent of piezo nonlinearity
    (1.0, -0.225, -0.652, False),  # the fit on curve 229
    (1.0, 0.0, -0.3, False),  # 1 - 0.9 x^2 < 0 beyond |x| = 1.05
    (-1.0, 0.0, 0.0, False),  # a reversed position
])
def test_monotonic_map_against_its_derivative(c1, a2, a3, increasing):
    assert monotonic_map(c1, a2, a3) is increasing
    # the same answer from position_map itself, sampled over the reach it uses
    fr = FringeRun(True, 500e-9, 1e-3, 0.0, c1, a2, a3, 0.0, 1e-6, 0.0, 0.5, 2.0, 0.0, 0.0, 0.0, 0.0, "time")
    u = position_map(np.linspace(-1.5e-6, 1.5e-6, 3001), fr)
    assert bool(np.all(np.diff(u) > 0)) is increasing


def test_force_volume_curve_with_a_wobbling_baseline_is_analysed():
    c = load(real_file("bruker-nanoscope_force-volume_v9.2_Egel.spm"))[229]
    r = analyze(c)
    z = c.piezo_nominal[c.approach]
    assert not r.details["fringes"].applied
    assert z.min() <= r.contact_point <= z.max()  # the contact point lies inside the data
    assert 1e3 < r.youngs_modulus < 1e6  # a hydrogel: kPa to hundreds of kPa (its neighbours: 52-172 kPa)
    assert r.adhesion_force < 0
