"""Lever damping (issue 23): the quality factor of the lever in its medium as damping
coefficients of the dynamical models (:mod:`afmforce.dynamics.models`; docs/dynamics.md,
"Cantilever damping").

* spring: viscous damping ``c = m omega0 / Q`` (:func:`spring_damping`);
* beam: Rayleigh damping ``C = alpha M + beta K`` of its mass and stiffness matrices in the
  generalised coordinates, with alpha and beta chosen so that both free modes have the
  requested quality factors (:func:`beam_damping`).

None is the paper's undamped model (zeros).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["spring_damping", "free_modes", "rayleigh_coefficients", "beam_damping"]


def spring_damping(spring_constant: float, mass: float, quality_factor: float | None) -> float:
    """Viscous damping ``c = m omega0 / Q = sqrt(k m) / Q`` of the spring [kg/s] (0 for Q None)."""
    if quality_factor is None:
        return 0.0
    return math.sqrt(spring_constant * mass) / quality_factor


def free_modes(A, masses) -> np.ndarray:
    """Angular frequencies of the beam's two free modes, ascending [rad/s] (eigenvalues of
    ``M^-1 K``, ``K = -A``, ``M = diag(masses)``; closed form of the 2x2 problem)."""
    ma, mb = masses
    a, b, c, d = -A[0, 0] / ma, -A[0, 1] / ma, -A[1, 0] / mb, -A[1, 1] / mb
    tr, det = a + d, a * d - b * c
    disc = math.sqrt(max(tr * tr / 4.0 - det, 0.0))
    return np.sqrt([tr / 2.0 - disc, tr / 2.0 + disc])


def rayleigh_coefficients(w1: float, w2: float, q1: float | None,
                          q2: float | None) -> tuple[float, float]:
    """(alpha [1/s], beta [s]) of ``C = alpha M + beta K`` giving modes ``w1 < w2`` [rad/s]
    the quality factors ``q1``, ``q2``.

    A mode of a Rayleigh-damped system keeps its shape and gets the damping ratio
    ``zeta_i = alpha / (2 w_i) + beta w_i / 2``; with ``zeta_i = 1 / (2 Q_i)`` the two
    equations give ``alpha = 2 w1 w2 (zeta1 w2 - zeta2 w1) / (w2^2 - w1^2)``,
    ``beta = 2 (zeta2 w2 - zeta1 w1) / (w2^2 - w1^2)``. ``C`` is positive definite for
    any positive Q (in modal coordinates it is ``diag(2 zeta_i w_i)``), even where alpha
    or beta is negative; a Q of None leaves its mode undamped (zeta 0).
    """
    z1 = 0.0 if q1 is None else 0.5 / q1
    z2 = 0.0 if q2 is None else 0.5 / q2
    d = w2 * w2 - w1 * w1
    return 2.0 * w1 * w2 * (z1 * w2 - z2 * w1) / d, 2.0 * (z2 * w2 - z1 * w1) / d


def beam_damping(A, masses, quality_factor: float | None,
                 quality_factor_2: float | None = None) -> np.ndarray:
    """Rayleigh damping matrix ``C = alpha M + beta K`` [kg/s] of the beam (issue 23).

    ``K = -A`` and ``M = diag(masses)`` in the generalised coordinates (q_alpha,
    q_beta); alpha and beta from :func:`rayleigh_coefficients`, so that the first and
    second free modes have the quality factors ``quality_factor`` and
    ``quality_factor_2`` (None: the first one's). ``quality_factor`` None: the first mode
    undamped; both None: zeros (the paper's model).
    """
    if quality_factor is None and quality_factor_2 is None:
        return np.zeros((2, 2))
    w1, w2 = free_modes(A, masses)
    q2 = quality_factor if quality_factor_2 is None else quality_factor_2
    alpha, beta = rayleigh_coefficients(float(w1), float(w2), quality_factor, q2)
    return alpha * np.diag(masses) - beta * np.asarray(A)
