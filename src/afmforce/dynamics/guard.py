"""Convergence guard: compare the key events with a second, tighter solve.

``simulate(..., check="auto")`` re-runs a cycle at a 10x tighter rtol and atol
when it lies in a risky regime (see :func:`risky`) and compares the events
that users read off a force curve. A difference above the tolerances of
:data:`EVENT_TOLERANCES` warns with :class:`ConvergenceWarning` (``"auto"``,
``"always"``) or raises :class:`~afmforce.errors.SolverError` (``"raise"``),
saying which event moved and by how much; either way the differences are in
``Trajectory.solver.event_errors`` (an estimate of each event's error). A
flagged run is solved once more, 100x tighter, so that the message can say
whether the 10x tighter run is converged (use it) or not (the events moved
again: a bouncing spring, for one, gives pull-off forces of -56, -10, -18 nN at
rtol 1e-4, 1e-5, 1e-6 and -56 nN converged).
"""

from __future__ import annotations

import functools
import math
import warnings

from ..errors import ParameterError, SolverError

__all__ = ["CHECKS", "EVENT_TOLERANCES", "ConvergenceWarning", "risky", "compare_events"]

#: Accepted values of ``check=``.
CHECKS = ("off", "auto", "always", "raise")

#: Event -> (absolute [SI], relative) tolerance: a difference counts when it exceeds
#: both (positions [m], force [N]).
EVENT_TOLERANCES = {
    "jump_in_position": (0.05e-9, 0.01),
    "contact_position": (0.05e-9, 0.01),
    "pull_off_position": (0.5e-9, 0.01),
    "hysteresis_offset": (0.01e-9, 0.01),
    "spike_height": (0.05e-9, 0.01),
    "pull_off_force": (0.1e-9, 0.01),
}

#: Damping ratio of the free mode below which a run is risky (bounces, ringing).
RISKY_DAMPING_RATIO = 0.05
#: Load-dependent friction at or above this zeta [kg/(s N^2)] is risky (stiff friction).
RISKY_ZETA = 1e12


class ConvergenceWarning(UserWarning):
    """Events of the run moved under a tighter second solve by more than their tolerance."""


@functools.lru_cache(maxsize=256)
def _free_mode(probe) -> tuple[float, float]:
    """(angular frequency of the beam's free mode [rad/s], lateral mobility [1/kg]) of a
    probe (cached: an eigenproblem, ~50 us, asked for by every unchecked run)."""
    from .models import beam_couplings, beam_matrices
    import numpy as np

    A, (ma, mb) = beam_matrices(probe.cantilever, probe.m_joint, probe.m_base)
    _, yq, _ = beam_couplings(probe.cantilever)
    minv = np.array([1.0 / ma, 1.0 / mb])
    w2 = np.linalg.eigvals(-minv[:, None] * A).real
    return math.sqrt(float(np.min(w2[w2 > 0]))), float(yq @ (minv * yq))


def _lever_drag_ratio(cfg) -> float:
    """Damping ratio of the free mode from the lever drag (issue 25) [-]: ``c mob_h / (2 w)``."""
    c = cfg.surface.lever_drag
    if c <= 0.0:
        return 0.0
    if cfg.model == "spring":
        return c / (2.0 * math.sqrt(cfg.probe.spring_constant * cfg.probe.mass))
    from .models import beam_couplings, beam_matrices
    w, _ = _free_mode(cfg.probe)
    _, (ma, mb) = beam_matrices(cfg.probe.cantilever, cfg.probe.m_joint, cfg.probe.m_base)
    hq, _, _ = beam_couplings(cfg.probe.cantilever)
    return c * (hq[0] ** 2 / ma + hq[1] ** 2 / mb) / (2.0 * w)


def damping_ratio(cfg) -> float:
    """Damping ratio of the free mode from lateral friction at rest [-] (0 for the spring).

    Drainage is not counted: far from the surface it vanishes. The drag on the lever body
    in a liquid (``lever_drag``, issue 25) is.
    """
    if cfg.model == "spring" or cfg.friction.law == "none":
        return _lever_drag_ratio(cfg)
    w, mob_y = _free_mode(cfg.probe)
    return cfg.friction.xi * mob_y / (2.0 * w) + _lever_drag_ratio(cfg)


def _stiff_load_friction(cfg) -> bool:
    return cfg.model == "beam" and cfg.friction.law == "load" and cfg.friction.zeta >= RISKY_ZETA


