"""A negative rupture distance that comes from the sensitivity is blamed on it (corpus5). On JSotres/FSAS'
NanoScope 8.15 force volume (MultiMode, mica in air, BSD 2-Clause; DeflSens 41.14 nm/V) the contact lines
run at 1.35-1.38 x the ramp (the deflection outruns the position: the file's sensitivity is 1.38 x the
slope's, 29.8 nm/V), so the separation runs backwards in contact and 132 of the 256 ruptures came out at
-0.02 to -9.9 nm, the warning blaming "the separation's zero or the retract's baseline". Curve 15 (the
trimmed file's second, tests/data/make_nanoscope_fv_image_grid_trimmed.py) ruptures at -3.8 nm, beyond
the drift lines' bound of 0.18 nm; the warning now names the contact line's rate and the sensitivity, and
the number is withheld (NaN: a rupture inside the compliance line beyond its uncertainty is no distance)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from afmforce.analysis.pipeline import analyze
from afmforce.io import load

TRIMMED = Path(__file__).resolve().parents[1] / "data" / \
    "bruker-nanoscope_v8.15_force-volume_64x64-scan_2x2-curves_trimmed.000"


def test_negative_rupture_on_a_backwards_contact_line_names_the_sensitivity():
    c = load(TRIMMED)[1]  # curve 15 of the 16 x 16 grid
    # independently: the retract's top 30 % of deflection against the nominal ramp (300 nm over 512 samples)
    ret = c.deflection_signal[c.retract] * 41.14015e-9     # [m] with the file's DeflSens
    z = np.abs(c.piezo_nominal[c.retract])
    top = ret > ret.max() - 0.3 * (ret.max() - np.median(ret[-100:]))
    rate = abs(np.polyfit(z[top], ret[top], 1)[0])
    assert 1.3 < rate < 1.45
    r = analyze(c)
    assert r.contact_kind == "hard" and math.isnan(r.rupture_distance)   # was -3.8 nm, reported
    assert r.rupture_distance_drift < 1e-9 and r.adhesion_force < 0       # the bound and the adhesion stay
    why = [w for w in r.warnings if w.startswith("rupture at -") and "physically impossible" in w]
    assert len(why) == 1
    assert -float(why[0].split()[2]) * 1e-9 > r.rupture_distance_drift  # the number beyond its bound, in words
    assert "not reported (rupture_distance NaN)" in why[0]
    assert "on the retract's contact line the deflection moves" in why[0] and "suspect input: sensitivity" in why[0]
    assert "the separation's zero or the retract's baseline" not in why[0]
