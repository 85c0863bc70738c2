"""Events of a simulated cycle: jump-in, contact, pull-off, spike, compliance offset.

Most events are located inside the integrator, on the dense output of every
accepted step (see :func:`afmforce.dynamics.radau._events`), so they do not
depend on the sampling rate:

* **jump-in** (criterion, stated once here): where the trajectory leaves
  the static branch, i.e. the first time on the approach, before contact,
  that the separation falls below ``h_s``, the separation of the static
  instability ``Fs'(h_s) = k`` (spec section 2). Quasi-statically this is
  exactly the static jump-in ``z_s`` (also reported); dynamically the tip
  reaches ``h_s`` later, at ``z > z_s``: the difference is the dynamic lag.
  Whether the tip then *jumps* is a second question: it does when the
  separation closes faster than ``jump_factor`` (2) times the drive speed,
  ``dh/dt < -2 dz/dt``, before contact (``jumped = True``). When friction
  holds the tip back (large xi * v, spec section 7) it never closes that
  fast: it creeps into contact, and the event says so (``jumped = False``)
  instead of inventing a jump. (The speed criterion alone fires
  quasi-statically where ``Fs' = k/2``, a factor 2^(1/3) farther out than the
  instability, so it is not used for the position.)
* **contact**: the first time the separation drops below
  ``contact_separation`` (1 nm, spec section 7) on the approach.
* **pull-off**: the first time the separation rises above
  ``contact_separation`` on the retract; the pull-off force is the most
  negative normal force Fz in contact on the retract (the adhesion).
* **minimum (apparent) deflection** before contact: the largest measured
  attraction (spec section 7, column 3).
* **spike**: the largest apparent deflection ``beta theta`` from jump-in (or
  contact, when creeping) to ``spike_window`` after contact (Fig 5: the
  positive apparent deflection while the tip cannot slide).

From the sampled trajectory (:func:`compliance_lines`): straight-line fits
``z = c0 + c1 * d~`` of drive position against apparent deflection in the
constant-compliance region of the inward and the outward run (over the
middle half of the drive range in contact); ``c1`` is the simulated
calibration slope (dz/dtheta per unit beta), and the offset of the two lines
at a fixed angle is ``z_inward - z_outward`` (eq 16; spec section 7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ._jit import fmax, fmin, piece

from .radau import APPROACH, RETRACT

__all__ = ["Events", "compliance_lines", "fit_compliance"]


@dataclass(frozen=True)
class Events:
    """Events of one approach-retract cycle (NaN where an event did not occur).

    Attributes
    ----------
    jumped : bool or None
        True: a jump-in by the criterion above; False: the tip crept into
        contact without a jump; None: no contact at all.
    jump_in_note : str
        A sentence saying which case occurred.
    jump_in_time, jump_in_position, jump_in_separation : float
        Where the trajectory leaves the static branch (first h < h_s on the
        approach): time [s], drive position z [m], separation h [m] (= h_s).
    static_jump_in_position, static_jump_in_separation : float
        The static instability Fs'(h_s) = k: drive position z_s [m] and h_s [m]
        (the quasi-static limit of the jump-in; the dynamic one lies beyond
        it by the lag).
    contact_time, contact_position : float
        First h < contact_separation on the approach [s, m].
    pull_off_time, pull_off_position : float
        First h > contact_separation on the retract [s, m].
    pull_off_force : float
        Most negative normal force in contact on the retract [N].
    min_deflection, min_deflection_position : float
        Smallest deflection z2 before contact on the approach, and where [m].
    min_apparent_deflection, min_apparent_deflection_position : float
        Smallest apparent deflection beta*theta before contact, and where [m]
        (the deflection itself for the spring model).
    spike_height, spike_time, spike_position : float
        Largest apparent deflection from jump-in to ``spike_window`` after
        contact [m], when [s], where [m] (NaN for the spring model, and with
        ``spike_window = 0``: not asked for).
    hysteresis_offset : float
        ``z_inward - z_outward`` of the constant-compliance lines at a fixed
        angle [m] (NaN without two usable contact lines).
    compliance_slope : float
        dz/dtheta of the constant-compliance lines [m/rad]: the calibration
        factor an experimenter would measure (beam model; NaN otherwise).
    turn_time, turn_position : float
        Where the approach turned [s, m].
    """

    jumped: bool | None
    jump_in_note: str
    jump_in_time: float
    jump_in_position: float
    jump_in_separation: float
    static_jump_in_position: float
    static_jump_in_separation: float
    contact_time: float
    contact_position: float
    pull_off_time: float
    pull_off_position: float
    pull_off_force: float
    min_deflection: float
    min_deflection_position: float
    min_apparent_deflection: float
    min_apparent_deflection_position: float
    spike_height: float
    spike_time: float
    spike_position: float
    hysteresis_offset: float
    compliance_slope: float
    turn_time: float
    turn_position: float

    def to_dict(self) -> dict:
        """Plain dict of the fields (SI)."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def compliance_lines(piezo_position, apparent_deflection, separation, segment,
                     contact_separation: float, contact_position: float, turn_position: float,
                     beta: float):
    """Fit the inward and outward constant-compliance lines.

    Uses in-contact samples (h < contact_separation) with z in the middle
    half of ``[contact_position, turn_position]`` on each run; fits
    ``z = c0 + c1 * d~`` by least squares (:func:`_line_fit`, compiled).

    Returns
    -------
    offset : float
        ``z_in - z_out`` at the apparent deflection in the middle of the common
        fitted range [m].
    slope : float
        ``beta * mean(c1)``: dz/dtheta [m/rad] (NaN when beta is NaN).
    """
    z = np.asarray(piezo_position, dtype=float)
    d = np.asarray(apparent_deflection, dtype=float)
    h = np.asarray(separation, dtype=float)
    seg = np.asarray(segment)
    if seg.dtype != np.int8:
        seg = seg.astype(np.int64, copy=False)
    return fit_compliance(z, d, h, seg, float(contact_separation), float(contact_position),
                          float(turn_position), float(beta))


