"""Jump into contact, pull-off, and the adhesion they imply (paper sections 2.1, 3.2).

* Jump-in: the largest downward step of the deflection on the approach within
  ``window`` samples of the contact split (the two-line boundary of
  :mod:`.regions`); significant if it exceeds ``nsigma`` times the step noise.
  ``index`` is the last sample before the jump (the last one on the free branch).
  Without a significant step (the tip crept into contact, or the jump is below
  the noise) ``found`` is False and the numbers describe the onset of contact:
  the last sample before the split.
* Through a barrier: a jump that starts at a repulsive force, after the force rose from the free
  baseline, is the jump through a repulsive barrier (a double layer's, a steric layer's, a surface
  layer that yields): the tip goes over the top once the force gradient beyond it exceeds k
  (dF/dh = k) and jumps into the primary minimum or onto the contact, where it may land repulsive
  too on a hard contact (Israelachvili, *Intermolecular and Surface Forces*, 3rd ed., ch. 14; Butt,
  Cappella & Kappl, Surf. Sci. Rep. 59, 1 (2005); a layer that yields: Butt & Franz, Phys. Rev. E 66,
  031601 (2002)). ``force_before`` is then the barrier height, ``deflection_before - deflection_after``
  the distance the tip jumps (:attr:`JumpIn.jump_distance`).
* Pull-off: the last retract sample on the contact line (see
  :func:`find_pull_off`); its force is the most negative deflection up to it
  (the adhesion), its jump-out distance that deflection as a positive length
  (Fig 9: 200 nm). A free cantilever ringing after the pull-off (sampled slower
  than it rings) is not taken for the jump. When the photodiode clipped the
  bottom of the pull-off, the deflection is a lower bound; the contact line
  extrapolated to the pull-off position estimates the real one.
* Adhesion: JKR ``F = -3 pi gamma R / 4`` (or DMT ``-pi gamma R``) gives gamma
  from a known radius, and R from gamma (``R = 4 k d_out / (3 pi gamma)``, the
  paper's way to fix R = 220 nm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import forces
from ..errors import ParameterError
from ._numeric import largest_step, robust_line
from .regions import RunRegions
from ._units import unit as _u
from .options import JumpsOptions as _J, SurfaceEnergyOptions as _E  # defaults declared once

__all__ = ["JumpIn", "PullOff", "Jumps", "find_jump_in", "find_pull_off", "jump_warnings", "pull_off_estimate",
           "AdhesionResult", "adhesion"]


@dataclass(frozen=True)
class JumpIn:
    """Jump into contact on the approach run.

    Attributes
    ----------
    found : bool  a significant jump exists (False: the tip crept into contact, and the
        numbers below describe the onset of contact)
    index : int  last sample before the jump (-1 if none) [-]
    position : float  position relative to contact [m]
    separation : float  separation just before the jump [m]
    deflection_before, deflection_after : float  [m]
    force_before, force_after : float  [N] (NaN without spring constant)
    significance : float  step / step noise [-]
    through_barrier : bool  the jump starts at a repulsive force the approach rose to from the free
        baseline: a jump through a repulsive barrier, whose height is ``force_before`` and whose
        length is ``deflection_before - deflection_after``
    """

    found: bool
    index: int = _u("")
    position: float = _u("m")
    separation: float = _u("m")
    deflection_before: float = _u("m")
    deflection_after: float = _u("m")
    force_before: float = _u("N")
    force_after: float = _u("N")
    significance: float = _u("")
    through_barrier: bool = False

    @property
    def jump_distance(self) -> float:
        """How far the tip jumps towards the surface at a fixed base [m]: the deflection's fall."""
        return self.deflection_before - self.deflection_after


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
    deflection_extrapolated : float
        The contact line at the pull-off position [m]: the deflection the clipped
        photodiode did not show (NaN when not clipped or no line)
    """

    found: bool
    index: int = _u("")
    position: float = _u("m")
    deflection: float = _u("m")
    force: float = _u("N")
    jump_out_distance: float = _u("m")
    significance: float = _u("")
    saturated: bool
    deflection_extrapolated: float = _u("m", math.nan)


@dataclass(frozen=True)
class Jumps:
    """The jumps step's result: the jump into contact and the pull-off.

    Attributes
    ----------
    jump_in : JumpIn
    pull_off : PullOff
    """

    jump_in: JumpIn
    pull_off: PullOff


#: A jump through a barrier starts at least this many times ``attractive_below`` above zero force [-]: below,
#: a drift line's offset near contact (the Nanosurf map in air: 3 x on a flat free branch) is not told from one.
BARRIER_MIN = 4.0
#: The free branch before a barrier's rise holds no attraction over this many samples [-] (one there: the tip
#: had jumped in, and the rise and fall are in contact).
BARRIER_FREE = 10
#: A jump through a barrier that lands above this fraction of the deflection it started from keeps most of
#: the barrier's load: a yielding layer's breakthrough (a gel: +4.38 -> +3.58 nm), not evidence of a jump
#: into hard contact (the contact kind's line decides); one that releases more (a double layer's barrier:
#: 57 -> 20 pN; a drag-loaded jump at 4 um/s: +1.76 -> -0.55 nm) has jumped into contact [-].
BARRIER_KEEPS = 0.5


def _nan_jump_in() -> JumpIn:
    nan = math.nan
    return JumpIn(False, -1, nan, nan, nan, nan, nan, nan, 0.0)


def find_jump_in(d: np.ndarray, separation: np.ndarray, position: np.ndarray, run: RunRegions,
                 noise: float, spring_constant: float, nsigma: float = _J.nsigma, window: int = _J.window,
                 attractive_below: float = math.inf) -> JumpIn:
    """Largest downward step of the approach within ``window`` samples of the contact split.

    ``noise`` is the deflection noise [m]; the step noise is ``sqrt(2) noise``.

    A jump into contact starts free and lands in attraction: a step that starts and lands above
    ``attractive_below`` [m] is a slip in contact (the split placed after a curved onset), not the jump.
    The jump is then the step into the attractive stretch that precedes that contact: walking back from
    the slip over the contact (deflection above ``attractive_below``), the line's crossing of zero force
    (within ``+-attractive_below``, over no more samples than the line then took up to the slip) and the
    attraction (below ``-attractive_below``), the largest downward step into and within that attraction, if it makes at
    least half of the attraction's depth (a lever that snaps; none such: the tip crept in through a
    gradual attraction, and the slip is judged as before). Default ``inf``: the
    largest step near the split, whatever its load.

    A downward step that starts above :data:`BARRIER_MIN` x ``attractive_below`` (repulsive) after the force
    rose to it from zero (walking back from the step, the first sample at or below ``attractive_below`` and
    the :data:`BARRIER_FREE` before it are not below ``-attractive_below``) is a jump through a repulsive
    barrier: ``through_barrier``. Not one: a step whose
    rise began in an attraction (the tip had jumped in already: a slip in contact, e.g. a stiff lever's in
    air), or one on a free branch that never came down to zero force (a misplaced zero: the step judges it).
    """
    idx = run.index
    dr = d[idx]
    i = largest_step(dr, max(run.split - window, 0), min(run.split + window, idx.size), -1.0)
    if i < 0:
        return _nan_jump_in()
    if dr[i] > attractive_below and dr[i + 1] > attractive_below:  # a slip in contact: look before it
        j = i
        while j >= 0 and dr[j] > attractive_below:  # back over the contact
            j -= 1
        m = j  # the last sample before the contact
        # over the line's crossing of zero force (samples within +-attractive_below: no more than the line
        # took from there up to the slip; a free branch the tip crept in from is longer) ...
        while j >= 0 and abs(dr[j]) <= attractive_below and m - j < i - m:
            j -= 1
        a = j  # the last attractive sample before the contact
        while j >= 0 and dr[j] < -attractive_below:  # ... and over the attraction after the jump
            j -= 1
        if j >= 0 and a > j:  # the jump: the largest downward step into and within that attraction ...
            jump = largest_step(dr, j, m + 1, -1.0)
            if dr[jump] - dr[jump + 1] >= 0.5 * (-dr[j + 1: a + 1].min()):  # ... if it makes most of it
                i = jump  # (a lever that snaps; a gradual attraction has no such step: crept in)
    step = dr[i] - dr[i + 1]
    sig = step / (math.sqrt(2.0) * noise) if noise > 0 else math.inf
    found = bool(sig > nsigma)
    if not found:  # no jump: the onset of contact, the last sample before the two-line split
        i = run.split - 1
        if not (0 <= i < idx.size - 1) or not run.has_compliance or run.saturated[i + 1]:
            return _nan_jump_in()
    g = idx[i]
    k = spring_constant
    barrier = False
    if found and dr[i] > BARRIER_MIN * attractive_below and dr[i] > dr[i + 1]:  # a fall that starts repulsive
        below = np.flatnonzero(dr[:i] <= attractive_below)
        # the force rose to it from zero force (the free branch), not from an attraction (the tip already
        # jumped in: a slip in contact), nor from nowhere (a free branch above zero: a misplaced zero)
        if below.size:
            b = int(below[-1])
            barrier = bool(dr[max(b - BARRIER_FREE, 0): b + 1].min() >= -attractive_below)
    return JumpIn(found, int(g), float(position[g]), float(separation[g]), float(dr[i]), float(dr[i + 1]),
                  float(k * dr[i]), float(k * dr[i + 1]), float(sig), barrier)


def find_pull_off(d: np.ndarray, position: np.ndarray, run: RunRegions, noise: float,
                  spring_constant: float, nsigma: float = _J.nsigma, window: int = _J.window,
                  attractive_below: float = math.inf) -> PullOff:
    """The last retract sample on the contact line before the cantilever leaves it.

    The contact (compliance and adhesion) line is fitted robustly on the
    retract's compliance region; walking forward in time from there, the
    pull-off is the sample before the first two consecutive samples that lie
    more than ``nsigma`` step noises above the line. A cantilever that rings
    after leaving the surface cannot be mistaken for the jump this way. If
    the contact is not a line (a soft sample), the largest upward step within
    ``window`` samples of the end of contact is used instead.

    A pull-off is an attraction: a departure from the line while the deflection
    has stayed above ``attractive_below`` [m] all the way (the retract leaving the
    compliance line in contact, displaced by friction or a slip at a repulsive
    load) is not the jump out of contact: then the pull-off is the largest rise after
    the deflection has come down to ``attractive_below`` (none there: no pull-off).
    The default, ``inf``, takes the first departure whatever its load. A departure without a rise
    after which the retract goes deeper is not the pull-off either (:func:`_still_in_contact`).
    """
    idx = run.index
    dr = d[idx]
    nan = math.nan
    thr = nsigma * math.sqrt(2.0) * noise if noise > 0 else 0.0
    comp = np.flatnonzero(run.compliance & ~run.saturated)
    i = -1
    line = None
    rise = -math.inf
    if comp.size >= 3:
        x = position[idx]
        x0 = x[comp].mean()
        a, b, *_ = robust_line(x[comp] - x0, dr[comp])
        line = lambda j: float(a + b * (x[j] - x0))  # noqa: E731
        r = dr - (a + b * (x - x0))
        above = (r > thr) & ~run.saturated  # a clipped signal leaves the line without leaving contact
        start = int(comp.max())
        cand = np.flatnonzero(above[start:-1] & above[start + 1:]) + start
        if cand.size and cand[0] > start and dr[: cand[0]].min() > attractive_below:
            # the retract left the line at a repulsive load (friction, a slip): not the pull-off; the jump out
            # of contact is the largest rise after the deflection has come down to an attraction
            low = np.flatnonzero(dr[: idx.size - 1] <= attractive_below)
            # ... before the retract came back to its free baseline: a later rise is a tether's rupture
            # (the JPK SMFS curve: its last unfolding peak, 267 nm away, was taken for the pull-off)
            hi = surface_end(dr, int(low[0]), thr) + 1 if low.size else idx.size
            i = largest_step(dr, int(low[0]), min(hi, idx.size), +1.0) if low.size else -1
            i = i if i >= 0 else -2  # -2: no attractive pull-off (no fall-back on the steps near the split)
        elif cand.size and cand[0] > start:
            i = int(cand[0]) - 1
            rise = float(r[i + 1])  # height above the line: a clipped contact has no step of its own
            i, rise = _still_in_contact(dr, i, rise, thr, run.saturated)
    if i == -1:  # fall back on the largest step near the end of contact
        i = largest_step(dr, max(run.split - window, 0), min(run.split + window, idx.size), +1.0)
    if i < 0 or i + 1 >= idx.size:
        return PullOff(False, -1, nan, nan, nan, nan, 0.0, False)
    step = max(dr[i + 1] - dr[i], rise)
    sig = step / (math.sqrt(2.0) * noise) if noise > 0 else math.inf
    if not sig > nsigma:
        return PullOff(False, -1, nan, nan, nan, nan, float(sig), False)
    j = int(np.argmin(dr[: i + 1]))
    dmin = float(dr[j])
    lo = int(comp.max()) if comp.size else 0
    # clipped at the bottom between the compliance region and the pull-off (the top clip is positive)
    sat = bool(np.any(run.saturated[lo: i + 1] & (dr[lo: i + 1] < 0)))
    d_ext = math.nan
    if sat and line is not None and line(i) < dmin:  # the line goes on below the clip
        d_ext = line(i)
    return PullOff(True, int(idx[i]), float(position[idx[i]]), dmin, float(spring_constant * dmin),
                   abs(dmin), float(sig), sat, float(d_ext))


def _still_in_contact(dr: np.ndarray, i: int, rise: float, thr: float, saturated: np.ndarray) -> tuple[int, float]:
    """The pull-off, given ``i``, the last sample on the contact line before the retract left it.

    A tip that leaves the surface springs back towards the baseline: its deflection rises and
    never again goes deeper than where it left (a freed lever rings about the baseline, with no
    more than the pull-off's amplitude). A retract that bends away from the line without rising
    (an adhesive contact that is not a straight line: the JPK QI curves of SPM 8.1, whose contact
    line flattens before the tip snaps off 9 nm lower) and then goes deeper than the retract had been
    up to ``i`` by more than ``thr`` is still in contact: the pull-off is the largest rise after that deeper point.
    A departure that is itself a jump (a surface pull-off followed by a tethered molecule that
    pulls deeper later) stays the pull-off, and so does a departure after which the retract comes back
    to its free baseline before the deeper point (:func:`left_surface`: a tether pulled after the tip
    left the surface; the JPK SMFS curve's unfolding peaks 267 nm away were taken for its pull-off).
    """
    if i + 1 >= dr.size or dr[i + 1] - dr[i] > thr:
        return i, rise
    after = np.flatnonzero(~saturated[i + 1:]) + i + 1
    if after.size < 2:
        return i, rise
    deep = int(after[np.argmin(dr[after])])
    if not dr[deep] < float(dr[: i + 1].min()) - thr:
        return i, rise
    if left_surface(dr, i + 1, deep, thr):
        return i, rise   # back at the free baseline before the deeper dip: that dip is a tether (analysis.tethers)
    j = largest_step(dr, deep, dr.size, +1.0)
    return (j, -math.inf) if j >= 0 else (i, rise)


def surface_end(dr: np.ndarray, lo: int, thr: float, hi: int | None = None) -> int:
    """Run sample from which the retract ``dr`` (deflection about zero force [m]) is back at its free
    baseline, looked for in ``[lo, hi)`` (``hi`` when never): its running median (the adhesion step's window,
    about 1/400 of the run) lies above ``-BACK_FRACTION thr`` (:mod:`.tethers`) for ``BACK_HOLD`` windows in
    a row."""
    from .tethers import BACK_FRACTION, BACK_HOLD, baseline_return, running_median

    hi = dr.size if hi is None else hi
    w = max(3, (dr.size // 400) | 1)
    if hi - lo < BACK_HOLD * w:
        return hi
    us = running_median(dr[lo:hi], w)
    return lo + baseline_return(us, 0, BACK_FRACTION * thr, BACK_HOLD * w)


def left_surface(dr: np.ndarray, lo: int, hi: int, thr: float) -> bool:
    """Whether the retract ``dr`` comes back to its free baseline between run samples ``lo`` and ``hi``
    (:func:`surface_end`)."""
    return surface_end(dr, lo, thr, hi) < hi


def pull_off_estimate(po: PullOff, spring_constant: float) -> float:
    """Pull-off force [N]: extrapolated along the contact line where the photodiode clipped it."""
    if po.saturated and math.isfinite(po.deflection_extrapolated):
        return spring_constant * po.deflection_extrapolated
    return po.force


def jump_warnings(ji: JumpIn, po: PullOff, spring_constant: float, clipped: bool = False,
                  retract: bool = True) -> list[str]:
    """Plain-words warnings on what the jumps could not give (``clipped``: the retract's contact is;
    ``retract`` False: the curve has no retract run, where no pull-off was looked for)."""
    k = spring_constant
    warn = []
    if not ji.found and ji.index >= 0:
        warn.append(f"no significant jump into contact (step {ji.significance:.2g} x the step noise): the tip "
                    f"crept into contact, or the jump is below the noise; contact begins at h = "
                    f"{ji.separation * 1e9:.3g} nm")
    elif not ji.found:
        warn.append("no jump into contact: the tip crept into contact (or the attraction is below the noise)")
    if clipped:
        warn.append("pull-off not in the record: the photodiode was saturated over the whole contact of the "
                    "retract run, so the tip left the surface while the signal was clipped; no pull-off "
                    "force, no adhesion")
    elif not po.found and retract:
        warn.append("no pull-off found on the retract run")
    elif po.saturated and math.isfinite(k):
        f_ext = k * po.deflection_extrapolated
        ext = (f", about {f_ext * 1e9:.3g} nN from the contact line extrapolated to the pull-off position"
               if math.isfinite(f_ext) else "")
        warn.append(f"photodiode saturated at pull-off: the pull-off force is a lower bound "
                    f"(|F| > {abs(po.force) * 1e9:.3g} nN){ext}")
    elif po.saturated:
        warn.append("photodiode saturated at pull-off: the pull-off force is a lower bound")
    return warn


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
    surface_energy: float = _u("J/m^2")
    radius: float = _u("m")
    surface_energy_assumed: float = _u("J/m^2")
    radius_given: float = _u("m")


def adhesion(pull_off: PullOff, spring_constant: float, *, radius: float | None = None,
             model: str = _E.model, hamaker: float = _E.hamaker, z0: float = _E.z0) -> AdhesionResult:
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
