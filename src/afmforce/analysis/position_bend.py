"""A nominal position that bends differently on the approach and on the retract (piezo hysteresis, creep,
nonlinearity).

On a hard contact the lever's base and the tip move together: at equal deflection the position is a line of
the signal on both runs, and where the tip meets the surface (zero load) the two runs' lines, once the shift
step has overlaid them, agree. A piezo's nominal position that bends differently on the two runs leaves them
apart there, and the retract's line (long, and bent over its whole pull to the pull-off) put the approach's
zero of separation nanometres off its jump-in: a virtual curve with a 2 % quadratic bend of opposite sign on
the two runs gave a sensitivity 3 % off and A R 55 % off, in silence.

:func:`position_bend` measures the gap at zero load between the approach's own line and the retract's (with
its standard error) and each run's bend; the zero step then takes the approach's own line, next to the jump-in
and the van der Waals attraction it carries, and :func:`bend_note` says why, and what the sensitivity may be
(the local slopes of both lines: the data cannot tell which is the lever's). Checked on the nominal channel
only: a measured (sensor) position is taken as the distance (as for the fringes, Fig 7B), and a disagreement
of its runs is the contact's (friction, which the friction step reads).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._numeric import robust_line
from ._units import unit as _u
from .regions import RunRegions

__all__ = ["PositionBend", "position_bend", "zero_gap", "bend_note", "GAP_SIGMAS", "MIN_GAP", "MAX_BEND",
           "MIN_BEND_SAMPLES"]

#: The approach's zero of separation from the retract's line and from its own must differ by more than this
#: many standard errors [-] ...
GAP_SIGMAS = 6.0
#: ... and by more than this [m] for the retract's line to be set aside: a tenth of a nanometre moves A R of a
#: van der Waals fit at a 5 nm jump-in by 6 %, twice its standard error on the virtual curve (the intact
#: virtual curve: 0.04 nm, 2 standard errors; tests/analysis/test_silent_bend_fringes.py).
MIN_GAP = 0.1e-9
#: Both lines must be straight to this relative change of their slope across their shared range [-]: a line
#: bent more is no constant-compliance line (a soft or nonlinear contact, which other warnings name; the AFM
#: Workshop CSV of the shared real files bends by 40 and 70 %), the piezo's bend is a few per cent.
MAX_BEND = 0.25
#: Fewest unsaturated compliance samples each run needs (and in the signal range both share, for the bends) [-].
MIN_BEND_SAMPLES = 20


@dataclass(frozen=True)
class PositionBend:
    """How the two runs' compliance lines disagree where the approach meets the surface.

    Attributes
    ----------
    gap : float
        Where the retract's line (positions as the shift step left them) puts the contact at zero load,
        less where the approach's own line puts it [m]: how far the approach's separations move with the line.
    gap_se : float  its standard error [m]
    approach, retract : float
        Relative change of ``dz/ds`` across the signal range the two lines share [-] (0: a line; NaN: fewer
        than :data:`MIN_BEND_SAMPLES` samples of a run there).
    slopes : tuple of float
        The smallest and largest local slope ``ds/dz`` of either run's whole line [signal/m].
    detected : bool
        ``|gap|`` beyond :data:`GAP_SIGMAS` standard errors and :data:`MIN_GAP`, on two lines straight
        within :data:`MAX_BEND`.
    """

    gap: float = _u("m")
    gap_se: float = _u("m")
    approach: float = _u("")
    retract: float = _u("")
    slopes: tuple[float, float] = _u("{signal}/m")
    detected: bool = False


def _quadratic(x: np.ndarray, y: np.ndarray, lo: float, hi: float) -> tuple[float, float, float, float, float]:
    """``y = a + b v + c v^2`` with ``v`` the position of ``x`` in ``[lo, hi]`` scaled to [-1, 1]: (b, c,
    se of b, se of c, covariance of b and c), with the residual scale's standard errors."""
    mid, half = 0.5 * (hi + lo), 0.5 * (hi - lo)
    v = (x - mid) / half
    X = np.column_stack([np.ones_like(v), v, v * v])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    res = y - X @ coef
    dof = max(y.size - 3, 1)
    cov = float(res @ res) / dof * np.linalg.inv(X.T @ X)
    return float(coef[1]), float(coef[2]), math.sqrt(cov[1, 1]), math.sqrt(cov[2, 2]), float(cov[1, 2])


def _local_slopes(z: np.ndarray, s: np.ndarray) -> tuple[float, float]:
    """The least and largest local slope ``ds/dz`` of a run's whole line: a quadratic's end slopes, each
    widened by two of its standard errors (a straight line's noise bends its fit a little either way)."""
    lo, hi = float(z.min()), float(z.max())
    b, c, sb, sc, cbc = _quadratic(z, s, lo, hi)
    half = 0.5 * (hi - lo)
    ends = []
    for sign in (-1.0, 1.0):
        se = math.sqrt(max(sb**2 + 4 * sc**2 + sign * 4 * cbc, 0.0))
        ends.append(((b + sign * 2 * c) - 2 * se, (b + sign * 2 * c) + 2 * se))
    return min(e[0] for e in ends) / half, max(e[1] for e in ends) / half


