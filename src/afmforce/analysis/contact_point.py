"""Contact point of a soft (curved) contact, and the contact kind of a curve.

Contact kinds (:func:`classify_contact`):

* ``"hard"``: a significant jump into contact, or a straight constant-compliance
  line (the deflection follows the position one to one once in contact): the
  paper's recipe applies (compliance lines, shift, zero of separation on the
  line, jump-in, pull-off, van der Waals fit, friction signature).
* ``"soft"``: no jump, and a contact that curves (the slope keeps growing with
  the load) or is much shallower than the deflection can follow: a sample that
  the tip indents. The zero of separation is the contact point found by
  :func:`soft_contact_point`; pull-off, van der Waals fit and friction signature
  do not apply.
* ``"none"``: the approach never reaches the surface (decided by the contact step).

Soft contact point (:func:`soft_contact_point`, method ``"hertz_local"``): the
approach up to its largest deflection, cut where the deflection reaches
``force_fraction`` (0.55) of its range (the start of the indentation, where the shape
of the indenter matters least), block-averaged to at most ``max_points``
points, is fitted by a baseline line plus a Hertz term,
``d = a + b z + c (z - z_c)_+^{3/2}`` (c >= 0), for every ``z_c`` on a grid of
``grid`` points within ``window`` (fraction of the run) of the Frechet
direct-path point (the point farthest below the straight line from the first
to the last sample: nanite's initial guess); for each ``z_c`` the fit is
linear, so the search is exhaustive and deterministic. The contact point is the
``z_c`` of least squares. On the shared real soft curves it agrees with
nanite's ``fit_line_polynomial`` within 30 nm or 10 % of the indentation
(``tests/analysis/test_contact_kinds.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import ParameterError
from ._units import unit as _u
from .options import KindOptions as _K  # the defaults: declared once, in the step's record

__all__ = ["ContactKind", "SoftContactPoint", "classify_contact", "soft_contact_point", "CONTACT_POINT_METHODS"]


@dataclass(frozen=True)
class SoftContactPoint:
    """Contact point of a soft contact.

    Attributes
    ----------
    method : str
    index : int  sample of the curve at (just before) the contact point [-]
    position : float  z at the contact point [m]
    deflection : float  baseline deflection there [m]
    initial_position : float  Frechet direct-path guess [m]
    indentation : float  z travel after contact less the deflection rise, at the turning point [m]
    exponent : float  of the contact term [-]
    """

    method: str
    index: int = _u("")
    position: float = _u("m")
    deflection: float = _u("m")
    initial_position: float = _u("m")
    indentation: float = _u("m")
    exponent: float = _u("")


def _block(x: np.ndarray, n: int) -> np.ndarray:
    m = x.size // n
    if m <= 1:
        return x
    k = x.size // m
    return x[:k * m].reshape(k, m).mean(1)


@njit(cache=True)
def _fit_grid(x: np.ndarray, y: np.ndarray, cands: np.ndarray, exponent: float) -> tuple[np.ndarray, np.ndarray]:
    """Least squares of ``y = a + b x + c (x - x_c)_+^p`` for each candidate ``x_c``: coefficients, residual sums
    (infinite where c <= 0). Normal equations per candidate (compiled loops)."""
    n = x.size
    sx = sxx = sy = sxy = syy = 0.0
    for i in range(n):
        sx += x[i]
        sxx += x[i] * x[i]
        sy += y[i]
        sxy += x[i] * y[i]
        syy += y[i] * y[i]
    coef = np.empty((cands.size, 3))
    rss = np.empty(cands.size)
    m = np.empty((3, 3))
    v = np.empty(3)
    for k in range(cands.size):
        sg = sgg = sxg = syg = 0.0
        for i in range(n):
            u = x[i] - cands[k]
            if u > 0.0:
                g = u ** exponent
                sg += g
                sgg += g * g
                sxg += g * x[i]
                syg += g * y[i]
        m[0, 0], m[0, 1], m[0, 2] = n + 1e-12, sx, sg
        m[1, 0], m[1, 1], m[1, 2] = sx, sxx + 1e-12, sxg
        m[2, 0], m[2, 1], m[2, 2] = sg, sxg, sgg + 1e-12
        v[0], v[1], v[2] = sy, sxy, syg
        c = np.linalg.solve(m, v)
        coef[k, 0], coef[k, 1], coef[k, 2] = c[0], c[1], c[2]
        r = syy - (c[0] * v[0] + c[1] * v[1] + c[2] * v[2])
        rss[k] = r if c[2] > 0 else np.inf
    return coef, rss


def soft_contact_point(z: np.ndarray, d: np.ndarray, index: np.ndarray, *, exponent: float = 1.5,
                       force_fraction: float = 0.55, window: float = 0.15, grid: int = 121,
                       max_points: int = 500) -> SoftContactPoint:
    """Contact point of the approach run ``index`` (time order) by the Hertz-local method.

    Parameters
    ----------
    z, d : ndarray
        Position [m] and deflection [m] (any linear signal works) of the whole curve.
    index : ndarray of int
        The approach run's samples, time order.
    exponent : float
        Power of the contact term [-] (3/2: Hertz, sphere or paraboloid).
    force_fraction : float
        Fit up to where the deflection reaches this fraction of its range [-].
    window : float
        Half-width of the search around the Frechet point, as a fraction of the run [-].
    grid : int
        Candidate contact points [-].
    max_points : int
        Block-average the run to at most this many points [-].
    """
    if not (0 < force_fraction <= 1 and 0 < window <= 1 and grid >= 3 and exponent > 1):
        raise ParameterError("contact point: force_fraction and window in (0, 1], grid >= 3, exponent > 1")
    zi, di = z[index], d[index]
    imax = int(np.argmax(di))
    if imax < 8:
        nan = math.nan
        return SoftContactPoint("hertz_local", -1, nan, nan, nan, nan, exponent)
    zr, dr = zi[: imax + 1], di[: imax + 1]
    above = np.flatnonzero(dr - dr.min() > force_fraction * np.ptp(dr))
    cut = int(above[0]) + 1 if above.size and above[0] > 8 else dr.size
    zb, db = _block(zr[:cut], max_points), _block(dr[:cut], max_points)
    span = zb[-1] - zb[0]
    if not span > 0:
        nan = math.nan
        return SoftContactPoint("hertz_local", -1, nan, nan, nan, nan, exponent)
    x = (zb - zb[0]) / span
    y = (db - db.min()) / max(np.ptp(db), 1e-300)
    straight = np.linspace(0.0, 1.0, x.size)
    x_init = float(x[int(np.argmin(y - straight))])
    cands = np.linspace(max(x_init - window, 0.0), min(x_init + window, 1.0), grid)
    coef, rss = _fit_grid(x, y, cands, exponent)
    j = int(np.argmin(rss))
    step = cands[1] - cands[0]  # refine: a finer grid over the neighbouring cells
    cands = np.linspace(max(cands[j] - step, 0.0), min(cands[j] + step, 1.0), 41)
    coef, rss = _fit_grid(x, y, cands, exponent)
    j = int(np.argmin(rss))
    zc = float(zb[0] + cands[j] * span)
    k = int(np.searchsorted(zr, zc)) if np.all(np.diff(zr) >= 0) else int(np.argmin(np.abs(zr - zc)))
    k = min(max(k - 1, 0), zr.size - 1)
    a, b = coef[j, 0], coef[j, 1]
    d_c = float(db.min() + (a + b * cands[j]) * np.ptp(db))
    indentation = float((zi[imax] - zc) - (di[imax] - d_c))
    return SoftContactPoint("hertz_local", int(index[k]), zc, d_c, float(zb[0] + x_init * span), indentation,
                            float(exponent))


#: Registered soft-contact-point methods (identifier -> function).
CONTACT_POINT_METHODS = {"hertz_local": soft_contact_point}


@dataclass(frozen=True)
class ContactKind:
    """What kind of contact the curve shows, and why.

    Attributes
    ----------
    kind : str  ``"hard"``, ``"soft"`` or ``"none"``
    reason : str  the evidence, in words with its numbers
    jump_significance : float  largest step near contact / step noise [-]
    stiffness_ratio : float
        Deflection per position on the approach's contact line [-] (about 1 on a
        rigid sample with a correct calibration; NaN when the calibration came
        from that very slope)
    curvature_ratio : float
        Slope of the contact's last third over its first third [-] (1: straight)
    """

    kind: str
    reason: str
    jump_significance: float = _u("")
    stiffness_ratio: float = _u("")
    curvature_ratio: float = _u("")


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    if x.size < 3 or np.ptp(x) == 0:
        return math.nan
    return float(np.polyfit(x - x.mean(), y, 1)[0])


def curvature_ratio(z: np.ndarray, d: np.ndarray, contact: np.ndarray, min_points: int = 30) -> float:
    """Slope of the last third of a contact region over the slope of its first third [-].

    NaN with fewer than ``min_points`` contact samples (too few to see a curvature).
    """
    if contact.size < min_points:
        return math.nan
    order = contact[np.argsort(z[contact], kind="stable")]
    n3 = order.size // 3
    early, late = _slope(z[order[:n3]], d[order[:n3]]), _slope(z[order[-n3:]], d[order[-n3:]])
    if not (math.isfinite(early) and math.isfinite(late)) or late <= 0:
        return math.nan
    return late / early if early > 0 else math.inf


def classify_contact(*, jump_significance: float, stiffness_ratio: float, curvature: float,
                     nsigma: float = _K.nsigma, min_stiffness: float = _K.min_stiffness,
                     max_curvature: float = _K.max_curvature) -> ContactKind:
    """Hard (jump-in, or a straight line the deflection follows) or soft (curved or shallow).

    Parameters
    ----------
    jump_significance : float  [-]
    stiffness_ratio : float  deflection per position in contact [-] (NaN: unknown)
    curvature : float  late / early contact slope [-]
    nsigma : float  a jump counts above this significance [-]
    min_stiffness : float  below: the tip indents the sample [-]
    max_curvature : float  above: the contact curves [-]
    """
    if math.isfinite(jump_significance) and jump_significance > nsigma:
        return ContactKind("hard", f"jump into contact ({jump_significance:.3g} x the step noise)",
                           jump_significance, stiffness_ratio, curvature)
    words = []
    soft = False
    if math.isfinite(curvature) and curvature > max_curvature:
        soft = True
        words.append(f"the contact stiffens with load (slope ratio late/early {curvature:.3g} > {max_curvature:g})")
    if math.isfinite(stiffness_ratio) and stiffness_ratio < min_stiffness:
        soft = True
        words.append(f"the deflection follows only {stiffness_ratio:.3g} of the position in contact "
                     f"(< {min_stiffness:g}): the tip indents the sample")
    if soft:
        return ContactKind("soft", "no jump into contact; " + "; ".join(words), jump_significance,
                           stiffness_ratio, curvature)
    s = f", deflection per position {stiffness_ratio:.3g}" if math.isfinite(stiffness_ratio) else ""
    if not math.isfinite(curvature):
        return ContactKind("hard", f"no jump into contact; too few contact samples to see a curvature{s}: "
                           "taken as a hard contact (a calibration curve)", jump_significance, stiffness_ratio,
                           curvature)
    return ContactKind("hard", f"no jump into contact, but a straight contact line (slope ratio late/early "
                       f"{curvature:.3g}{s})", jump_significance, stiffness_ratio, curvature)
