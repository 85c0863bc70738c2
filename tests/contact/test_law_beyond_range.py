"""A law fitted beyond its range has no interval: E (and an adhesive law's w) is undetermined, [0, open].

A sphere's force grows as the Hertz law (F = 4/3 E* sqrt(R) delta^1.5) only while delta << R; a sphere pressed
deeper than its radius is a cylinder pressing (F ~ 2 E* R delta, Sneddon's flat punch for delta >> R). Fitting
Hertz to such a curve finds a best match whose covariance interval is the noise's alone: before, a tight
interval (a few %) around a modulus off the truth by a systematic factor; now E is reported undetermined with
the warning giving the match and the interval it would have claimed. Within the range nothing changes: the
interval holds the truth (closed form).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.contact.fit import fit_indentation, model_force, out_of_range

R, NU, E = 1e-6, 0.5, 5e3   # [m], [-], [Pa]
ESTAR = E / (1 - NU**2)


def _curve(depth_max, law, seed=0):
    rng = np.random.default_rng(seed)
    u = np.linspace(-0.5 * depth_max, depth_max, 600)     # position past the contact point at 0 [m]
    d = np.clip(u, 0, None)
    F = law(d) + 2e-12 * rng.standard_normal(u.size)     # 2 pN noise [N]
    return u, F


def test_within_range_interval_holds_the_truth():
    u, F = _curve(0.5 * R, lambda d: model_force("hertz_paraboloid", d, E, {"radius": R}, NU))
    fit = fit_indentation(u, F, "hertz_paraboloid", {"radius": R}, nu=NU)
    assert not out_of_range("hertz_paraboloid", {"radius": R}, fit.max_indentation)
    assert fit.youngs_modulus_low < E < fit.youngs_modulus_high
    assert not any("undetermined" in w for w in fit.warnings)


def test_adhesive_law_beyond_range_w_undetermined():
    from afmforce.contact import adhesive

    geom = {"radius": 50e-9}
    u = np.linspace(-100e-9, 300e-9, 400)      # 300 nm into a 50 nm tip: 6 R
    F = np.asarray(adhesive.adhesive_force("jkr", np.clip(u, 0, None), E, 1e-4, geom["radius"], NU, 1.0,
                                           "approach"))
    F = F + 1e-12 * np.random.default_rng(1).standard_normal(u.size)
    fit = fit_indentation(u, F, "jkr", geom, nu=NU)
    assert fit.youngs_modulus_low == 0.0 and math.isnan(fit.youngs_modulus_high)
    assert fit.work_of_adhesion_low == 0.0 and math.isnan(fit.work_of_adhesion_high)
    assert not any("not distinguishable from 0" in w for w in fit.warnings)
