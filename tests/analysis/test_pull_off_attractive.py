"""A pull-off is an attraction: a retract that leaves its compliance line at a repulsive load is not
pulling off (`afmforce.analysis.jumps.find_pull_off`, ``attractive_below``).

Real case: curve 1 of the trimmed Nanosurf map (tests/data): the retract leaves the compliance line at
+34.8 nN (friction/hysteresis in contact), comes down to a -7.5 nN adhesion dip and then rises off the
surface. Before the fix the jumps step took the +34.8 nN departure for the pull-off and refused the whole
curve as physically impossible; the pull-off is the dip, read here from the file's raw retract block
(its far end is its baseline) independently of afmforce's analysis.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from afmforce.analysis.pipeline import analyze
from afmforce.io import load

MAP = Path(__file__).resolve().parents[1] / "data" / "nanosurf-nid_spectroscopy-map_2x2_trimmed.nid"


def test_pull_off_is_the_adhesion_dip_not_a_repulsive_departure():
    curve = load(MAP)[1]
    res = analyze(curve)
    assert "impossible" not in res.verdict, res.verdict
    ret = np.asarray(curve.deflection_signal, float)[np.asarray(curve.segment) == 1]
    assert curve.deflection_unit == "N"                  # this file stores the force itself
    dip = float(np.median(ret[-200:]) - ret.min())         # [N]; the retract ends far from the surface
    assert res.pull_off_force < 0
    assert abs(abs(res.pull_off_force) - dip) < 1e-9, (res.pull_off_force, dip)
    assert res.pull_off_force == res.adhesion_force or abs(res.pull_off_force - res.adhesion_force) < 1e-12