def _zero(z: np.ndarray, d: np.ndarray, idx: np.ndarray) -> tuple[float, float]:
    """Where a run's robust contact line ``d(z)`` crosses zero deflection [m], and its standard error."""
    zm = float(z[idx].mean())
    a, b, se_a, se_b, *_ = robust_line(z[idx] - zm, d[idx])
    if not (math.isfinite(b) and b > 0):
        return math.nan, math.nan
    x0 = -a / b
    return zm + x0, math.hypot(se_a / b, x0 * se_b / b)


def zero_gap(z: np.ndarray, d: np.ndarray, approach: RunRegions, retract: RunRegions) -> tuple[float, float]:
    """How far the retract's compliance line puts the contact at zero load from where the approach's own
    line puts it, positions as given (the approach shifted or not) [m], and the standard error [m]."""
    za, sa = _zero(z, d, approach.index[approach.compliance & ~approach.saturated])
    zr, sr = _zero(z, d, retract.index[retract.compliance & ~retract.saturated])
    return zr - za, math.hypot(sa, sr)


def _bends(z: np.ndarray, s: np.ndarray, runs: list[np.ndarray]) -> tuple[float, float]:
    """Each run's relative change of ``dz/ds`` across the signal range both lines cover (NaN: too few samples)."""
    lo = max(float(s[i].min()) for i in runs)
    hi = min(float(s[i].max()) for i in runs)
    if not hi > lo:
        return math.nan, math.nan
    out = []
    for i in runs:
        i = i[(s[i] >= lo) & (s[i] <= hi)]
        if i.size < MIN_BEND_SAMPLES:
            return math.nan, math.nan
        b, c, *_ = _quadratic(s[i], z[i], lo, hi)
        out.append(4.0 * c / b if b > 0 else math.nan)
    return out[0], out[1]


def position_bend(z: np.ndarray, s: np.ndarray, approach: RunRegions | None,
                  retract: RunRegions | None) -> PositionBend | None:
    """How the runs' compliance lines of the position ``z`` [m] against the signal ``s`` (zero at zero load)
    disagree (None: a run without a line, or with fewer than :data:`MIN_BEND_SAMPLES` unsaturated samples on it)."""
    if approach is None or retract is None or not (approach.has_compliance and retract.has_compliance):
        return None
    runs = [r.index[r.compliance & ~r.saturated] for r in (approach, retract)]
    if min(i.size for i in runs) < MIN_BEND_SAMPLES or not all(np.ptp(z[i]) > 0 and np.ptp(s[i]) > 0 for i in runs):
        return None   # (a degenerate line: its positions or its signal do not move; the compliance step said so)
    try:
        gap, se = zero_gap(z, s, approach, retract)
        if not (math.isfinite(gap) and math.isfinite(se)):
            return None
        ba, br = _bends(z, s, runs)
        slopes = [_local_slopes(z[i], s[i]) for i in runs]
    except np.linalg.LinAlgError:
        return None
    return PositionBend(gap=gap, gap_se=se, approach=ba, retract=br,
                        slopes=(min(x[0] for x in slopes), max(x[1] for x in slopes)),
                        detected=bool(abs(gap) > GAP_SIGMAS * se and abs(gap) > MIN_GAP
                                      and max(abs(ba), abs(br)) <= MAX_BEND))


def bend_note(b: PositionBend, unit: str, calibrated_by_slope: bool) -> str:
    """The warning of a detected disagreement: what it is, what was done, what the sensitivity may be."""
    bends = ("" if not (math.isfinite(b.approach) and math.isfinite(b.retract)) else
             f"; over the deflection range both share, the position's slope changes by {b.approach * 100:+.2g} % on "
             f"the approach and {b.retract * 100:+.2g} % on the retract")
    if unit == "V":
        lo, hi = 1e9 / b.slopes[1], 1e9 / b.slopes[0]
        what = f"sensitivities from {lo:.4g} to {hi:.4g} nm/V"
    else:
        what = f"slopes from {b.slopes[0]:.4g} to {b.slopes[1]:.4g} {unit}/m"
    sens = (f"the local slopes of the two contact lines give {what} and the data cannot tell which is the "
            "lever's: " + ("the sensitivity fitted, and every force, are uncertain by that much; give the lever's "
                           "`sensitivity` (e.g. from its thermal spectrum)" if calibrated_by_slope else
                           "the file's sensitivity is used"))
    return (f"the approach's and the retract's compliance lines disagree where the tip meets the surface: the "
            f"retract's line, shifted onto the approach's, puts the contact at zero load {b.gap * 1e9:+.3g} nm from "
            f"the approach's own ({abs(b.gap) / b.gap_se:.3g} standard errors){bends}: the piezo's nominal position "
            f"bends differently on the two runs (hysteresis, creep, nonlinearity), or friction proportional to load "
            f"(friction step); the zero of separation is taken from the approach's own line, next to its jump-in "
            f"and van der Waals attraction (the retract's separations are approximate); {sens}; record the "
            f"measured (sensor) position if the instrument has one")
