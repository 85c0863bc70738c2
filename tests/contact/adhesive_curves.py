"""Synthetic adhesive indentation curves from an independent solver of the contact laws.

The forces come from the published equations solved here, in SI or in a different unknown
than the fit uses, with a tight bracketing root finder (scipy's brentq), never from
:mod:`afmforce.contact.adhesive`:

* JKR (Johnson, Kendall & Roberts 1971): ``delta = a^2/R - sqrt(2 pi w a / E*)``,
  ``F = 4 E* a^3 / (3 R) - sqrt(8 pi w E* a^3)``, the contact radius ``a`` the largest root
  (the stable branch), solved in metres.
* DMT: ``F = 4/3 E* sqrt(R) delta^1.5 - 2 pi w R``.
* Maugis-Dugdale (Maugis 1992; Johnson & Greenwood 1997, with ``lambda``): for a given
  dimensionless indentation D the second equation gives ``m`` from A,
  ``sqrt(m^2 - 1) = 3 (A^2 - D) / (4 lambda A)``, and the first equation is solved for A (the
  largest root); afmforce instead solves for m.

Used by tests/contact/test_adhesive_fit.py and benchmarks/bench_adhesive.py.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

E_TRUE, W_TRUE, R_TIP, NU, LAM = 2e3, 1e-4, 5e-6, 0.5, 1.0  # Pa, J/m^2, m, -, -
NOISE = 2e-11  # N


def _estar(E, nu):
    return E / (1 - nu * nu)


def jkr_force(delta, E, w, R, nu=NU, retract=False):
    """JKR force [N] on the approach (0 for delta <= 0; ``retract``: the neck down to the branch's
    smallest indentation, 0 past it), a by brentq in metres (rtol 1e-15)."""
    es = _estar(E, nu)
    a_star = (math.pi * w * R * R / (8 * es)) ** (1 / 3)  # d delta / d a = 0: the branch's minimum

    def dl(a, d):
        return a * a / R - math.sqrt(2 * math.pi * w * a / es) - d

    d_min = dl(a_star, 0.0)
    out = np.zeros(np.shape(delta))
    for i, d in enumerate(np.ravel(delta)):
        if d <= 0 and not (retract and d >= d_min):
            continue
        hi = 2 * a_star + math.sqrt(R * max(d, 0.0))
        while dl(hi, d) <= 0:
            hi *= 2
        a = a_star if d == d_min else brentq(dl, a_star, hi, args=(d,), xtol=1e-30, rtol=1e-15, maxiter=500)
        out.flat[i] = 4 * es * a ** 3 / (3 * R) - math.sqrt(8 * math.pi * w * es * a ** 3)
    return out


def dmt_force(delta, E, w, R, nu=NU):
    """DMT force [N] on the approach."""
    d = np.asarray(delta, float)
    return np.where(d > 0, 4 / 3 * _estar(E, nu) * math.sqrt(R) * np.maximum(d, 0) ** 1.5 - 2 * math.pi * w * R,
                    0.0)


def _maugis_g(A, D, lam):
    """Maugis's first equation minus 1 at contact radius A, with m from the second at indentation D."""
    t = 3 * (A * A - D) / (4 * lam * A)  # sqrt(m^2 - 1)
    m2 = 1 + t * t
    at = np.arctan(t)
    return (lam * A * A / 2 * (t + (m2 - 2) * at) + 4 * lam * lam * A / 3 * (t * at - np.sqrt(m2) + 1)
            - 1)


def maugis_dimensionless_force(D, lam):
    """P at dimensionless indentation D >= 0: the largest root A of Maugis's equations (brentq)."""
    a_lo = math.sqrt(max(D, 0.0)) * (1 + 1e-15) + 1e-300  # t >= 0 needs A >= sqrt(D)
    grid = a_lo + np.geomspace(1e-9, 1e3, 4000) * max(1.0, a_lo)
    g = _maugis_g(grid, D, lam)
    k = np.flatnonzero((g[:-1] < 0) & (g[1:] >= 0))
    if k.size == 0:
        raise RuntimeError(f"no Maugis root at D = {D}")
    k = k[-1]
    A = brentq(lambda a: float(_maugis_g(a, D, lam)), grid[k], grid[k + 1], xtol=1e-300, rtol=1e-15, maxiter=500)
    t = 3 * (A * A - D) / (4 * lam * A)
    return A ** 3 - lam * A * A * (t + (1 + t * t) * math.atan(t))


def maugis_force(delta, E, w, R, nu=NU, lam=LAM):
    """Maugis-Dugdale force [N] on the approach: scales pi w R and (pi^2 w^2 R / K^2)^(1/3), K = 4/3 E*."""
    K = 4 / 3 * _estar(E, nu)
    fs, ds = math.pi * w * R, (math.pi ** 2 * w * w * R / (K * K)) ** (1 / 3)
    out = np.zeros(np.shape(delta))
    for i, d in enumerate(np.ravel(delta)):
        if d > 0:
            out.flat[i] = fs * maugis_dimensionless_force(d / ds, lam)
    return out


LAWS = {"jkr": jkr_force, "dmt": dmt_force, "maugis": maugis_force}


def curve(law: str, seed: int, n: int = 300, E: float = E_TRUE, w: float = W_TRUE, noise: float = NOISE):
    """One approach: tip depth u [m] over 3.5 um, force [N] = law(u - c) + b + noise.

    The contact point c (uniform in 0.2-0.4 um, off any grid) and the baseline b (normal, 0.1 nN)
    are drawn per seed. Returns ``(u, F, truth)`` with truth = dict(E, w, c, b).
    """
    rng = np.random.default_rng(1000 + seed)
    c = float(rng.uniform(0.2e-6, 0.4e-6))
    b = float(rng.normal(0.0, 1e-10))
    u = np.linspace(-2e-6, 1.5e-6, n)
    F = LAWS[law](u - c, E, w, R_TIP) + b + rng.normal(0.0, noise, n)
    return u, F, {"E": E, "w": w, "c": c, "b": b}
