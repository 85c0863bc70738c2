"""Dynamic diagnosis of a measured curve: is it quasi-static? (paper section 2.1, 3.2).

For the curve's speed, spring constant and deflection resolution:

* inertia parameter ``R = v |Fs'| / (4 f k dx)`` (eq 3) at the jump into
  contact, where the static gradient equals k (so ``R = v / (4 f dx)``);
  inertia is measurable when R > 1;
* inertial lag ``dx = v / (4 f)`` (eq 4);
* the jump-in separation against the static one predicted by the fitted van der
  Waals law: jumping in from farther out is the paper's evidence of dynamics or
  of an extra attraction (section 3.2, "too large by at least 1 nm");
* friction's signature on the compliance lines: a parallel offset in the
  friction direction (viscous friction's, proportional to xi v, spec section 7)
  goes with an underestimated precontact attraction (section 2.3, Figs 5-6) --
  or the instrument's hysteresis mimics it (section 3.1); the data alone cannot
  tell. Non-parallel lines (friction proportional to load, or a soft contact)
  are reported, not flagged;
* the precontact attraction against the adhesion: for the law of eq 2 the
  pull-off force of a rigid contact is the largest attraction
  ``-A R / (16 z0^2)``, so ``A R`` fitted on the approach should match
  ``16 z0^2 |F_pull|``; a much weaker approach attraction is what friction
  does (spec section 7: -0.94 instead of -1.96 nm at 1e-9 N) -- or an extra
  adhesion (capillarity, deformation) beyond van der Waals.

A run judged dynamic is *flagged*: its van der Waals fit is marked unreliable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..constants import Z0
from ._numeric import ptp, robust_line_thin
from ._units import unit as _u

__all__ = ["DEAD_ZONE_MIN_BIAS", "DynamicDiagnosis", "dead_zone", "diagnose_curve", "drive_start", "run_velocity"]


@dataclass(frozen=True)
class DynamicDiagnosis:
    """Plain-words dynamic diagnosis with the numbers behind it.

    Attributes
    ----------
    velocity : float  approach speed [m/s]
    spring_constant : float  [N/m]
    resonance_frequency : float  [Hz] (NaN if unknown)
    resolution : float  deflection resolution [m]
    force_gradient : float  measured |dF/dh| where the tip meets the surface [N/m] (NaN: not measured)
    force_gradient_method : str  how it was measured
    inertia_parameter : float  eq 3 [-]
    inertial_lag : float  eq 4 [m]
    jump_in_separation : float  measured [m]
    static_jump_in_separation : float  from the fitted law [m]
    jump_excess : float  measured - static [m]
    attraction_ratio : float  fitted A R / (16 z0^2 |F_pull|) [-]
    dynamic : bool  flagged as dynamic
    verdict : str
    assessed : bool
        The run could be judged: flagged dynamic, or both inertia (eq 3) and friction
        (the compliance lines) assessed. Otherwise ``dynamic`` is False without evidence
        and the verdict starts with "dynamics not assessed".
    """

    velocity: float = _u("m/s")
    spring_constant: float = _u("N/m")
    resonance_frequency: float = _u("Hz")
    resolution: float = _u("m")
    force_gradient: float = _u("N/m")
    force_gradient_method: str
    inertia_parameter: float = _u("")
    inertial_lag: float = _u("m")
    jump_in_separation: float = _u("m")
    static_jump_in_separation: float = _u("m")
    jump_excess: float = _u("m")
    attraction_ratio: float = _u("")
    dynamic: bool
    verdict: str
    assessed: bool = True


def dead_zone(zm: np.ndarray) -> int:
    """Samples at the start of a run in which a measured (sensor) position has not moved [-].

    A position sensor with backlash (a play operator, e.g. the ``paper`` instrument's
    :class:`afmforce.instrument.PositionDetector`; the Park scanner of the paper, Fig 8) stands
    still after each reversal until the drive has taken up the play, then follows it at a
    constant lag. These samples are no measure of the drive: a line through them is tilted (the
    ``paper`` preset at 8 um/s: 6.90 um/s from the whole run, 8.00 without its first 15 nm).
    The run's first samples within half a sensor step plus 4 noise rms of its first value are
    the dead zone; 0 where it would leave fewer than a third of the run (or 10 samples).
    """
    zm = np.asarray(zm, float)
    n = zm.size
    if n < 30:
        return 0
    d = np.abs(np.diff(zm))
    step = float(np.median(d[d > 0])) if np.any(d > 0) else 0.0
    d2 = np.diff(zm, 2)
    noise = float(np.median(np.abs(d2 - np.median(d2)))) * 1.4826 / math.sqrt(6.0)
    tol = 0.5 * step + 4.0 * noise
    moved = np.flatnonzero(np.abs(zm - zm[0]) > tol)
    if moved.size == 0:
        return 0
    k = int(moved[0]) - 1          # the last sample still at rest is kept: the play's kink
    return k if k > 0 and n - k >= max(10, n // 3) else 0


#: A dead zone (:func:`dead_zone`) is left out of a run's line only where it tilts the line by more than this
#: fraction of the speed [-]. Real ramps start within the tolerance for 1-7 samples (the turn, the noise): on
#: the 64 real and test files those zones moved the speed by at most 0.13 % (JPK force-save-3); the ``paper``
#: preset's play by 13.7 % at 8 um/s and 1.4 % at 2 um/s (approach; at 0.5 um/s its 0.34 % is no better left
#: out: -0.11 % from the whole run, -0.46 % without it).
DEAD_ZONE_MIN_BIAS = 0.005


def drive_start(t: np.ndarray, zm: np.ndarray) -> int:
    """First sample of a run's measured (sensor) position that measures the drive [-]: the end of its
    :func:`dead_zone` where leaving that out changes the run's speed by more than
    :data:`DEAD_ZONE_MIN_BIAS`, else 0: the analysis's speed (:func:`run_velocity`). The fit's line
    (:func:`afmforce.fit.ramp.drive_line`) leaves out every :func:`dead_zone` (it drives the model along
    the line: its position matters too); the speeds differ by under that fraction."""
    return drive_start_slopes(t, zm)[0]


def drive_start_slopes(t: np.ndarray, zm: np.ndarray, dead: int | None = None) -> tuple[int, float, float]:
    """:func:`drive_start` and the two speeds it compared [m/s]: the robust slope of the whole run and of the
    run after its :func:`dead_zone` (``dead``: that zone when the caller has it), both NaN where there is no
    dead zone (then not computed). The speed of the run from the returned start is the slope of that part
    (:meth:`~.state.State.velocity` takes it instead of fitting that line a third time)."""
    t = np.asarray(t, float)
    zm = np.asarray(zm, float)
    k = dead_zone(zm) if dead is None else dead
    if not k:
        return 0, math.nan, math.nan
    whole, rest = _slope(t, zm), _slope(t[k:], zm[k:])
    return (k if abs(rest - whole) > DEAD_ZONE_MIN_BIAS * abs(rest) else 0), whole, rest


def _slope(t: np.ndarray, z: np.ndarray) -> float:
    if t.size < 3 or ptp(t) == 0:
        return math.nan
    return float(robust_line_thin(t - t[0], z)[1])


def run_velocity(t: np.ndarray, z: np.ndarray, measured: bool = False) -> float:
    """Speed of a run [m/s]: robust slope of position against time.

    Parameters
    ----------
    t : array  [s]
    z : array  [m]
    measured : bool
        ``z`` is a measured (sensor) position: its dead zone after the turn is left out
        (:func:`drive_start`), as the dynamic fit does (:func:`afmforce.fit.ramp.drive_line`).
        A nominal (commanded) position has none: the whole run is fitted.
    """
    if measured:
        k = drive_start(t, z)
        t, z = t[k:], z[k:]
    if t.size < 3 or ptp(t) == 0:
        return math.nan
    _, b, *_ = robust_line_thin(t - t[0], z)
    return float(abs(b))


def _inertia(velocity, gradient, f, k, dx):
    try:
        from ..diagnostics import inertia_parameter, inertial_lag
    except ImportError:  # pragma: no cover - diagnostics is part of the package
        return (abs(velocity) * abs(gradient) / (4 * f * k * dx), abs(velocity) / (4 * f))
    return float(inertia_parameter(velocity, gradient, f, k, dx)), float(inertial_lag(velocity, f))


def diagnose_curve(*, velocity: float, spring_constant: float, resonance_frequency: float | None,
                   resolution: float, force_gradient: float = math.nan, force_gradient_method: str = "",
                   jump_in_separation: float = math.nan,
                   static_jump_in_separation: float = math.nan, jump_tolerance: float = 1e-9,
                   jump_fraction: float = 0.25, sample_step: float = 0.0, friction: str | None = None,
                   friction_verdict: str = "", hamaker_radius: float = math.nan,
                   pull_off_force: float = math.nan, contact_separation: float = math.nan,
                   attraction_ratio: float = 0.75, quality_factor: float = math.nan,
                   air_quality: float = 20.0) -> DynamicDiagnosis:
    """Combine eq 3, eq 4 and the jump-in distance into a verdict.

    Parameters
    ----------
    velocity : float  [m/s]
    spring_constant : float  [N/m]
    resonance_frequency : float or None  [Hz]
    resolution : float  [m]
    force_gradient : float
        Measured |dF/dh| [N/m] (eq 3 needs it; never replaced by a default).
    force_gradient_method : str
        How it was measured (or why not).
    jump_in_separation, static_jump_in_separation : float  [m]
    jump_tolerance : float
        Excess over the static jump-in separation that counts [m] ...
    jump_fraction : float
        ... and as a fraction of the static value [-] (both must be exceeded).
    sample_step : float
        Position step between samples [m], added to ``jump_tolerance`` (the last
        sample before the jump may lie up to one step outside the static point).
    friction, friction_verdict : str
        Kind and words of the :class:`~.compliance.FrictionSignature` (``"not detected"``:
        coincident lines, which bound friction but never exclude it).
    hamaker_radius : float
        A R of the approach fit [J m].
    pull_off_force : float
        [N] (negative).
    contact_separation : float
        z0 of eq 2 [m] (NaN or 0: 0.35 nm).
    attraction_ratio : float
        Flag when fitted A R < this x ``16 z0^2 |F_pull|`` [-].
    quality_factor : float
        Q of the free resonance (the file's thermal Q) [-]: at or above ``air_quality`` the
        curve was recorded in air.

    An early jump-in or an attraction weaker than the pull-off implies is dynamics (friction,
    inertia) or an extra attraction. In air (a meniscus forms at the contact) it is named likely
    capillary; elsewhere it flags the run dynamic. Inertia excluded (eq 3 < 1) leaves friction:
    coincident compliance lines do not exclude it (the paper's xi = 0.1 kg/s at 0.1 um/s offsets
    them by 0.5 nm while hiding about half the precontact attraction, Figs 5-6).
    """
    nan = math.nan
    f = nan if resonance_frequency is None else float(resonance_frequency)
    k = float(spring_constant)
    words = []
    dynamic = False
    r_par, lag, grad = nan, nan, float(force_gradient)
    if not (math.isfinite(velocity) and velocity > 0):
        words.append("inertia not assessed: speed unknown (no time base)")
    elif not (math.isfinite(f) and f > 0):
        words.append("inertia not assessed: resonance frequency unknown (not in the file; give "
                     "`resonance_frequency`)")
    elif not (math.isfinite(resolution) and resolution > 0):
        words.append("inertia not assessed: deflection resolution unknown")
    elif not (math.isfinite(k) and k > 0):
        words.append("inertia not assessed: spring constant unknown")
    elif not (math.isfinite(grad) and grad > 0):
        words.append(f"inertia not assessed: force gradient not measured ({force_gradient_method or 'unknown'})")
    else:
        r_par, lag = _inertia(velocity, grad, f, k, resolution)
        nums = (f"v = {velocity * 1e9:.3g} nm/s, |F'| = {grad:.3g} N/m ({force_gradient_method}), f = {f:.4g} Hz, "
                f"k = {k:.3g} N/m, dx = {resolution * 1e12:.3g} pm")
        if r_par > 1:
            dynamic = True
            words.append(f"dynamic: inertia parameter {r_par:.3g} > 1 (eq 3; {nums}), lag about {lag * 1e9:.3g} nm "
                         "(eq 4): the static force law is distorted near contact")
        else:
            words.append(f"quasi-static: inertia parameter {r_par:.3g} < 1 (eq 3; {nums}), lag about "
                         f"{lag * 1e9:.3g} nm (eq 4)")
    excess = jump_in_separation - static_jump_in_separation
    in_air = math.isfinite(quality_factor) and quality_factor >= air_quality
    extra = f"likely capillary (in air: quality factor {quality_factor:.3g})" if in_air else ""
    # inertia excluded leaves friction, which coincident compliance lines cannot exclude (Figs 5-6)
    no_inertia = math.isfinite(r_par) and r_par <= 1
    friction_words = (f"friction (inertia excluded, eq 3: {r_par:.2g} < 1; coincident compliance lines do not "
                      "exclude friction, Figs 5-6)" if no_inertia else "")
    if (math.isfinite(excess) and excess > jump_tolerance + abs(sample_step)
            and excess > jump_fraction * static_jump_in_separation):
        what = (f"jump-in at {jump_in_separation * 1e9:.3g} nm, {excess * 1e9:.3g} nm farther out than "
                f"the static {static_jump_in_separation * 1e9:.3g} nm of the fitted law")
        if extra:
            words.append(f"{what}: {extra}")
        else:
            dynamic = True
            words.append(f"{what}: " + (f"{friction_words} or an extra attraction (capillarity)" if no_inertia
                                         else "dynamic effects (friction, inertia) or an extra attraction "
                                              "(capillarity)"))
            friction_words = "friction" if no_inertia else ""  # said once
    if friction == "constant":  # viscous friction's offset grows with xi v (spec section 7)
        dynamic = True
        words.append(f"friction signature ({friction_verdict}): friction underestimates the precontact "
                     "attraction (Figs 5-6) unless the offset is the instrument's hysteresis")
    elif friction == "load-proportional":
        words.append(f"{friction_verdict} (static friction changes k and beta, eqs 18-19)")
    elif friction == "opposite":
        words.append("compliance lines offset against friction's direction: an instrument artefact")
    elif friction in ("nonlinear", "undetermined", "not assessed"):
        words.append(friction_verdict)
    elif friction == "pinned":
        dynamic = True
        words.append("negative compliance slope: pinned tip, forces of the wrong sign (eqs 20-21)")
    z0 = contact_separation if math.isfinite(contact_separation) and contact_separation > 0 else Z0
    ar_pull = 16.0 * z0 * z0 * abs(pull_off_force) if math.isfinite(pull_off_force) else math.nan
    ratio = hamaker_radius / ar_pull if math.isfinite(ar_pull) and ar_pull > 0 else math.nan
    if math.isfinite(ratio) and ratio < attraction_ratio:
        what = f"the approach attraction is {ratio:.2f} x what the pull-off implies (A R = 16 z0^2 |F|)"
        if extra:
            words.append(f"{what}: an extra adhesion, {extra}")
        else:
            dynamic = True
            words.append(f"{what}: underestimated by " + (f"{friction_words}, or an extra adhesion (capillarity)"
                                                          if no_inertia else
                                                          "friction or speed, or an extra adhesion (capillarity)"))
    # "not dynamic" needs both mechanisms excluded: inertia (eq 3) and friction (the compliance lines);
    # the jump-in and attraction tests can only flag a dynamic run, not clear one
    # "not detected" is assessed: the lines were compared (and bound the friction they allow), not cleared
    friction_assessed = friction in ("not detected", "constant", "load-proportional", "opposite", "pinned")
    assessed = dynamic or (math.isfinite(r_par) and friction_assessed)
    if not assessed:
        missing = [w for w, ok in (("inertia", math.isfinite(r_par)), ("friction", friction_assessed)) if not ok]
        words.insert(0, f"dynamics not assessed ({' and '.join(missing)} not assessed, nothing flags the run)")
    return DynamicDiagnosis(float(velocity), k, f, float(resolution), grad, force_gradient_method, float(r_par), float(lag),
                            float(jump_in_separation), float(static_jump_in_separation), float(excess),
                            float(ratio), dynamic, "; ".join(words), assessed)
