"""The fringe fit's compiled kernel never divides by zero (issue 32, item 7): one curve of the
real NanoScope force volume took a Levenberg-Marquardt trial step to log(P/P0) < -745, where
P = P0 exp(q) underflows to 0 and 2 pi / P raised ZeroDivisionError, failing the whole file.
A trial step whose period under- or overflows is rejected (cost +inf), the fit goes on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis._fringe_kernel import _prepare, lm_fit, vp_eval


def _run(n: int = 400, period: float = 150e-9):
    rng = np.random.default_rng(3)
    z = np.linspace(0, 1.2e-6, n)
    r = 0.02 * np.cos(2 * np.pi * z / period + 0.4) + 0.002 * rng.standard_normal(n)
    return z, r, _prepare(z, r, None)


def test_trial_period_underflow_or_overflow_is_rejected_not_raised():
    z, r, p = _run()
    res, J = np.empty(z.size), np.empty((z.size, 1))
    for q0 in (-800.0, 800.0):  # exp(-800) = 0, exp(800) = inf
        cost = vp_eval(np.array([q0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                       res, J, False, False)
        assert cost == math.inf
    finite = vp_eval(np.array([0.0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                     res, J, True, False)
    assert 0 < finite < 0.5 * np.sum(p.r_perp ** 2) * 0.2  # the true period explains most of the variance


def test_fit_from_a_far_start_ends_without_error():
    """Started at log(P/P0) = -740 (P about 1e-321 m: the next steps underflow), LM returns a finite
    cost no worse than its start, or +inf for a start it cannot evaluate, never an exception."""
    z, r, p = _run()
    for start in (-740.0, 700.0, 0.2):
        q, cost, status = lm_fit(np.array([start]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0,
                                 p.r_perp, 200, 1e-6, 1e-7, False)
        assert status in (0, 1) and (math.isinf(cost) or cost <= 0.5 * np.sum(p.r_perp ** 2))
    q, cost, _ = lm_fit(np.array([0.03]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                        200, 1e-10, 1e-12, False)
    assert 150e-9 * math.exp(q[0]) == pytest.approx(150e-9, rel=0.01)  # converges to the period


def test_the_first_runs_python_kernels_reject_an_overflowing_trial_step_too(tmp_path):
    """The first `afmforce analyze` after an install runs these kernels as Python (cli/_firstrun),
    where math.exp(800) raises OverflowError instead of giving inf: the audit's first run of the
    corpus failed jpk-force_stress-relaxation_cell1-0001.jpk-force with "unexpected OverflowError:
    math range error" (its fringe fit's trial step). The same calls as above, with numba's JIT off."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    script = tmp_path / "python_kernels.py"
    script.write_text(
        "import math, numpy as np\n"
        "from afmforce.analysis._fringe_kernel import _prepare, lm_fit, vp_eval\n"
        "z = np.linspace(0, 1.2e-6, 200)\n"
        "r = 0.02 * np.cos(2 * np.pi * z / 150e-9 + 0.4)\n"
        "p = _prepare(z, r, None)\n"
        "res, J = np.empty(z.size), np.empty((z.size, 1))\n"
        "for q0 in (-800.0, 800.0):\n"
        "    c = vp_eval(np.array([q0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,"
        " res, J, False, False)\n"
        "    assert c == math.inf, c\n"
        "q, cost, status = lm_fit(np.array([700.0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0,"
        " p.r_perp, 50, 1e-6, 1e-7, False)\n"
        "print('ok', status)\n")
    src = str(Path(__file__).resolve().parents[2] / "src")
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1",
           "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}
    out = subprocess.run([sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0 and out.stdout.startswith("ok"), out.stderr[-2000:]
