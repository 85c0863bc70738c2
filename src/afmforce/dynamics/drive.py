"""Drive protocols: the piecewise-linear substrate position z(t) and the start state.

An approach at speed v from ``start`` up to ``turn`` (or until a load is
reached), an optional dwell, and a retract down to ``end``. Each piece is a
:class:`Segment` with ``z(t) = z_start + velocity (t - t_start)``; the
integrator treats every segment separately so that the kink of z(t) at the
turn is never stepped over (the solution is not smooth there).

The cantilever starts at rest in static equilibrium at ``start`` (no friction
at rest): ``k z2 = Fs(z2 - z)`` on the out-of-contact branch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import ParameterError
from .radau import APPROACH, DWELL, RETRACT
from .static import static_deflection, surface_jump_in, surface_static_deflection, \
    surface_static_force

__all__ = ["Segment", "segments", "initial_state", "SEGMENT_NAMES"]

SEGMENT_NAMES = {APPROACH: "approach", RETRACT: "retract", DWELL: "dwell"}


@dataclass(frozen=True)
class Segment:
    """One linear piece of the drive.

    Attributes
    ----------
    kind : int
        0 approach, 1 retract, 2 dwell (``Trajectory.segment`` codes).
    t_start, t_end : float
        Time span [s]; for an approach that turns at a load, ``t_end`` is the
        latest possible turn (at ``turn``).
    z_start : float
        Drive position at ``t_start`` [m].
    velocity : float
        dz/dt [m/s]: positive on approach, negative on retract, 0 in a dwell.
    """

    kind: int
    t_start: float
    t_end: float
    z_start: float
    velocity: float

    @property
    def z_end(self) -> float:
        """Drive position at ``t_end`` [m]."""
        return self.z_start + self.velocity * (self.t_end - self.t_start)

    def position(self, t):
        """z(t) [m] on this segment."""
        return self.z_start + self.velocity * (np.asarray(t, float) - self.t_start)


def approach_segment(cfg) -> Segment:
    """The approach from ``start`` to ``turn`` (the latest turn for a load turn)."""
    d = cfg.drive
    return Segment(APPROACH, 0.0, (d.turn - d.start) / d.velocity, d.start, d.velocity)


def segments(cfg, t_turn: float | None = None, z_turn: float | None = None) -> list[Segment]:
    """Approach, dwell (if any) and retract, given the actual turn time and position."""
    d = cfg.drive
    app = approach_segment(cfg)
    if t_turn is None:
        t_turn, z_turn = app.t_end, app.z_end
    app = Segment(APPROACH, 0.0, t_turn, d.start, d.velocity)
    out = [app]
    t = t_turn
    if d.dwell > 0:
        out.append(Segment(DWELL, t, t + d.dwell, z_turn, 0.0))
        t += d.dwell
    vr = d.retract_speed
    out.append(Segment(RETRACT, t, t + (z_turn - d.end) / vr, z_turn, -vr))
    return out


def start_deflection(cfg) -> float:
    """Static (friction-free) deflection z2 at the start position [m].

    Use ``cfg.start_deflection`` (solved once per configuration).

    Raises
    ------
    ParameterError
        If the start position is at or past the static jump-in, or the
        equilibrium separation is already below ``contact_separation``.
    """
    k = cfg.force_constant
    s, start = cfg.surface, cfg.drive.start
    hj, zj, _ = surface_jump_in(k, s)     # eq 2 on the geometry (+ double layer, issue 25)
    if math.isfinite(zj) and start >= zj:
        raise ParameterError(
            f"start {start * 1e9:.4g} nm is already in contact: the static jump-in is at "
            f"z = {zj * 1e9:.4g} nm (h = {hj * 1e9:.4g} nm); start further out (more negative)")
    if s.eq2_only:
        d = _static_start(start, k, s.paper_radius, s.hamaker, s.z0)
    else:
        d = surface_static_deflection(start, k, s)
    h = d - start
    if not h > cfg.solver.contact_separation:
        raise ParameterError(
            f"start {start * 1e9:.4g} nm is already in contact (equilibrium separation "
            f"{h * 1e9:.3g} nm); start further out (more negative)")
    return d


@lru_cache(maxsize=1024)
def _static_start(start: float, k: float, radius: float, hamaker: float, z0: float) -> float:
    """The static deflection at ``start`` (a Brent solve), once per parameter set [m]."""
    return float(static_deflection(start, k, radius, hamaker, z0))


def initial_state(cfg) -> np.ndarray:
    """State vector at rest in static equilibrium at ``start``.

    spring: ``(x, x')``; beam: ``(q_alpha, q_beta, q_alpha', q_beta')`` with
    ``(x, theta) = G P (Fz, 0)`` (eqs 7-10), ``q_alpha = x``,
    ``q_beta = L1 theta + 3x/2``.
    """
    d = cfg.start_deflection
    if cfg.model == "spring":
        return np.array([d, 0.0])
    cant, s = cfg.cantilever, cfg.surface
    h = d - cfg.drive.start      # eq 2 (forces.vdw_force) on a scalar
    r = s.paper_radius
    fz = -(s.hamaker * r / (12.0 * h * h)) * (1.0 - 0.25 * (s.z0 / h) ** 6)
    if not s.eq2_only:
        fz = float(surface_static_force(s, h)[0])
    gx, gt = _unit_load_response(cant)
    x, theta = gx * fz, gt * fz
    return np.array([x, cant.L1 * theta + 1.5 * x, 0.0, 0.0])


@lru_cache(maxsize=256)
def _unit_load_response(cant) -> tuple[float, float]:
    """(x, theta) per unit Fz: the first column of ``G P`` (eqs 7-10) [m/N, 1/N]."""
    x, theta = cant.beam_compliance @ cant.force_to_load @ np.array([1.0, 0.0])
    return float(x), float(theta)
