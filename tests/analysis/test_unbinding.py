"""Unbinding steps of the retract (issue 24): a hard contact's pull-off jump is the end of the dip, not a step.

Synthetic retracts with known steps (heights and positions by construction), then the real files: the
Asylum SiN curve in air (hard contact, one pull-off jump and the lever settling after it) has none;
the JPK cell curves keep theirs.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis.regions import RunRegions
from afmforce.analysis.unbinding import retract_adhesion

NM = 1e-9


def _retract(levels, edges, tail=None, seed=0):
    """A retract 1 nm per sample from +50 nm (in contact) to -1050 nm: a line down to the deepest point
    at -20 nm, then the deflection ``levels[i]`` [nm] from ``edges[i]`` [nm from contact] on; ``tail``:
    an exponential settling [nm, samples] added after the last edge. Noise 0.1 nm."""
    x = np.arange(50.0, -1050.0, -1.0) * NM  # position from contact [m], negative away from the sample
    d = np.where(x > -20 * NM, x, -20 * NM)  # in contact: deflection follows the position; the dip at -20 nm
    for level, edge in zip(levels, edges):
        d = np.where(x <= -edge * NM, level * NM, d)
    if tail is not None:
        amp, tau = tail
        after = np.clip((-x / NM - edges[-1]), 0, None)
        d = d + np.where(x <= -edges[-1] * NM, -amp * NM * np.exp(-after / tau), 0.0)
    d = d + 0.1 * NM * np.random.default_rng(seed).standard_normal(x.size)
    n = x.size
    run = RunRegions("retract", np.arange(n), int(np.argmax(x <= -20 * NM)), x > 0, x < -500 * NM,
                     x > 10 * NM, np.zeros(n, bool), 0.1 * NM)
    return d, x, run


def test_tethers_give_one_step_each_at_their_position_and_height():
    d, x, run = _retract([-12.0, -5.0, 0.0], [100.0, 200.0, 300.0])
    res = retract_adhesion(d, x, run, 0.02)
    assert res.found and res.force == pytest.approx(-20 * NM * 0.02, rel=0.05)
    assert [s.distance / NM for s in res.steps] == pytest.approx([100, 200, 300], abs=2)
    assert [s.force / (0.02 * NM) for s in res.steps] == pytest.approx([8, 7, 5], abs=0.5)
    assert res.rupture_distance == pytest.approx(300 * NM, abs=2 * NM)


def test_a_pull_off_jump_with_its_settling_tail_is_not_a_step():
    # the dip ends in one jump at 21 nm to -2 nm, settling to zero over a few samples (the Asylum curve's shape)
    d, x, run = _retract([0.0], [21.0], tail=(2.0, 1.5))
    pull_off = int(np.argmax(x <= -20 * NM))  # the last sample in contact, as the jumps step gives it
    assert len(retract_adhesion(d, x, run, 0.25).steps) == 1  # without the pull-off: counted as one step
    res = retract_adhesion(d, x, run, 0.25, pull_off=pull_off)
    assert res.found and res.steps == () and "0 unbinding step(s)" in res.verdict
    assert res.rupture_distance == pytest.approx(21 * NM, abs=4 * NM)
    # tethers after the pull-off of a first contact stay steps: only the rise containing the pull-off goes
    d, x, run = _retract([-12.0, -5.0, 0.0], [100.0, 200.0, 300.0])
    res = retract_adhesion(d, x, run, 0.02, pull_off=int(np.argmax(x <= -100 * NM)) - 1)
    assert [s.distance / NM for s in res.steps] == pytest.approx([200, 300], abs=2)
