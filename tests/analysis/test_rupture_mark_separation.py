"""The figure's "last rupture" line stands where the rupture is on the separation axis (review of 2026-11-29).

A soft contact's ``rupture_distance`` counts along the retract's travel from where it leaves its contact; the
force-separation panel drew it at that number on the separation axis: on the PicoForce colloid (kontrkulka) the
last unbinding step lies at h = 84.5 nm, its line stood at h = 123 nm on the flat baseline. Reference: the
separation of the step's own sample (the unbinding step's marker), independent of the travel.
"""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from afmforce.analysis.pipeline import analyze
from afmforce.io import load
from afmforce.plotting.curves import _rupture_separation, plot_force_separation
from realdata import real_file

DATA = __import__("pathlib").Path(__file__).resolve().parents[1] / "data"


def _line_x(result) -> float:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    plot_force_separation(result, ax=ax)
    xs = [ln.get_xdata()[0] for ln in ax.get_lines() if str(ln.get_label()).startswith("last rupture")]
    plt.close(fig)
    assert len(xs) == 1
    return float(xs[0]) * 1e-9


def test_the_line_is_drawn_at_the_last_steps_separation_on_the_real_colloid():
    path = real_file("bruker-nanoscope_v6.13_PicoForce_matfiz_kontrkulka00000.000")
    r = analyze(load(path)[0])
    ad = r.details["adhesion"]
    last = [s for s in ad.steps if abs(s.distance - ad.rupture_distance) < 1e-15]
    assert len(last) == 1                                   # the rupture is the last step (a gradual return after it)
    step_h = float(r.separation[last[0].index])
    assert _line_x(r) == pytest.approx(step_h, abs=1e-12)
    assert abs(step_h - ad.rupture_distance) > 20e-9        # the number itself is a travel, 38 nm off


def test_a_return_rupture_lies_beyond_the_last_step_by_the_travel_between_them():
    r = analyze(load(DATA / "jpk_cellhesion_spot3.jpk-force")[0])
    ad = r.details["adhesion"]
    assert math.isfinite(ad.rupture_distance) and ad.steps
    s = max(ad.steps, key=lambda s: s.distance)
    assert s.distance < ad.rupture_distance                 # the return, after the last step, is the rupture
    at, step_h = _line_x(r), float(r.separation[s.index])
    travel = ad.rupture_distance - s.distance
    # the separation grows by the travel plus the lever's relaxation from the step's deflection (<= the dip's)
    assert step_h + travel - 1e-9 <= at <= step_h + travel + abs(ad.deflection) + 1e-9
    assert np.isfinite(at)
