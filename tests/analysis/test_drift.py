"""Drift baselines (analysis.drift): closed-form synthetic baselines with known lines.

A settling lever after the pull-off (an exponential rising from below) must not be read as drift,
and the retract keeps its own line only when the data show a different drift than the approach's.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.analysis.drift import fit_baseline, retract_line

NOISE = 1e-3  # [V]
T = np.arange(165) / 2000.0 + 0.408  # the beam run's retract free part: 165 samples at 2 kHz [s]


def _settling(slope: float, seed: int = 1, amplitude: float = -6e-3, tau: float = 6.5e-3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return 0.1 + slope * (T - T[0]) + amplitude * np.exp(-(T - T[0]) / tau) + rng.normal(0, NOISE, T.size)


def test_settling_is_not_drift():
    """True slope 0, 40 noise draws: the plain line reads the settling as drift (0.022 V/s, 5 standard
    errors of 3.3e-3 V/s); with the transient regressor the slope is unbiased (its scatter is ~3x larger,
    the collinearity of a slow exponential with the line: the reason continues_approach prefers the
    approach line), and the approach line is kept for every draw."""
    plain, fitted = [], []
    for seed in range(40):
        s = _settling(0.0, seed)
        plain.append(fit_baseline(T, s, 1)[1])
        fitted.append(fit_baseline(T, s, 1, transient=True)[1])
        assert retract_line(T, s, 0.1, 0.0, T[0], T[0] - 0.2, NOISE)[0] == "approach"
    se = NOISE / (np.ptp(T) * np.sqrt(T.size / 12))
    assert np.mean(plain) > 5 * se
    assert abs(np.mean(fitted)) < 3 * np.std(fitted) / np.sqrt(len(fitted))
    assert abs(np.mean(fitted)) < se


def test_baseline_bowing_the_other_way_is_left_to_the_line():
    """An exponential from above is not a lever settling after a pull-off: not used."""
    s = _settling(0.0, amplitude=+6e-3)
    assert fit_baseline(T, s, 1, transient=True) == fit_baseline(T, s, 1)


def test_retract_line_is_the_simplest_the_data_allow():
    """Same drift as the approach (plus settling): the approach line continued. A drift rate that
    changes by 0.1 V/s at the turn (0.2 s before the free part): continuous, with that slope. A jump
    of 20 mV at the turn as well: separate, with the jump in its offset."""
    t0a, off_a, slope_a, t_turn = 0.0, 0.05, 0.02, T[0] - 0.2
    at_turn = off_a + slope_a * t_turn
    same = _settling(0.0) - 0.1 + off_a + slope_a * T
    assert retract_line(T, same, off_a, slope_a, t0a, t_turn, NOISE)[0] == "approach"
    bent = same + 0.1 * (T - t_turn)
    line, off, slope = retract_line(T, bent, off_a, slope_a, t0a, t_turn, NOISE)
    assert line == "continuous" and off == pytest.approx(at_turn)
    assert slope == pytest.approx(slope_a + 0.1, abs=0.01)
    line, off, slope = retract_line(T, bent + 0.02, off_a, slope_a, t0a, t_turn, NOISE)
    assert line == "separate"
    assert off - at_turn == pytest.approx(0.02, abs=0.01)


def test_compiled_irls_matches_the_numpy_iterations():
    """drift._irls (compiled loops) gives the numpy version's fit to rounding: same iterations,
    sums in another order (relative differences ~1e-13, far below any reported digit)."""
    import numpy as np

    from afmforce.analysis.drift import _irls, _irls_numpy

    rng = np.random.default_rng(3)
    for n, p in ((40, 1), (500, 2), (4001, 2), (3000, 3)):
        t = np.linspace(0, 1, n)
        X = np.column_stack([np.ones(n), t, 1 / (1.1 - t) ** 2][:p])
        X = X / np.max(np.abs(X), axis=0)
        y = X @ rng.normal(size=p) + rng.normal(0, 0.01, n)
        y[rng.integers(0, n, n // 20)] += 0.5  # outliers the bisquare weights reject
        (c1, s1, q1), (c2, s2, q2) = _irls(X, y), _irls_numpy(X, y)
        np.testing.assert_allclose(c1, c2, rtol=1e-10, atol=1e-12)
        assert s1 == pytest.approx(s2, rel=1e-10) and q1 == pytest.approx(q2, rel=1e-9)
    X = np.column_stack([np.ones(50), np.ones(50)])  # singular normal equations: the numpy fallback (lstsq)
    c, s, q = _irls(X, np.ones(50))
    assert np.all(np.isfinite(c)) and c.sum() == pytest.approx(1.0)
