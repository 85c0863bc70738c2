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

Soft contact point (:func:`soft_contact_point`, method ``"power_local"``): the
approach is block-averaged to at most ``max_points`` points (so that noise
cannot decide where it ends or where the fit stops), taken up to its largest
(averaged) deflection and cut where that deflection first reaches
``force_fraction`` (0.65) of its range (the start of the indentation, where the
shape of the indenter matters least). It is fitted by a baseline line plus a
power-law contact term, ``d = a + b z + c (z - z_c)_+^p`` (c >= 0), for every
``z_c`` on a grid of ``grid`` points within ``window`` (fraction of the run) of
the Frechet direct-path point (the point farthest below the straight line from
the first to the last sample: nanite's initial guess); for each ``z_c`` the fit
is linear, so the search is exhaustive and deterministic. The contact point is
the ``z_c`` of least squares.

The exponent ``p = 1.75`` lies between Hertz's 3/2 (paraboloid) and 2 (cone). It
was chosen against nanite's ``fit_line_polynomial`` (the reference the field
uses; a line plus ``delta^3 / (a delta^2 + b delta + c)``, cubic at the onset and
linear deep in) on the eleven shared soft curves: with ``p = 3/2`` the point lay
after nanite's on most of them, with ``p = 2`` before; ``p`` from 1.7 to 1.8 with
``force_fraction`` from 0.6 to 0.7 keeps every curve but one within 30 nm or 10 %
of the indentation (worst 0.93 of the tolerance at the chosen values), and the
chosen pair lies inside that region. The exception is the 2016 CellHesion curve,
whose onset is ambiguous and carries a warning. Method ``"hertz_local"`` is the
same fit with ``p = 3/2`` (``tests/analysis/test_contact_kinds.py``).

nanite's own point is a local Nelder-Mead optimum and moves by up to 4 um (the
2016 curve) or 0.96 um (a map curve) when its input is block-averaged, so no
method can be expected to match it closer than the curve's ambiguity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..errors import ParameterError
from ._numeric import polyfit, ptp
from ._units import unit as _u
from .options import KindOptions as _K  # the defaults: declared once, in the step's record

