"""find_glitches' batched candidate tests (issue 35) give the indices of the plain per-candidate recipe."""

from __future__ import annotations

import math

import numpy as np

from afmforce.analysis.glitches import GLITCH_QUIET_SIGMAS, GLITCH_SIGMAS, GLITCH_WINDOW, find_glitches


def _plain(s: np.ndarray) -> np.ndarray:
    """The module docstring's recipe, one candidate at a time with np.median (the code before issue 35)."""
    s = np.asarray(s, float)
    if s.size < 5:
        return np.zeros(0, np.intp)
    d2 = s[1:-1] - 0.5 * (s[:-2] + s[2:])
    sigma = 1.4826 * float(np.median(np.abs(d2 - np.median(d2)))) / math.sqrt(1.5)
    if not sigma > 0.0:
        steps = np.abs(np.diff(s))
        steps = steps[steps > 0.0]
        sigma = float(steps.min()) / math.sqrt(12.0) if steps.size else 0.0
    if not sigma > 0.0:
        return np.zeros(0, np.intp)
    out = []
    x = np.array([-2.0, -1.0, 1.0, 2.0])
    for i in range(2, s.size - 2):
        if not abs(d2[i - 1]) > GLITCH_SIGMAS * sigma:
            continue
        y = s[[i - 2, i - 1, i + 1, i + 2]]
        near = np.concatenate([d2[max(0, i - 1 - GLITCH_WINDOW): max(0, i - 2)], d2[i + 1: i + GLITCH_WINDOW]])
        local = 1.4826 * float(np.median(np.abs(near - np.median(near)))) / math.sqrt(1.5) if near.size else 0.0
        sigma_i = max(sigma, local)
        a = float(y.mean())
        b = float(np.dot(x, y - y.mean())) / 10.0
        if np.max(np.abs(y - (a + b * x))) < GLITCH_QUIET_SIGMAS * sigma_i and abs(s[i] - a) > GLITCH_SIGMAS * sigma_i:
            out.append(i)
    return np.asarray(out, np.intp)


def test_batched_tests_equal_the_plain_recipe():
    rng = np.random.default_rng(35)
    found = 0
    for trial in range(1500):
        n = int(rng.integers(5, 40)) if trial % 2 else int(rng.integers(40, 1500))
        s = rng.normal(size=n) * 10 ** rng.uniform(-3, 3)
        if trial % 3 == 0:
            s = np.round(s, 1)                                   # quantised: ties, zero deviations
        if trial % 4 == 0:
            s += np.linspace(0, rng.uniform(0, 100), n) ** rng.uniform(1, 3)   # a curved contact
        if trial % 5 == 0:
            s[rng.integers(0, n):] += rng.normal() * 1000        # a jump: no glitch
        for _ in range(int(rng.integers(0, 8))):                 # glitches, near the ends too
            j = int(rng.integers(0, n))
            s[j] += rng.normal() * 10 ** rng.uniform(0, 4)
            if trial % 11 == 0 and j + 1 < n:
                s[j + 1] = s[j]                                  # two samples off: no single-sample glitch
        want = _plain(s)
        found += want.size > 0
        assert np.array_equal(find_glitches(s), want), trial
    assert found > 300  # the glitches were there to be found
