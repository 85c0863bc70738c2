"""Packed model parameters of a configuration (what the compiled vector field reads), cached
per cantilever geometry, and the highest free mode frequency."""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .. import surface_laws
from .config import SimulationConfig
from .damping import beam_damping
from .models import MODEL_BEAM, beam_matrices, pack_beam, pack_spring

__all__ = ["parameter_vector", "fill_liquid", "free_frequency_max", "H_GUARD_FRACTION"]

#: Trial states with a separation below this fraction of z0 are rejected by the
#: force law (eq 2 would turn attractive again at h -> 0; at 0.2 z0 the
#: soft-wall repulsion of the default parameters is already ~3 mN).
H_GUARD_FRACTION = 0.2


def free_frequency_max(p, model) -> float:
    """Highest free (out-of-contact) mode frequency [Hz] of the packed model."""
    from . import models as M
    if model == M.MODEL_SPRING:
        w2 = p[M.K] * p[M.INV_M]
    else:   # eigenvalues of -diag(1/m) A (2x2, closed form)
        a, b = -p[M.INV_MA] * p[M.A00], -p[M.INV_MA] * p[M.A01]
        c, d = -p[M.INV_MB] * p[M.A10], -p[M.INV_MB] * p[M.A11]
        tr, det = a + d, a * d - b * c
        disc = math.sqrt(max(tr * tr / 4.0 - det, 0.0))
        w2 = max(abs(tr / 2.0 + disc), abs(tr / 2.0 - disc))
    return math.sqrt(w2) / (2.0 * math.pi)


@lru_cache(maxsize=256)
def _beam_template(cantilever, m_joint: float, m_base: float) -> np.ndarray:
    """The geometry/mass part of the beam's parameter vector (surfaces filled per run)."""
    p = pack_beam(cantilever, m_joint=m_joint, m_base=m_base, radius=1.0, hamaker=0.0, z0=1.0,
                  viscosity=0.0, xi=0.0, zeta=0.0, h_guard=0.0)
    p.flags.writeable = False
    return p


@lru_cache(maxsize=256)
def _beam_damping(cantilever, m_joint: float, m_base: float, q1, q2) -> tuple[float, ...]:
    """The beam's Rayleigh damping matrix (C00, C01, C10, C11) [kg/s] (issue 23), per geometry."""
    A, masses = beam_matrices(cantilever, m_joint, m_base)
    return tuple(float(c) for c in beam_damping(A, masses, q1, q2).ravel())


@lru_cache(maxsize=256)
def _beam_fmax(cantilever, m_joint: float, m_base: float) -> float:
    return free_frequency_max(_beam_template(cantilever, m_joint, m_base), MODEL_BEAM)


def parameter_vector(cfg: SimulationConfig) -> np.ndarray:
    """Packed model parameters for the compiled vector field."""
    s, probe = cfg.surface, cfg.probe
    guard = H_GUARD_FRACTION * s.z0
    radius = s.paper_radius      # the paper's sphere-sphere formulas; 2R on a flat (issue 25)
    if cfg.model == "spring":
        p = pack_spring(spring_constant=probe.spring_constant, mass=probe.mass, radius=radius,
                        hamaker=s.hamaker, z0=s.z0, viscosity=s.viscosity, h_guard=guard,
                        quality_factor=probe.quality_factor)
        return fill_liquid(p, s)
    from . import models as M
    xi, zeta = cfg.friction.coefficients
    p = _beam_template(probe.cantilever, probe.m_joint, probe.m_base).copy()
    # the same values as pack_beam(cfg.cantilever, ...) fills in
    p[M.AR] = s.hamaker * radius
    p[M.Z0] = s.z0
    p[M.CD] = 6.0 * math.pi * s.viscosity * radius**2 / 4.0
    p[M.H_GUARD] = guard
    p[M.XI] = xi
    p[M.ZETA] = zeta
    if probe.quality_factor is not None or probe.quality_factor_2 is not None:
        p[M.C00:M.C11 + 1] = _beam_damping(probe.cantilever, probe.m_joint, probe.m_base,
                                           probe.quality_factor, probe.quality_factor_2)
    return fill_liquid(p, s)


def fill_liquid(p: np.ndarray, s) -> np.ndarray:
    """Fill the liquid entries of ``p`` (double layer, slip, lever drag; issue 25) from the
    :class:`~afmforce.dynamics.parts.Surface` ``s``; all zero in air (the paper's model)."""
    from . import models as M
    from ..forces import EPS0, effective_radius
    if s.double_layer != "none":
        p1 = s.surface_potential
        p2 = p1 if s.surface_potential_2 is None else s.surface_potential_2
        kappa = 1.0 / s.debye_length
        pref = 2.0 * math.pi * float(effective_radius(s.radius, s.geometry)) * 0.5 * s.permittivity * EPS0 * kappa
        p[M.DL_KAPPA] = kappa
        p[M.DL_A] = pref * 2.0 * p1 * p2
        exact = s.double_layer != "weak_overlap"
        p[M.DL_EXACT] = 1.0 if exact else 0.0
        sign = -1.0 if s.double_layer == "constant_potential" else 1.0
        p[M.DL_B] = pref * sign * (p1 * p1 + p2 * p2) if exact else 0.0
    p[M.SLIP6B] = 6.0 * s.slip_length
    p[M.LEVER] = s.lever_drag
    p[M.LEVER_H] = s.lever_height
    if s.laws:
        p[M.P_LAWS:] = surface_laws.pack(s.law_values, s.radius_eff)
    return p