@njit(cache=True, error_model="numpy", nogil=True)
def fit_compliance(z, d, h, seg, hc, contact_position, turn_position, beta):
    """:func:`compliance_lines` on arrays, compiled (no GIL; the simulation calls it from
    its compiled sampling pass). Returns ``(offset, slope)``, NaN where not fitted."""
    if not (math.isfinite(contact_position) and turn_position > contact_position):
        return math.nan, math.nan
    span = turn_position - contact_position
    lo, hi = contact_position + 0.25 * span, turn_position - 0.25 * span
    fits = np.empty((2, 4))
    for j, kind in enumerate((APPROACH, RETRACT)):   # kind an int64, not two literals
        count, c0, c1, dlo, dhi = _line_fit(z, d, h, seg, kind, hc, lo, hi)
        if count < 5 or not math.isfinite(c1):
            return math.nan, math.nan
        fits[j, 0], fits[j, 1], fits[j, 2], fits[j, 3] = c0, c1, dlo, dhi
    a0, a1, alo, ahi = fits[0, 0], fits[0, 1], fits[0, 2], fits[0, 3]
    b0, b1, blo, bhi = fits[1, 0], fits[1, 1], fits[1, 2], fits[1, 3]
    dmid = 0.5 * (fmax(alo, blo) + fmin(ahi, bhi))
    offset = (a0 + a1 * dmid) - (b0 + b1 * dmid)
    slope = beta * 0.5 * (a1 + b1) if math.isfinite(beta) else math.nan
    return offset, slope


@piece()
def _line_fit(z, d, h, seg, kind, hc, lo, hi):
    """Least-squares line ``z = c0 + c1 d`` through the samples of segment ``kind`` with
    ``h < hc`` and ``lo <= z <= hi`` (what ``np.polyfit(d[m], z[m], 1)`` fits, in one
    compiled pass over the centred sums, without the GIL).

    Returns ``(count, c0, c1, min d, max d)``; ``c1`` is NaN when the d values do not
    vary (or fewer than two samples).
    """
    n = 0
    sd = 0.0
    sz = 0.0
    dmin = math.inf
    dmax = -math.inf
    for i in range(z.shape[0]):
        if seg[i] == kind and h[i] < hc and z[i] >= lo and z[i] <= hi:
            n += 1
            sd += d[i]
            sz += z[i]
            dmin = fmin(dmin, d[i])
            dmax = fmax(dmax, d[i])
    if n < 2 or not dmax > dmin:
        return n, math.nan, math.nan, dmin, dmax
    dm = sd / n
    zm = sz / n
    sdd = 0.0
    sdz = 0.0
    for i in range(z.shape[0]):
        if seg[i] == kind and h[i] < hc and z[i] >= lo and z[i] <= hi:
            dd = d[i] - dm
            sdd += dd * dd
            sdz += dd * (z[i] - zm)
    if not sdd > 0.0:
        return n, math.nan, math.nan, dmin, dmax
    c1 = sdz / sdd
    return n, zm - c1 * dm, c1, dmin, dmax
