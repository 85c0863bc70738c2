"""A piezo hysteresis loop that closes at the turn, on a hard contact (docs/analysis.md, "Caught since").

The virtual AFM's ``Piezo(hysteresis=h)`` (1 um span) on the round-trip spring curve (190 nm from a rest to the
turn, nominal position only, the file's sensitivity 50 nm/V): every play of the operator stays in its dead band,
so the nominal position is the true one times 1 / (1 - h) on both runs near the turn. Both compliance lines are
straight and coincide, so :mod:`~afmforce.analysis.position_bend` sees nothing; the slope gives the piezo's
local gain (1.02, 1.05, 1.11 x the sensitivity for h = 2, 5, 10 %) and A R came out 1.07, 1.15, 1.33 x the truth,
said nowhere below the 10 % of the slope's warning. On the nominal channel the slope's factor is now said when
it is beyond 1 % and 5 standard errors, with what it does to the separations and A R.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

pytest.importorskip("afmforce.instrument")

from afmforce.instrument import Piezo  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from test_roundtrip_virtual_afm import S, _run  # noqa: E402  (the round-trip curve and its instrument)

SAID = "on the piezo's nominal position (no position sensor)"


def _said(res):
    return [w for w in res.warnings if SAID in w]


@pytest.mark.parametrize("h", [0.02, 0.05])
def test_a_loop_that_closes_at_the_turn_is_said_with_its_factor(h):
    tr, cfg, raw, res = _run(1e-6, {"piezo": Piezo(hysteresis=h, hysteresis_span=1e-6), "detector": None})
    assert res.position_channel == "nominal" and res.calibration_source == "metadata"
    gain = res.sensitivity_fit / S                       # the piezo's local gain the slope carries: 1 / (1 - h)
    assert gain == pytest.approx(1 / (1 - h), rel=0.01)
    (w,) = _said(res)
    factor = float(re.search(r"calibration ([0-9.]+) x the file's", w).group(1))
    assert factor == pytest.approx(gain, rel=0.005)
    ar = res.hamaker_radius / (5e-19 * cfg["radius"])    # eq 2's A R of the trajectory
    scale = float(re.search(r"A R by about ([0-9.]+) x", w).group(1))
    assert ar > 1 + 2 * (res.hamaker_radius_se / (5e-19 * cfg["radius"])) or h < 0.05   # biased past its se
    assert scale == pytest.approx(gain ** 2, rel=0.01)


def test_a_linear_piezo_says_nothing():
    tr, cfg, raw, res = _run(1e-6, {"piezo": Piezo(), "detector": None})
    assert res.position_channel == "nominal" and not _said(res)
