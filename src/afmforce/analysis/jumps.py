"""Jump into contact, pull-off, and the adhesion they imply (paper sections 2.1, 3.2).

* Jump-in: the largest downward step of the deflection on the approach within
  ``window`` samples of the contact split (the two-line boundary of
  :mod:`.regions`); significant if it exceeds ``nsigma`` times the step noise.
  ``index`` is the last sample before the jump (the last one on the free branch).
* Pull-off: the last retract sample on the contact line (see
  :func:`find_pull_off`); its force is the most negative deflection up to it
  (the adhesion), its jump-out distance that deflection as a positive length
  (Fig 9: 200 nm). A free cantilever ringing after the pull-off (sampled slower
  than it rings) is not taken for the jump.
* Adhesion: JKR ``F = -3 pi gamma R / 4`` (or DMT ``-pi gamma R``) gives gamma
  from a known radius, and R from gamma (``R = 4 k d_out / (3 pi gamma)``, the
  paper's way to fix R = 220 nm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import forces
from ..constants import HAMAKER, Z0
from ..errors import ParameterError
from ._numeric import largest_step, robust_line
from .regions import RunRegions

__all__ = ["JumpIn", "PullOff", "find_jump_in", "find_pull_off", "AdhesionResult", "adhesion"]


@dataclass(frozen=True)
class JumpIn:
    """Jump into contact on the approach run.

    Attributes
    ----------
    found : bool  a significant jump exists (False: the tip crept into contact)
    index : int  last sample before the jump (-1 if none) [-]
    position : float  position relative to contact [m]
    separation : float  separation just before the jump [m]
    deflection_before, deflection_after : float  [m]
    force_before, force_after : float  [N] (NaN without spring constant)
    significance : float  step / step noise [-]
    """

    found: bool
    index: int
    position: float
    separation: float
    deflection_before: float
    deflection_after: float
    force_before: float
    force_after: float
    significance: float


@dataclass(frozen=True)
class PullOff:
    """Jump out of contact on the retract run.

    Attributes
    ----------
    found : bool
    index : int  last sample in contact (-1 if none) [-]
    position : float  position relative to contact at pull-off [m]
    deflection : float  most negative deflection before the jump (adhesion) [m]
    force : float  pull-off force, k x deflection [N]
    jump_out_distance : float  |deflection| at pull-off [m]
    significance : float  [-]
    saturated : bool  the photodiode clipped at the bottom: force is a lower bound
    """

    found: bool
    index: int
    position: float
    deflection: float
    force: float
    jump_out_distance: float
    significance: float
    saturated: bool


def _nan_jump_in() -> JumpIn:
    nan = math.nan
    return JumpIn(False, -1, nan, nan, nan, nan, nan, nan, 0.0)


def find_jump_in(d: np.ndarray, separation: np.ndarray, position: np.ndarray, run: RunRegions,
                 noise: float, spring_constant: float, nsigma: float = 5.0, window: int = 3) -> JumpIn:
    """Largest downward step of the approach within ``window`` samples of the contact split.

    ``noise`` is the deflection noise [m]; the step noise is ``sqrt(2) noise``.
    """
    idx = run.index
    dr = d[idx]
    i = largest_step(dr, max(run.split - window, 0), min(run.split + window, idx.size), -1.0)
    if i < 0:
        return _nan_jump_in()
    step = dr[i] - dr[i + 1]
    sig = step / (math.sqrt(2.0) * noise) if noise > 0 else math.inf
    if not sig > nsigma:
        return _nan_jump_in()
    g = idx[i]
    k = spring_constant
    return JumpIn(True, int(g), float(position[g]), float(separation[g]), float(dr[i]), float(dr[i + 1]),
                  float(k * dr[i]), float(k * dr[i + 1]), float(sig))


def find_pull_off(d: np.ndarray, position: np.ndarray, run: RunRegions, noise: float,
                  spring_constant: float, nsigma: float = 5.0, window: int = 3) -> PullOff:
    """The last retract sample on the contact line before the cantilever leaves it.

    The contact (compliance and adhesion) line is fitted robustly on the
    retract's compliance region; walking forward in time from there, the
    pull-off is the sample before the first two consecutive samples that lie
    more than ``nsigma`` step noises above the line. A cantilever that rings
    after leaving the surface cannot be mistaken for the jump this way. If
    the contact is not a line (a soft sample), the largest upward step within
    ``window`` samples of the end of contact is used instead.
    """
    idx = run.index
    dr = d[idx]
    nan = math.nan
    thr = nsigma * math.sqrt(2.0) * noise if noise > 0 else 0.0
    comp = np.flatnonzero(run.compliance & ~run.saturated)
    i = -1
    if comp.size >= 3:
        x = position[idx]
        x0 = x[comp].mean()
        a, b, *_ = robust_line(x[comp] - x0, dr[comp])
        r = dr - (a + b * (x - x0))
        above = (r > thr) & ~run.saturated  # a clipped signal leaves the line without leaving contact
        start = int(comp.max())
        cand = np.flatnonzero(above[start:-1] & above[start + 1:]) + start
        if cand.size and cand[0] > start:
            i = int(cand[0]) - 1
    if i < 0:  # fall back on the largest step near the end of contact
        i = largest_step(dr, max(run.split - window, 0), min(run.split + window, idx.size), +1.0)
    if i < 0 or i + 1 >= idx.size:
        return PullOff(False, -1, nan, nan, nan, nan, 0.0, False)
    step = dr[i + 1] - dr[i]
    sig = step / (math.sqrt(2.0) * noise) if noise > 0 else math.inf
    if not sig > nsigma:
        return PullOff(False, -1, nan, nan, nan, nan, float(sig), False)
    j = int(np.argmin(dr[: i + 1]))
    dmin = float(dr[j])
    sat = bool(run.saturated[: i + 1].any() and run.saturated[j])
    return PullOff(True, int(idx[i]), float(position[idx[i]]), dmin, float(spring_constant * dmin),
                   abs(dmin), float(sig), sat)


@dataclass(frozen=True)
class AdhesionResult:
    """Surface energy and radius from the pull-off.

    Attributes
    ----------
    model : str  ``"jkr"`` or ``"dmt"``
    surface_energy : float  gamma from the given radius [J/m^2] (NaN without radius)
    radius : float  R from the jump-out and the assumed gamma [m]
    surface_energy_assumed : float  gamma used for R: A/(16 pi z0^2) [J/m^2]
    radius_given : float  [m] (NaN if none)
    """

    model: str
    surface_energy: float
    radius: float
    surface_energy_assumed: float
    radius_given: float


def adhesion(pull_off: PullOff, spring_constant: float, *, radius: float | None = None,
             model: str = "jkr", hamaker: float = HAMAKER, z0: float = Z0) -> AdhesionResult:
    """gamma from a known R, and R from gamma = A/(16 pi z0^2) (section 2.1)."""
    if model not in ("jkr", "dmt"):
        raise ParameterError(f"adhesion model must be jkr or dmt, got {model!r}")
    g_assumed = float(forces.surface_energy(hamaker, z0))
    f = pull_off.force
    c = 0.75 * math.pi if model == "jkr" else math.pi  # |F| = c gamma R
    r_given = math.nan if radius is None else float(radius)
    gamma = -f / (c * r_given) if math.isfinite(r_given) else math.nan
    r_est = (spring_constant * pull_off.jump_out_distance) / (c * g_assumed)
    return AdhesionResult(model=model, surface_energy=float(gamma), radius=float(r_est),
                          surface_energy_assumed=g_assumed, radius_given=r_given)