def risky(cfg) -> str:
    """Why the run is in a risky regime ('' when it is not)."""
    why = []
    zr = damping_ratio(cfg)
    if zr < RISKY_DAMPING_RATIO:
        why.append(f"free-mode damping ratio {zr:.3g} < {RISKY_DAMPING_RATIO}")
    if _stiff_load_friction(cfg):
        why.append(f"stiff load-dependent friction (zeta {cfg.zeta:.3g} kg/(s N^2))")
    return "; ".join(why)


def compare_events(a, b) -> dict[str, float]:
    """|a - b| for every event of :data:`EVENT_TOLERANCES` finite in both (SI)."""
    out = {}
    for name in EVENT_TOLERANCES:
        x, y = getattr(a, name), getattr(b, name)
        if math.isfinite(x) and math.isfinite(y):
            out[name] = abs(x - y)
        elif math.isfinite(x) != math.isfinite(y):
            out[name] = math.inf
    return out


def exceeded(errors: dict[str, float], b) -> list[str]:
    """Events whose difference exceeds both tolerances (b: the tighter run's events)."""
    bad = []
    for name, d in errors.items():
        atol, rtol = EVENT_TOLERANCES[name]
        ref = abs(getattr(b, name))
        if d > atol and not (math.isfinite(ref) and d <= rtol * ref):
            bad.append(name)
    return bad


def run_check(check: str, cfg, events, resolve):
    """Apply the guard; ``resolve(cfg)`` runs the second solve and returns its events.

    Returns (event_errors, note).
    """
    if check not in CHECKS:
        raise ParameterError(f"check must be one of {CHECKS}, got {check!r}")
    if check == "off":
        if _stiff_load_friction(cfg):
            warnings.warn(
                f"unchecked run with stiff load-dependent friction (zeta {cfg.zeta:.3g} kg/(s N^2)): "
                "the in-contact ringing rectifies into the friction and the hysteresis converges "
                "only at tight tolerances (Fig 5 with zeta 3e14: 0.46 nm at default, 0.84 nm "
                "converged at rtol 1e-7, atol 1e-15 m); pass check='auto' to measure the error, "
                "or tighten rtol/atol", ConvergenceWarning, stacklevel=3)
            return {}, "not checked (stiff load-dependent friction: warned)"
        return {}, "not checked"
    why = risky(cfg)
    if check == "auto" and not why:
        return {}, "not checked (not a risky regime)"
    tight = cfg.replace(rtol=max(cfg.rtol / 10.0, 1e-12), atol=cfg.atol / 10.0)
    b = resolve(tight)
    errors = compare_events(events, b)
    bad = exceeded(errors, b)
    note = f"checked against rtol {tight.rtol:.3g}, atol {tight.atol:.3g} m" + (
        f" ({why})" if why else "")
    if bad:
        # is the tighter run itself converged? One more solve, 100x tighter, only for a
        # flagged run: the message then says which run to trust, with the numbers
        tighter = cfg.replace(rtol=max(cfg.rtol / 100.0, 1e-12), atol=cfg.atol / 100.0)
        c = resolve(tighter)
        bad_tight = exceeded(compare_events(b, c), c)
        msg = (f"the events are not converged at rtol {cfg.rtol:.3g}, atol {cfg.atol:.3g} m: "
               f"{_values(bad, events, b, c)} (default vs 10x vs 100x tighter); ")
        if not bad_tight:
            msg += (f"the 10x tighter run (rtol {tight.rtol:.3g}, atol {tight.atol:.3g} m) agrees "
                    "with the 100x tighter one: use it")
            note += "; NOT converged: " + ", ".join(bad) + "; the 10x tighter run is"
        else:
            msg += (f"the 10x tighter run is not converged either ({', '.join(bad_tight)} moved "
                    "again at 100x tighter)" + (
                        f": in this regime ({why}) a bouncing or ringing contact can make "
                        "these events depend on every detail of the solve" if why else "")
                    + f"; tighten further (rtol {tighter.rtol / 10:.3g} or below) and compare, "
                    "and do not read these events off a single run")
            note += ("; NOT converged: " + ", ".join(bad) + "; nor at 10x tighter: "
                     + ", ".join(bad_tight))
        if check == "raise":
            raise SolverError(msg)
        warnings.warn(msg, ConvergenceWarning, stacklevel=3)
    return errors, note


def _values(names, *runs) -> str:
    """``name a vs b vs c unit`` for each event name over the runs' events."""
    out = []
    for n in names:
        unit, scale = ("nN", 1e9) if n == "pull_off_force" else ("nm", 1e9)
        out.append(f"{n} " + " vs ".join(f"{getattr(r, n) * scale:.4g}" for r in runs)
                   + f" {unit}")
    return ", ".join(out)
