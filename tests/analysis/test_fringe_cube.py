"""fringes._cube: a map of order 1 or 2 (a3 = 0) skips x**3 (numpy's pow) with the same numbers (issue 35)."""

from __future__ import annotations

import math

import numpy as np

from afmforce.analysis.fringes import FringeRun, _design, position_map


def _design_pow(z, zm, L, P, c1, a2, a3):
    x = (z - zm) / L
    u = zm + c1 * L * (x + a2 * x**2 + a3 * x**3)
    th = 2 * math.pi * u / P
    return np.column_stack([np.cos(th), np.sin(th), np.ones_like(x), x]), x, u


def _map_pow(z, fr):
    x = (np.asarray(z, float) - fr.z_mid) / fr.half_range
    xc = np.clip(x, -1.5, 1.5)
    poly = xc + fr.a2 * xc**2 + fr.a3 * xc**3
    slope = 1.0 + 2 * fr.a2 * xc + 3 * fr.a3 * xc**2
    return fr.z_mid + fr.scale * fr.half_range * (poly + slope * (x - xc))


def test_design_and_map_without_pow_are_bitwise_equal():
    rng = np.random.default_rng(35)
    for trial in range(3000):
        n = int(rng.integers(2, 200))
        z = rng.normal(size=n) * 10 ** rng.uniform(-9, -3) + rng.choice([0.0, 1e-6, -3e-5])
        if trial % 3 == 0:
            z = np.round(z, 9)                                   # repeated positions
        if trial % 5 == 0:
            z[rng.integers(0, n)] = 0.5 * (z.max() + z.min())   # x exactly 0: signed zeros
        if trial % 17 == 0:
            z[0] = np.nan
        zm, L = 0.5 * (z.max() + z.min()), 0.5 * float(z.max() - z.min()) or 1.0
        if trial % 7 == 0:
            zm = 0.0
        a2 = float(rng.choice([0.0, -0.0, rng.normal() * 0.1]))
        for a3 in (0.0, -0.0, float(rng.normal() * 0.05)):
            P, c1 = abs(rng.normal()) * 1e-7 + 1e-9, float(rng.choice([1.0, rng.uniform(0.5, 2)]))
            with np.errstate(all="ignore"):
                for got, want in zip(_design(z, zm, L, P, c1, a2, a3), _design_pow(z, zm, L, P, c1, a2, a3)):
                    assert got.tobytes() == want.tobytes(), trial
                fr = FringeRun(True, P, 1.0, 0.3, c1, a2, a3, zm, L, 0.0, 0.5, 3.0, 0.1)
                far = z * float(rng.choice([1.0, 3.0, -2.0]))     # beyond the fitted range too (the clip)
                assert position_map(far, fr).tobytes() == _map_pow(far, fr).tobytes(), trial