__all__ = ["ContactKind", "SoftContactPoint", "classify_contact", "soft_contact_point", "hertz_contact_point",
           "CONTACT_POINT_METHODS"]


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
    position_low, position_high : float
        Candidate contact points whose least squares lie within 4 sigma^2 of the
        best (about 2 sigma, sigma^2 from the best fit's residuals) [m]: a lower
        bound on the uncertainty (model error is not in it); wide on an ambiguous onset
    """

    method: str
    index: int = _u("")
    position: float = _u("m")
    deflection: float = _u("m")
    initial_position: float = _u("m")
    indentation: float = _u("m")
    exponent: float = _u("")
    position_low: float = _u("m", math.nan)
    position_high: float = _u("m", math.nan)


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
    # u ** 1.75 and u ** 1.5 by square roots (a few times faster than pow; equal to ~1 ulp)
    kind = 1 if exponent == 1.75 else 2 if exponent == 1.5 else 0
    # the samples before the first one beyond a candidate add nothing: start there (the same terms in
    # the same order), found on the running maximum of x (an approach rises, a measured one with noise)
    top = np.empty(n)
    run = -np.inf
    for i in range(n):
        run = max(run, x[i])
        top[i] = run
    for k in range(cands.size):
        sg = sgg = sxg = syg = 0.0
        start = np.searchsorted(top, cands[k], side="right")
        for i in range(start, n):
            u = x[i] - cands[k]
            if u > 0.0:
                if kind == 1:
                    r = math.sqrt(u)
                    g = u * r * math.sqrt(r)
                elif kind == 2:
                    g = u * math.sqrt(u)
                else:
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


def soft_contact_point(z: np.ndarray, d: np.ndarray, index: np.ndarray, *, exponent: float = 1.75,
                       force_fraction: float = _K.force_fraction, window: float = _K.window, grid: int = 121,
                       max_points: int = 500, method: str = "power_local") -> SoftContactPoint:
    """Contact point of the approach run ``index`` (time order) by a local power-law fit.

    Parameters
    ----------
    z, d : ndarray
        Position [m] and deflection [m] (any linear signal works) of the whole curve.
    index : ndarray of int
        The approach run's samples, time order.
    exponent : float
        Power of the contact term [-] (1.75 by default, see the module notes; 3/2: Hertz).
    force_fraction : float
        Fit up to where the block-averaged deflection reaches this fraction of its range [-].
    window : float
        Half-width of the search around the Frechet point, as a fraction of the run [-].
    grid : int
        Candidate contact points [-].
    max_points : int
        Block-average the run to at most this many points [-].
    method : str
        Name recorded in the result.
    """
    if not (0 < force_fraction <= 1 and 0 < window <= 1 and grid >= 3 and exponent > 1):
        raise ParameterError("contact point: force_fraction and window in (0, 1], grid >= 3, exponent > 1")
    nan = math.nan
    zi, di = z[index], d[index]
    # the largest deflection and the fit's end on the block average: a noise spike decides neither
    m = max(zi.size // max_points, 1)
    jb = int(np.argmax(_block(di, max_points)))
    imax = min((jb + 1) * m - 1, zi.size - 1) if m > 1 else int(np.argmax(di))
    if imax < 8:
        return SoftContactPoint(method, -1, nan, nan, nan, nan, exponent)
    zb, db = _block(zi[: imax + 1], max_points), _block(di[: imax + 1], max_points)
    above = np.flatnonzero(db - db.min() > force_fraction * ptp(db))
    cut = int(above[0]) + 1 if above.size and above[0] > 8 else db.size
    zb, db = zb[:cut], db[:cut]
    span = zb[-1] - zb[0] if zb.size > 1 else 0.0
    if not span > 0 or zb.size < 8:
        return SoftContactPoint(method, -1, nan, nan, nan, nan, exponent)
    x = (zb - zb[0]) / span
    y = (db - db.min()) / max(ptp(db), 1e-300)
    straight = np.linspace(0.0, 1.0, x.size)
    x_init = float(x[int(np.argmin(y - straight))])
    cands = np.linspace(max(x_init - window, 0.0), min(x_init + window, 1.0), grid)
    coef, rss = _fit_grid(x, y, cands, exponent)
    j = int(np.argmin(rss))
    coarse, coarse_rss = cands, rss
    step = cands[1] - cands[0]  # refine: a finer grid over the neighbouring cells
    cands = np.linspace(max(cands[j] - step, 0.0), min(cands[j] + step, 1.0), 41)
    coef, rss = _fit_grid(x, y, cands, exponent)
    j = int(np.argmin(rss))
    zc = float(zb[0] + cands[j] * span)
    s2 = rss[j] / max(x.size - 4, 1)  # 4 parameters: a, b, c, z_c
    near = coarse[coarse_rss <= rss[j] + 4.0 * s2]
    low = float(zb[0] + min(near.min(), cands[j]) * span) if near.size else zc
    high = float(zb[0] + max(near.max(), cands[j]) * span) if near.size else zc
    zr = zi[: imax + 1]
    k = int(np.searchsorted(zr, zc)) if np.all(np.diff(zr) >= 0) else int(np.argmin(np.abs(zr - zc)))
    k = min(max(k - 1, 0), zr.size - 1)
    a, b = coef[j, 0], coef[j, 1]
    d_c = float(db.min() + (a + b * cands[j]) * ptp(db))
    indentation = float((zi[imax] - zc) - (di[imax] - d_c))
    return SoftContactPoint(method, int(index[k]), zc, d_c, float(zb[0] + x_init * span), indentation,
                            float(exponent), min(low, high), max(low, high))


def hertz_contact_point(z: np.ndarray, d: np.ndarray, index: np.ndarray, **options) -> SoftContactPoint:
    """:func:`soft_contact_point` with the Hertz exponent 3/2 (paraboloid indenter)."""
    options.setdefault("exponent", 1.5)
    return soft_contact_point(z, d, index, method="hertz_local", **options)


#: Registered soft-contact-point methods (identifier -> function).
CONTACT_POINT_METHODS = {"power_local": soft_contact_point, "hertz_local": hertz_contact_point}


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
    if x.size < 3 or ptp(x) == 0:
        return math.nan
    return float(polyfit(x - x.mean(), y, 1)[0])


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
