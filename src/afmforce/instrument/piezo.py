"""The piezo drive: nominal (commanded) position versus true substrate position.

Model
-----
The commanded position ``u`` (drive voltage times the nominal gain) moves the
substrate to the true position ``z`` through two operators in series
(a Hammerstein structure, the usual description of rate-dependent piezo
hysteresis):

1. **Prandtl-Ishlinskii (PI) hysteresis** ``w = H[u] = g (p0 u + sum_i p_i F_{r_i}[u])``,
   a weighted sum of play operators ``F_r`` (Krasnosel'skii & Pokrovskii,
   *Systems with Hysteresis*, Springer 1989; for piezo actuators Kuhnen,
   *Eur. J. Control* 9, 407 (2003)). Thresholds ``r_i = i r_max / n``
   (i = 1..n) carry equal weights ``p_i = alpha / n`` and ``p0 = 1 - alpha``:
   on leaving a turning point the slope rises from ``g (1 - alpha)`` to ``g``
   over a distance ``2 r_max`` -- the nonlinearity that makes the fringes in
   the paper's Fig 7A unevenly spaced -- and a major loop has the width
   ``2 S``, ``S = alpha r_max (n + 1) / (2 n)``, in nominal position.
2. **Creep** ``z = C[w] = c0 w + sum_j c_j L_j[w]``, ``tau_j dL_j/dt = w - L_j``,
   ``c0 = 1 - sum_j c_j > 0``: the linear creep operator of Krejčí & Kuhnen
   (*IEE Proc. Control Theory Appl.* 148, 185 (2001)) with a few relaxation
   times. On a ramp at speed ``v`` the substrate lags the command by
   ``v sum_j c_j tau_j`` once the transients have died, so the loop widens
   with speed: in steady state its width in nominal position is
   ``2 S + 2 v sum_j c_j tau_j / g`` (:meth:`Piezo.steady_loop_width`).

Both operators are exactly invertible: the inverse of a PI operator is a PI
operator with thresholds ``r'_i = sum_{j<=i} p_j (r_i - r_j)`` and weights
``p'_i = -p_i / (P_i P_{i-1})``, ``P_i = sum_{j<=i} p_j`` (Kuhnen 2003), and
the creep operator, discretised exactly for inputs linear between samples
(first-order hold), is inverted sample by sample. :meth:`Piezo.nominal_from_true`
(used by the instrument: the trajectory gives the true position) and
:meth:`Piezo.true_from_nominal` (for users correcting measured data) are
inverses of each other on the same time grid, to rounding.

Initial state (a **decision**): before the first sample the piezo was at rest
(creep relaxed) after a move in the direction opposite to its first motion,
i.e. the first sample is a turning point of the hysteresis, and the nominal
position equals the true one there. This is the state of an instrument that
held the surfaces still before the curve, as in the paper's Fig 7 protocol.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._fields import meta as _meta
from .._validate import positive
from ..errors import ParameterError

__all__ = ["Piezo", "pi_inverse_parameters", "initial_direction"]


@dataclass(frozen=True)
class Piezo:
    """Nonlinear, hysteretic, creeping piezo drive (see the module docstring).

    Parameters
    ----------
    gain : float
        Ratio of true to nominal displacement on long strokes [-] (1: the
        nominal gain is right there).
    hysteresis : float
        alpha, the share of the slope carried by the play operators [-], in [0, 1).
    hysteresis_span : float
        r_max, the largest play threshold [m].
    n_plays : int
        Number of play operators n.
    creep_amplitudes : tuple of float
        c_j, weights of the relaxation terms [-] (>= 0, sum < 1).
    creep_times : tuple of float
        tau_j, their relaxation times [s] (> 0, same length).
    """

    gain: float = field(default=1.0,
          metadata=_meta("dimensionless", "", "true/nominal displacement ratio on long strokes"))
    hysteresis: float = field(default=0.0,
          metadata=_meta("dimensionless", "", "Prandtl-Ishlinskii play share alpha, 0 <= alpha < 1"))
    hysteresis_span: float = field(default=1e-6,
          metadata=_meta("length", "m", "largest play threshold r_max"))
    n_plays: int = field(default=10, metadata=_meta("integer", "", "number of play operators"))
    creep_amplitudes: tuple[float, ...] = field(default=(),
          metadata=_meta("dimensionless", "", "creep weights c_j (sum < 1)"))
    creep_times: tuple[float, ...] = field(default=(),
          metadata=_meta("time", "s", "creep relaxation times tau_j"))

    def __post_init__(self) -> None:
        set_ = lambda n, v: object.__setattr__(self, n, v)  # noqa: E731
        set_("gain", positive("piezo gain", self.gain))
        a = float(self.hysteresis)
        if not (math.isfinite(a) and 0.0 <= a < 1.0):
            raise ParameterError(f"piezo hysteresis must lie in [0, 1), got {self.hysteresis!r}")
        set_("hysteresis", a)
        set_("hysteresis_span", positive("piezo hysteresis_span", self.hysteresis_span, "m"))
        n = self.n_plays
        if isinstance(n, bool) or int(n) != n or int(n) < 1:
            raise ParameterError(f"piezo n_plays must be a whole number >= 1, got {n!r}")
        set_("n_plays", int(n))
        amps = tuple(float(c) for c in np.atleast_1d(np.asarray(self.creep_amplitudes, float)))
        times = tuple(float(t) for t in np.atleast_1d(np.asarray(self.creep_times, float)))
        if len(amps) != len(times):
            raise ParameterError(
                f"piezo creep_amplitudes ({len(amps)}) and creep_times ({len(times)}) need the same length")
        if any(not math.isfinite(c) or c < 0 for c in amps) or sum(amps) >= 1.0:
            raise ParameterError(
                f"piezo creep_amplitudes must be >= 0 with a sum below 1, got {list(amps)}")
        for t in times:
            positive("piezo creep_times", t, "s")
        set_("creep_amplitudes", amps)
        set_("creep_times", times)

    # --- PI parameters -------------------------------------------------------
    @property
    def thresholds(self) -> np.ndarray:
        """Play thresholds r_i [m] (i = 1..n)."""
        n = self.n_plays
        return self.hysteresis_span * np.arange(1, n + 1) / n

    @property
    def weights(self) -> tuple[float, np.ndarray]:
        """(p0, p_i) of the PI operator, including the gain [-]."""
        n = self.n_plays
        return self.gain * (1.0 - self.hysteresis), np.full(n, self.gain * self.hysteresis / n)

    @property
    def is_identity(self) -> bool:
        """True when nominal and true positions coincide exactly."""
        return self.gain == 1.0 and self.hysteresis == 0.0 and not any(self.creep_amplitudes)

    @property
    def creep_lag_time(self) -> float:
        """``sum_j c_j tau_j`` [s]: steady lag of the substrate = speed x this."""
        return float(sum(c * t for c, t in zip(self.creep_amplitudes, self.creep_times)))

    def steady_loop_width(self, speed: float) -> float:
        """Width of a major loop in nominal position at fixed true position [m].

        Steady state on long strokes (longer than ``2 r_max`` and the creep
        times) at drive speed ``speed`` [m/s]: ``2 S + 2 v sum c_j tau_j / g``
        with ``S = alpha r_max (n + 1) / (2 n)``.
        """
        n = self.n_plays
        S = self.hysteresis * self.hysteresis_span * (n + 1) / (2 * n)
        return 2.0 * S + 2.0 * abs(speed) * self.creep_lag_time / self.gain

    # --- maps ------------------------------------------------------------------
    def true_from_nominal(self, time, nominal) -> np.ndarray:
        """True substrate position z [m] for a commanded position u [m] (physical direction)."""
        t, u = _series(time, nominal)
        if self.is_identity:
            return u.copy()
        x0 = u[0]
        s = initial_direction(u)
        p0, p = self.weights
        r = self.thresholds
        w = _pi_relative(u - x0, r, p, p0, s)
        z = self._creep(t, w, inverse=False)
        return z + x0

    def nominal_from_true(self, time, true) -> np.ndarray:
        """Nominal position u [m] reported for a true substrate position z [m] (exact inverse)."""
        t, z = _series(time, true)
        if self.is_identity:
            return z.copy()
        x0 = z[0]
        s = initial_direction(z)
        w = self._creep(t, z - x0, inverse=True)
        p0, p = self.weights
        r_inv, p0_inv, p_inv = pi_inverse_parameters(self.thresholds, p0, p)
        u = _pi_relative(w, r_inv, p_inv, p0_inv, s)
        return u + x0

    def _creep(self, t, x, inverse: bool) -> np.ndarray:
        if not any(self.creep_amplitudes):
            return x
        c = np.asarray(self.creep_amplitudes, float)
        tau = np.asarray(self.creep_times, float)
        direct = 1.0 - float(c.sum())
        from . import _kernels  # numba: imported on first use, not at CLI start-up

        fn = _kernels.relaxation_inverse if inverse else _kernels.relaxation_forward
        return fn(t, np.ascontiguousarray(x, float), direct, c, tau)


def initial_direction(x: np.ndarray) -> float:
    """+1 if the first motion of ``x`` is increasing (or there is none), else -1."""
    moved = np.flatnonzero(x != x[0])
    if moved.size == 0:
        return 1.0
    return 1.0 if x[moved[0]] > x[0] else -1.0


def pi_inverse_parameters(thresholds, p0: float, weights):
    """Thresholds and weights of the inverse PI operator (Kuhnen 2003).

    Returns ``(r', p0', p')`` with ``r'_i = p0 r_i + sum_{j<i} p_j (r_i - r_j)``,
    ``p0' = 1/p0``, ``p'_i = -p_i / (P_i P_{i-1})``, ``P_i = p0 + sum_{j<=i} p_j``.
    Thresholds must be increasing and the weights non-negative.
    """
    r = np.asarray(thresholds, float)
    p = np.asarray(weights, float)
    P = p0 + np.cumsum(p)
    P_prev = np.concatenate(([p0], P[:-1]))
    r_inv = np.array([p0 * r[i] + np.sum(p[:i] * (r[i] - r[:i])) for i in range(r.size)])
    return r_inv, 1.0 / p0, -p / (P * P_prev)


def _pi_relative(x_rel, r, p, p0, direction) -> np.ndarray:
    """PI operator on ``x - x[0]`` from a turning point, shifted to start at 0."""
    state0 = direction * np.asarray(r, float)
    from . import _kernels

    y = _kernels.play_superposition(np.ascontiguousarray(x_rel, float), np.asarray(r, float),
                                    np.asarray(p, float), float(p0), state0)
    return y - y[0]


def _series(time, x) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(time, float)
    v = np.asarray(x, float)
    if t.ndim != 1 or v.shape != t.shape or t.size < 1:
        raise ParameterError(f"time and position must be 1-D arrays of the same length, got {t.shape} and {v.shape}")
    return t, v
