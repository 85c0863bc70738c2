"""A misfit is not 1/f noise: the fit refits with a 1/f noise model only when its level is an AFM's.

A colleague's case: ``afmforce fit`` with ``spring_constant=200`` (a slip for 0.2 N/m) had the
1/f step read the gross misfit as 65 nm of 1/f noise against 0.05 nm of white noise, whiten it
away and pass the adequacy test (reduced chi-square 3.7e-6, "friction not detected"). The unit
that decides: :func:`afmforce.fit.noise.estimate_pink` on the residuals of a white fit, then
:func:`afmforce.fit.noise.pink_refusal`. Here both get residuals built without a simulation: a
stand-in for the fit problem whose residuals are ``D b`` (``D`` removes the offset, the drift and
the span of a one-column Jacobian) for (a) the ``typical`` instrument's noise (0.05 nm white +
0.05 nm 1/f, :func:`afmforce.instrument.noise.pink_noise`) and (b) the same noise plus a
60 nm model error of a shape the fitted column cannot take (the fitted column decays over 5 % of
the record before contact, the error over 2 %, with a linear ramp): what a wrong stiffness
leaves, tens of nm of smooth misfit near contact.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from afmforce.fit.noise import PINK_MAX_RATIO, estimate_pink, pink_refusal
from afmforce.instrument.noise import pink_noise

N = 1500          # samples per curve
WHITE = 0.05e-9   # [m] the typical instrument's white rms
PINK = 0.05e-9    # [m] and its 1/f rms


class _Problem:
    """What estimate_pink reads of a fit problem: the curves, their designs, the residuals and the
    Jacobian of a white least-squares fit of offset, drift and one model amplitude per curve set."""

    def __init__(self, data: list[np.ndarray], shape: np.ndarray):
        t = np.linspace(0.0, 1.0, N)
        design = np.column_stack([np.ones(N), t])
        self.curves = [SimpleNamespace(mask=np.ones(N, bool), sigma=WHITE, metadata={}, n=N,
                                       jump_index=N - 100) for _ in data]
        self.ev = SimpleNamespace(curves=self.curves, design=lambda i: design)
        Q = np.linalg.qr(design)[0]
        col = (shape - Q @ (Q.T @ shape)) / WHITE          # the model column, baseline profiled out
        self._J = np.concatenate([col] * len(data))[:, None]
        b = np.concatenate([(d - Q @ (Q.T @ d)) / WHITE for d in data])
        self._r = b - self._J @ np.linalg.lstsq(self._J, b, rcond=None)[0]

    def curve_residuals(self, x):
        return np.split(self._r, len(self.curves))

    def jacobian(self, x):
        return self._J


def _decision(misfit: float, seed: int) -> tuple[float, float, str | None]:
    """``(1/f rms [m], significance, refusal)`` for two curves of typical noise + a misfit [m]."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, 1.0, N)
    shape = np.exp(-(1.0 - s) / 0.05)                          # the fitted model's column
    wrong = np.exp(-(1.0 - s) / 0.02) * (1.0 + 3.0 * (1.0 - s))  # what the wrong model misses
    data = [rng.normal(0.0, WHITE, N) + pink_noise(N, PINK, rng) + misfit * wrong for _ in range(2)]
    s2p, signif = estimate_pink(_Problem(data, shape), None)
    return math.sqrt(s2p), signif, pink_refusal(s2p, [WHITE, WHITE])


def test_real_1f_noise_is_refitted():
    """The typical instrument's 1/f noise is found (within a factor 2) and kept for the refit."""
    for seed in range(3):
        pink, signif, refusal = _decision(0.0, seed)
        assert 0.5 * PINK < pink < 2.0 * PINK, pink
        assert refusal is None


def test_gross_misfit_is_not_taken_for_1f_noise():
    """A model error of tens of nm: significant excess, far above an AFM's 1/f: refused, said why."""
    pink, signif, refusal = _decision(60e-9, 0)
    assert signif > 3.0 and pink > PINK_MAX_RATIO * WHITE, (pink, signif)
    assert refusal is not None and "misfit" in refusal and f"{pink * 1e9:.3g} nm" in refusal


def test_refusal_threshold():
    """The decision itself: at the ratio the level is kept, beyond it refused; the largest white rms counts."""
    assert pink_refusal((PINK_MAX_RATIO * WHITE) ** 2 * 0.99, [WHITE]) is None
    assert pink_refusal((PINK_MAX_RATIO * WHITE) ** 2 * 1.01, [WHITE]) is not None
    assert pink_refusal((PINK_MAX_RATIO * WHITE) ** 2 * 1.01, [WHITE, 2 * WHITE]) is None
    assert pink_refusal(0.0, [WHITE]) is None
