"""Would an exponential integrator take fewer steps after the pull-off? (issue 35.5)
``python benchmarks/bench_exprb_pulloff.py [--span 2.5e-3] [--atols 1e-12,1e-13,3e-14,1e-14]``.

A measurement, not a solver of the package. Takes the state of the default Fig-5 cycle at the
first step after the pull-off (the integrator run as Python, whose steps are the compiled
one's bitwise), and integrates the next ``--span`` seconds (the tip's release from the adhesion
fold with the beam's 65 kHz mode rung up, benchmarks/README.md "Fourth pass") three ways:

* the reference: scipy ``solve_ivp(Radau)``, rtol 1e-11, atol 1e-17 m (1e-13 m/s), the
  package's vector field and Jacobian (``dynamics.models.rhs``/``jac``);
* afmforce's default steps (recorded): their count and their error at their step starts;
* the exponential Rosenbrock method ``exprb32`` (Hochbruck, Ostermann & Schweitzer, SIAM J.
  Numer. Anal. 47, 786 (2009): order 3, the exponential Rosenbrock-Euler step embedded,
  error estimate ``2 h phi3(hJ) D``) on the system made autonomous with ``t`` as a state,
  the phi functions from ``scipy.linalg.expm`` of a block matrix, the package's error norm
  (positions ``atol``, velocities ``10 atol omega`` + rtol 1e-4), for each ``--atols``: its
  accepted and rejected steps and its largest position error at its step ends.

Compare the step counts where the largest errors agree. ~1 min (the reference: ~50 s).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ["NUMBA_DISABLE_JIT"] = "1"      # before numba is imported

import numpy as np  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--span", type=float, default=2.5e-3)
    ap.add_argument("--atols", default="1e-12,1e-13,3e-14,1e-14")
    args = ap.parse_args(argv)

    from scipy.integrate import solve_ivp
    from scipy.linalg import expm

    from afmforce.dynamics import SimulationConfig, radau, simulate
    from afmforce.dynamics._setup import _setup
    from afmforce.dynamics.models import error_frequency, jac, rhs

    cfg = SimulationConfig()
    steps = []
    inner = radau.sample_step

    def record(t_old, t_new, h, y_old, *rest):
        steps.append((t_old, t_new, y_old.copy()))
        return inner(t_old, t_new, h, y_old, *rest)

    radau.sample_step = record
    tr = simulate(cfg)
    radau.sample_step = inner
    st = _setup(cfg)
    T = args.span
    t0, _, y0 = next(s for s in steps if s[0] >= tr.events.pull_off_time)
    seg = [g for g in st.plan if g.t_start <= t0 <= g.t_end][-1]
    za, ta, v = seg.z_start, seg.t_start, seg.velocity
    model, p = st.kmodel, st.p

    def F(t, y):
        out = np.empty(4)
        if not rhs(model, p, za + v * (t - ta), v, y, out):
            raise FloatingPointError("below the force law's guard")
        return out

    def Jy(t, y):
        J = np.empty((4, 4))
        jac(model, p, za + v * (t - ta), v, y, J)
        return J

    w0 = time.perf_counter()
    ref = solve_ivp(F, (t0, t0 + T), y0, method="Radau", rtol=1e-11,
                    atol=np.array([1e-17, 1e-17, 1e-13, 1e-13]), jac=Jy, dense_output=True)
    print(f"reference (scipy Radau, rtol 1e-11): {ref.t.size} steps, {time.perf_counter() - w0:.0f} s")
    ours = [s for s in steps if t0 <= s[0] <= t0 + T]
    e_ours = max(np.max(np.abs(s[2] - ref.sol(s[0]))[:2]) for s in ours)
    print(f"afmforce default (rtol 1e-4, atol 1e-12): {len(ours)} accepted steps in "
          f"{T * 1e3:g} ms after the pull-off; largest position error at their starts "
          f"{e_ours * 1e12:.2f} pm")

    def phis(M):
        n = M.shape[0]
        B = np.zeros((4 * n, 4 * n))
        B[:n, :n] = M
        for k in range(3):
            B[k * n:(k + 1) * n, (k + 1) * n:(k + 2) * n] = np.eye(n)
        E = expm(B)
        return [E[:n, k * n:(k + 1) * n] for k in range(4)]

    def aug(t, y):
        d = 1e-9
        Ja = np.zeros((5, 5))
        Ja[:4, :4] = Jy(t, y)
        Ja[:4, 4] = (F(t + d, y) - F(t - d, y)) / (2 * d)
        return np.append(F(t, y), 1.0), Ja

    def exprb32(atol):
        t, y, h = t0, y0.copy(), 1e-6
        acc = rej = 0
        emax = 0.0
        while t < t0 + T - 1e-15:
            h = min(h, t0 + T - t)
            u = np.append(y, t)
            Fa, Ja = aug(t, y)
            P = phis(h * Ja)
            U2 = u + h * P[1] @ Fa
            try:
                FU2 = np.append(F(U2[4], U2[:4]), 1.0)
            except FloatingPointError:
                h *= 0.5
                rej += 1
                continue
            corr = 2 * h * P[3] @ ((FU2 - Ja @ U2) - (Fa - Ja @ u))
            w = error_frequency(model, p, za + v * (t - ta), v, y)
            av = atol * 10.0 * w
            sc = np.array([atol, atol, av + 1e-4 * abs(y[2]), av + 1e-4 * abs(y[3])])
            e = float(np.sqrt(np.mean((corr[:4] / sc) ** 2)))
            if e <= 1.0:
                u1 = U2 + corr
                t, y = u1[4], u1[:4]
                acc += 1
                emax = max(emax, float(np.max(np.abs(y - ref.sol(t))[:2])))
            else:
                rej += 1
            h *= min(5.0, max(0.2, 0.9 * max(e, 1e-10) ** (-1.0 / 3.0)))
        return acc, rej, emax

    for atol in (float(a) for a in args.atols.split(",")):
        acc, rej, emax = exprb32(atol)
        print(f"exprb32 atol {atol:.0e}: {acc} accepted, {rej} rejected; largest position error "
              f"at its step ends {emax * 1e12:.2f} pm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
