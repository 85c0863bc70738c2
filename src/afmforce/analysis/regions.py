"""Contact, constant-compliance and zero-force regions of each run.

Each run (approach, retract; in time order) is split where two independent
straight lines fit it best (:func:`~._numeric.two_line_split`): on the approach
the split falls at the jump into contact, on the retract at the pull-off. The
far part is the zero-force region (its farthest ``baseline_fraction`` is used
for the baseline, leaving the attraction near contact out); the near part is
the contact region (its ``compliance_fraction`` nearest the turning point is
used for the constant-compliance line). Saturated samples (the photodiode
clipped at its extreme value) are left out of both.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AnalysisError
from ._numeric import mad_sigma, two_line_split

__all__ = ["RunRegions", "find_run_regions", "saturated_mask", "run_indices"]


@dataclass(frozen=True)
class RunRegions:
    """Regions of one run; boolean masks are over the run's samples in time order.

    Attributes
    ----------
    kind : str
        ``"approach"`` or ``"retract"``.
    index : ndarray of int
        Indices of the run's samples in the curve [-].
    split : int
        Position in the run of the first contact sample (approach) or of the first
        free sample after the pull-off (retract) [-].
    contact, zero_force, compliance, saturated : ndarray of bool
        In contact; used for the baseline; used for the compliance line; clipped.
    noise : float
        Robust noise of the free part's signal [signal unit].
    """

    kind: str
    index: np.ndarray
    split: int
    contact: np.ndarray
    zero_force: np.ndarray
    compliance: np.ndarray
    saturated: np.ndarray
    noise: float = float("nan")


def run_indices(segment: np.ndarray, which: int) -> np.ndarray:
    """Indices of segment ``which`` (0 approach, 1 retract), in time order."""
    return np.flatnonzero(np.asarray(segment) == which)


def saturated_mask(signal: np.ndarray, min_run: int = 3) -> np.ndarray:
    """Samples stuck at the extreme values of the signal (a clipped photodiode).

    A sample is saturated when it equals the global maximum (or minimum) and at
    least ``min_run`` samples share that exact value.
    """
    out = np.zeros(signal.size, dtype=bool)
    for extreme in (signal.max(), signal.min()):
        hit = signal == extreme
        if hit.sum() >= min_run:
            out |= hit
    return out


def find_run_regions(z: np.ndarray, s: np.ndarray, index: np.ndarray, kind: str, *,
                     saturated: np.ndarray, min_points: int = 5, baseline_fraction: float = 0.7,
                     compliance_fraction: float = 0.5, min_contrast: float = 10.0,
                     noise: float | None = None) -> RunRegions:
    """Find the contact and zero-force regions of one run.

    Parameters
    ----------
    z, s : ndarray
        Position [m] and deflection signal [any unit] of the whole curve.
    index : ndarray of int
        The run's samples in time order.
    kind : str
        ``"approach"`` or ``"retract"``.
    saturated : ndarray of bool
        Saturated samples of the whole curve.
    noise : float, optional
        Noise of the other run [signal unit]: the contrast test uses the smaller
        of the two (a cantilever ringing freely after pull-off makes the retract's
        free part noisy).

    Raises
    ------
    AnalysisError
        Too few samples, a flat signal, or no constant-compliance region.
    """
    n = index.size
    if n < 2 * min_points + 2:
        raise AnalysisError(f"the {kind} run has {n} samples; at least {2 * min_points + 2} are needed")
    zr, sr, sat = z[index], s[index], saturated[index]
    if np.ptp(sr) == 0:
        raise AnalysisError(f"flat curve: the deflection signal of the {kind} run is constant")
    ok = ~sat
    if ok.sum() < 2 * min_points:
        raise AnalysisError(f"the {kind} run is saturated (the photodiode is clipped almost everywhere)")
    if np.ptp(sr[ok]) == 0:
        raise AnalysisError(f"flat curve: the deflection signal of the {kind} run is constant")
    pos = np.flatnonzero(ok)
    # approach: far side first in time; retract: contact first -> reverse so far side comes first
    order = pos if kind == "approach" else pos[::-1]
    k = two_line_split(zr[order], sr[order], min_points)
    if k < 0:
        raise AnalysisError(f"the {kind} run is too short to find a contact region")
    far, near = order[:k], order[k:]
    # contrast test: the contact line must rise well above the baseline noise
    own = float(mad_sigma(np.diff(sr[far])) / np.sqrt(2.0)) if far.size > 2 else 0.0
    sigma = own if noise is None or not np.isfinite(noise) else min(own, float(noise))
    span = np.ptp(sr[near]) if near.size else 0.0
    if not (span > min_contrast * max(sigma, 1e-300)) or near.size < min_points:
        raise AnalysisError(
            f"no contact region found on the {kind} run (the signal rises only {span:.3g} over a "
            f"noise of {sigma:.3g}); is the surface reached?")
    split = int(near.min() if kind == "approach" else far.min())
    contact = np.zeros(n, bool)
    contact[near] = True
    zero_force = np.zeros(n, bool)
    zfar = zr[far]
    z_lo, z_hi = zfar.min(), zfar.max()
    zero_force[far[zfar <= z_lo + baseline_fraction * (z_hi - z_lo)]] = True
    if zero_force.sum() < min_points:
        zero_force[far] = True
    compliance = np.zeros(n, bool)
    znear = zr[near]
    z_top = znear.max()
    keep = znear >= z_top - compliance_fraction * (z_top - znear.min())
    compliance[near[keep]] = True
    if compliance.sum() < min_points:
        compliance[near] = True
    return RunRegions(kind=kind, index=index, split=split, contact=contact, zero_force=zero_force,
                      compliance=compliance, saturated=sat, noise=own)
