"""Benchmark of the dynamics engine (issue 3): ``python benchmarks/bench_dynamics.py``.

1. First-call compile time (fresh numba cache, in a subprocess) and the cached
   start-up time (second subprocess, same cache).
2. The Fig-5 cycle (beam, xi = 0.1 kg/s, 0.1 um/s, -40 -> +20 -> -230 nm) with
   afmforce (best of N after warm-up) and with a straightforward scipy
   ``solve_ivp(method="Radau")`` of the same equations (analytic Jacobian, rtol 1e-4,
   :mod:`afmforce.dynamics.reference`); both checked against the tight reference
   (afmforce at a 100x tighter atol): minimum apparent deflection and jump-in
   position within 0.01 nm, pull-off within 0.5 nm. Prints the speed ratio.
3. The Fig-6 runs (xi = 0.01, 0.1 kg/s x 0.1, 1 um/s) and the paper's mass check
   (the same four with both masses x100): eight full cycles, total time.
4. Long ramps: the spring model at Figs 9/10 parameters (1 ug, R = 220 nm, 7.2 um/s,
   2 um ramps) and the beam at 20 um/s over 5 um.

Options: ``--repeat N`` (default 20), ``--skip-compile``, ``--json FILE``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np

COMPILE_SNIPPET = """
import time
t0 = time.perf_counter()
import afmforce.dynamics as d
t1 = time.perf_counter()
d.simulate()
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def compile_times():
    """(import, first call) in a fresh cache, then (import, first call) with that cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        out = []
        for _ in range(2):
            r = subprocess.run([sys.executable, "-c", COMPILE_SNIPPET], env=env, check=True,
                               capture_output=True, text=True)
            out.append(tuple(float(x) for x in r.stdout.split()))
    return out


def best_time(fn, repeat):
    best = np.inf
    result = None
    for _ in range(repeat):
        t = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t)
    return best, result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--skip-compile", action="store_true")
    ap.add_argument("--json", metavar="FILE")
    args = ap.parse_args(argv)

    from afmforce.dynamics import simulate
    from afmforce.dynamics.reference import reference_solve

    report = {}
    print("afmforce dynamics benchmark (issue 3)")
    print(f"  python {sys.version.split()[0]}, {os.cpu_count()} CPUs")
    if not args.skip_compile:
        (imp0, first0), (imp1, first1) = compile_times()
        report.update(compile_first_call_s=first0, cached_first_call_s=first1)
        print(f"  first call, fresh numba cache : {first0:7.2f} s  (import {imp0:.2f} s; target < 15 s)")
        print(f"  first call, cached            : {first1:7.2f} s  (import {imp1:.2f} s)")

    simulate()                                             # warm-up in this process
    t_ours, tr = best_time(lambda: simulate(), args.repeat)
    tight = simulate(atol=1e-14)
    t_scipy, ref = best_time(lambda: reference_solve(rtol=1e-4, atol=1e-12), 1)

    e, et = tr.events, tight.events
    rows = [
        ("afmforce (rtol 1e-4, atol 1 pm)", e.min_apparent_deflection, e.jump_in_position,
         e.pull_off_position, t_ours, tr.solver.steps),
        ("scipy Radau (rtol 1e-4)", ref.min_apparent_deflection, ref.jump_in_position,
         ref.pull_off_position, t_scipy, ref.steps),
        ("tight reference (atol 0.01 pm)", et.min_apparent_deflection, et.jump_in_position,
         et.pull_off_position, tight.solver.wall_time, tight.solver.steps),
    ]
    print("\nFig-5 cycle (beam, xi 0.1 kg/s, 0.1 um/s)")
    print(f"  {'solver':34s} {'min app. defl':>14s} {'jump-in z':>11s} {'pull-off z':>11s}"
          f" {'time':>10s} {'steps':>8s}")
    for name, ma, jz, pz, t, n in rows:
        print(f"  {name:34s} {ma * 1e9:11.4f} nm {jz * 1e9:8.4f} nm {pz * 1e9:8.3f} nm"
              f" {t * 1e3:7.1f} ms {n:8d}")
    ok = True
    for name, ma, jz, pz, *_ in rows[:2]:
        good = (abs(ma - et.min_apparent_deflection) < 0.01e-9
                and abs(jz - et.jump_in_position) < 0.01e-9
                and abs(pz - et.pull_off_position) < 0.5e-9)
        ok &= good
        print(f"  {name:34s} agrees with the tight reference: {'yes' if good else 'NO'}")
    ratio = t_scipy / t_ours
    print(f"\n  speed ratio afmforce / scipy: {ratio:.0f}x  (target >= 100x)")
    report.update(fig5_afmforce_s=t_ours, fig5_scipy_s=t_scipy, speed_ratio=ratio,
                  fig5_steps=tr.solver.steps, agrees_with_tight_reference=bool(ok))

    runs = [dict(xi=xi, velocity=v) for xi in (0.01, 0.1) for v in (0.1e-6, 1e-6)]
    heavy = [dict(r, m_joint=1e-8, m_base=1e-8) for r in runs]

    def fig6(kws):
        return [simulate(**kw) for kw in kws]

    t4, _ = best_time(lambda: fig6(runs), max(1, args.repeat // 4))
    t8, res8 = best_time(lambda: fig6(runs + heavy), max(1, args.repeat // 4))
    print(f"\nFig 6: four runs {t4 * 1e3:.1f} ms; with the mass x100 check, eight runs "
          f"{t8 * 1e3:.1f} ms (target < 500 ms)")
    for kw, r in zip(runs + heavy, res8):
        ev = r.events
        print(f"  xi={kw['xi']:<5g} v={kw['velocity'] * 1e6:<4g}um/s m={'x100' if 'm_joint' in kw else 'x1  '}"
              f" min app {ev.min_apparent_deflection * 1e9:7.3f} nm  offset"
              f" {ev.hysteresis_offset * 1e9:6.3f} nm  spike {ev.spike_height * 1e9:6.3f} nm"
              f"  pull-off {ev.pull_off_position * 1e9:8.2f} nm  {r.solver.steps:6d} steps")
    report.update(fig6_four_runs_s=t4, fig6_eight_runs_s=t8)

    print("\nLong ramps")
    long_runs = {
        "spring 1 ug, R 220 nm, 7.2 um/s, -2 um..+50 nm..-2 um, 1.6 kHz":
            dict(model="spring", mass=1e-9, spring_constant=0.21, radius=220e-9,
                 velocity=7.2e-6, start=-2e-6, turn=50e-9, end=-2e-6, sample_rate=1.6e3),
        "spring 10 ug (Fig 1), 10 um/s, -5 um..+100 nm..-5 um":
            dict(model="spring", velocity=10e-6, start=-5e-6, turn=100e-9, end=-5e-6),
        "beam xi 0.01, 20 um/s, -5 um..+100 nm..-5 um, 50 kHz":
            dict(xi=0.01, velocity=20e-6, start=-5e-6, turn=100e-9, end=-5e-6,
                 sample_rate=50e3),
    }
    for name, kw in long_runs.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t, r = best_time(lambda kw=kw: simulate(**kw), 3)
        print(f"  {name:62s} {t * 1e3:7.1f} ms {r.solver.steps:7d} steps")
        report[f"long: {name}"] = t

    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=2)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
