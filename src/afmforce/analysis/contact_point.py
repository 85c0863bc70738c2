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

from ..errors import ParameterError
from ._contact_kernel import curvature_kernel, fit_grid, soft_contact_kernel
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


#: The grid fit, compiled (:func:`._contact_kernel.fit_grid`; the name tests and older callers use).
_fit_grid = fit_grid


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
    zi = np.ascontiguousarray(z[index], dtype=np.float64)
    di = np.ascontiguousarray(d[index], dtype=np.float64)
    k, zc, d_c, z_init, indentation, low, high = soft_contact_kernel(
        zi, di, float(exponent), float(force_fraction), float(window), int(grid), int(max_points))
    if k < 0:
        return SoftContactPoint(method, -1, nan, nan, nan, nan, exponent)
    return SoftContactPoint(method, int(index[int(k)]), float(zc), float(d_c), float(z_init), float(indentation),
                            float(exponent), float(low), float(high))


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
    z = np.ascontiguousarray(z, dtype=np.float64)
    d = np.ascontiguousarray(d, dtype=np.float64)
    early, late = curvature_kernel(z, d, np.ascontiguousarray(contact, dtype=np.int64))
    if early == -math.inf or late == -math.inf:  # the compiled polyfit refused one: numpy's (its fallback)
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
