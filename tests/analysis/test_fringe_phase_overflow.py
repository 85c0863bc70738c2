"""The fringe fit's trial step whose phase overflows is rejected, compiled and as the first run's
Python alike (corpus5): on the real NanoScope 8.15 force volume `Test.004` (JSotres/FSAS
`SampleFiles/`, 16 x 16 curves on mica in air) curves 4 and 184 took a Levenberg-Marquardt trial
step to log(P/P0) of about -700, where the period P = P0 exp(q) is still positive (a subnormal
number) but 2 pi / P, hence every phase, is infinite: the first run's Python kernels raised
"math domain error" from math.cos(inf) and `afmforce analyze` failed both curves ("unexpected
ValueError"; the compiled kernels, where math.cos(inf) is NaN, rejected the step). The cost is
+inf now on both (no fit exists there) and the step is rejected as any other."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

from afmforce.analysis._fringe_kernel import _prepare, lm_fit, vp_eval

SCRIPT = """
import math, numpy as np
from afmforce.analysis._fringe_kernel import _prepare, lm_fit, vp_eval
z = np.linspace(0, 1.2e-6, 200)
r = 0.02 * np.cos(2 * np.pi * z / 150e-9 + 0.4)
p = _prepare(z, r, None)
res, J = np.empty(z.size), np.empty((z.size, 1))
P = 150e-9 * math.exp(-700.0)
assert 0.0 < P and math.isinf(2 * math.pi / P)
for q0 in (-700.0, -710.0):
    c = vp_eval(np.array([q0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                res, J, False, FAST)
    assert c == math.inf, c
q, cost, status = lm_fit(np.array([-700.0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0,
                         p.r_perp, 50, 1e-6, 1e-7, FAST)
assert math.isinf(cost) and status == 1, (cost, status)
print('ok')
"""


def test_compiled_kernel_gives_inf_not_nan_where_the_phase_overflows():
    z = np.linspace(0, 1.2e-6, 200)
    r = 0.02 * np.cos(2 * np.pi * z / 150e-9 + 0.4)
    p = _prepare(z, r, None)
    res, J = np.empty(z.size), np.empty((z.size, 1))
    for fast in (False, True):
        cost = vp_eval(np.array([-700.0]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                       res, J, False, fast)
        assert cost == math.inf
    q, cost, _ = lm_fit(np.array([0.03]), False, 150e-9, 0.0, 0, p.x, p.x2, p.x3, p.zm, p.L, p.Q0, p.r_perp,
                        200, 1e-10, 1e-12, False)
    assert 150e-9 * math.exp(q[0]) == __import__("pytest").approx(150e-9, rel=0.01)  # a good start converges


def test_first_runs_python_kernels_reject_the_step_without_math_domain_error(tmp_path):
    src = str(Path(__file__).resolve().parents[2] / "src")
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1",
           "PYTHONPATH": src + os.pathsep + os.environ.get("PYTHONPATH", "")}
    for fast in ("False", "True"):
        script = tmp_path / f"phase_{fast}.py"
        script.write_text(SCRIPT.replace("FAST", fast))
        out = subprocess.run([sys.executable, str(script)], env=env, capture_output=True, text=True, timeout=600)
        assert out.returncode == 0 and out.stdout.startswith("ok"), out.stderr[-2000:]
