"""Speed regression gate of the forward model (issue 35.5): ``python benchmarks/regression.py``.

Measures, in one process, ratios that do not depend on the machine's speed:

* ``fig5_x_radau``: scipy ``solve_ivp(Radau)`` of the Fig-5 cycle at equal accuracy (rtol 1e-4,
  analytic Jacobian, the lean right-hand side of ``bench_work_precision.py``) over afmforce's
  ``simulate()`` of the same cycle, CPU time of this thread (best of each);
* ``fig5_damped_x_radau``: the same with lever damping on (``quality_factor=300``: the compiled
  terms beyond the paper's, issue 23) — the paper's case must not pay for them, nor they regress;
* ``short_call_x_radau``: the Radau solve over one short ``simulate(**kwargs)`` call (19 steps,
  the configuration built from flat names: what a fit or a sweep pays per evaluation).

afmforce's runs are timed in three blocks interleaved with the Radau solves, so that a load
that comes and goes hits both. afmforce's Fig-5 events are checked against a 100x tighter solve
(approach 0.01 nm, pull-off 0.5 nm): the speed counts at equal accuracy only. Then the
measured ratios are compared with ``benchmarks/baseline.json`` (the last release's, measured
the same way): exit status 1 when one is more than 10 % worse (``benchmarks/gate.py``) or the
accuracy check fails. ``--update`` writes the measurement as the new baseline (at a release).
Options: ``--baseline FILE``, ``--tolerance F``, ``--runs N``, ``--json FILE``.
The wall-time ratios (which a loaded machine inflates: the long scipy solve is preempted more
often than a 2 ms run) are printed, not gated.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import subprocess
import sys
import time
import warnings
from datetime import datetime, timezone
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import gate  # noqa: E402

BASELINE = HERE / "baseline.json"
SHORT = dict(start=-8e-9, turn=-6.5e-9, end=-9e-9, velocity=1e-6, sample_rate=1e5)
WHAT = {
    "fig5_x_radau": "scipy Radau (rtol 1e-4) CPU time / afmforce Fig-5 cycle CPU time",
    "fig5_damped_x_radau": "scipy Radau CPU time / afmforce Fig-5 cycle with quality_factor=300",
    "short_call_x_radau": "scipy Radau CPU time / one short simulate(**kwargs) call (19 steps)",
}


def _best(fn, n):
    cpu, wall = math.inf, math.inf
    for _ in range(n):
        w0, c0 = time.perf_counter(), time.thread_time()
        fn()
        cpu = min(cpu, time.thread_time() - c0)
        wall = min(wall, time.perf_counter() - w0)
    return cpu, wall


def measure(runs: int = 30, radau_repeats: int = 3) -> dict:
    """The ratios (and the times behind them)."""
    from bench_work_precision import scipy_cycle

    from afmforce.dynamics import SimulationConfig, simulate

    warnings.simplefilter("ignore")
    cfg = SimulationConfig()
    damped = cfg.replace(quality_factor=300.0)
    for c in (cfg, damped):                      # compile / warm up
        simulate(c)
        simulate(c)
    simulate(**SHORT)
    counter = [0]

    def fresh(base):
        # a new configuration each run: no setup cached on it (as a sweep or a fit sees)
        counter[0] += 1
        return base.replace(xi=0.1 + 1e-12 * counter[0])

    ours = {"fig5": [], "fig5_damped": [], "short": []}
    radau = []

    def block():
        ours["fig5"].append(_best(lambda: simulate(fresh(cfg)), runs))
        ours["fig5_damped"].append(_best(lambda: simulate(fresh(damped)), runs))
        ours["short"].append(_best(lambda: simulate(**SHORT), 10 * runs))

    block()
    for _ in range(radau_repeats):
        radau.append(_best(lambda: scipy_cycle(cfg, "Radau", 1e-4, 1e-12), 1))
        block()
    r_cpu = min(c for c, _ in radau)
    r_wall = min(w for _, w in radau)
    t = {k: (min(c for c, _ in v), min(w for _, w in v)) for k, v in ours.items()}
    # equal accuracy: afmforce's default against a 100x tighter solve
    e, et = simulate(cfg).events, simulate(cfg, atol=1e-14).events
    acc = dict(approach=abs(e.min_apparent_deflection - et.min_apparent_deflection),
               jump_in=abs(e.jump_in_position - et.jump_in_position),
               pull_off=abs(e.pull_off_position - et.pull_off_position))
    accurate = acc["approach"] < 0.01e-9 and acc["jump_in"] < 0.01e-9 and acc["pull_off"] < 0.5e-9
    return dict(
        ratios={"fig5_x_radau": r_cpu / t["fig5"][0],
                "fig5_damped_x_radau": r_cpu / t["fig5_damped"][0],
                "short_call_x_radau": r_cpu / t["short"][0]},
        wall_ratios={"fig5_x_radau": r_wall / t["fig5"][1],
                     "short_call_x_radau": r_wall / t["short"][1]},
        seconds=dict(radau_cpu=r_cpu, radau_wall=r_wall,
                     **{f"{k}_cpu": v[0] for k, v in t.items()},
                     **{f"{k}_wall": v[1] for k, v in t.items()}),
        accuracy_m=acc, accurate=accurate)


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, text=True,
                              capture_output=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", type=Path, default=BASELINE)
    ap.add_argument("--tolerance", type=float, default=None,
                    help="fraction worse than stored that fails (default: the baseline's, 0.10)")
    ap.add_argument("--runs", type=int, default=30, help="afmforce runs per block (best of)")
    ap.add_argument("--update", action="store_true",
                    help="write this measurement as the baseline (at a release)")
    ap.add_argument("--json", metavar="FILE")
    args = ap.parse_args(argv)

    load0 = os.getloadavg()[0]
    m = measure(args.runs)
    load1 = os.getloadavg()[0]
    s = m["seconds"]
    print(f"afmforce forward model, regression gate (load average {load0:.1f} -> {load1:.1f}, "
          f"{os.cpu_count()} CPUs)")
    print(f"  scipy Radau Fig-5 cycle: {s['radau_cpu']:.3f} s CPU ({s['radau_wall']:.3f} s wall)")
    print(f"  afmforce Fig-5 cycle:    {s['fig5_cpu'] * 1e3:.3f} ms CPU "
          f"({s['fig5_wall'] * 1e3:.3f} ms wall); damped {s['fig5_damped_cpu'] * 1e3:.3f} ms CPU")
    print(f"  short simulate() call:   {s['short_cpu'] * 1e3:.4f} ms CPU "
          f"({s['short_wall'] * 1e3:.4f} ms wall)")
    a = m["accuracy_m"]
    print(f"  accuracy vs a 100x tighter solve: approach {a['approach'] * 1e9:.5f} nm, jump-in "
          f"{a['jump_in'] * 1e9:.5f} nm, pull-off {a['pull_off'] * 1e9:.4f} nm: "
          + ("ok" if m["accurate"] else "FAILED (speed is compared at equal accuracy only)"))
    w = m["wall_ratios"]
    print(f"  wall-time ratios (not gated): Fig 5 {w['fig5_x_radau']:.0f}x Radau, short call "
          f"{w['short_call_x_radau']:.0f}x")
    if args.json:
        Path(args.json).write_text(json.dumps(dict(m, load_average=[load0, load1]), indent=1))
    if args.update:
        data = dict(
            release="the tree of this measurement (update at each release: --update)",
            measured=dict(date=datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
                          commit=_commit(), load_average=[round(load0, 1), round(load1, 1)],
                          cpus=os.cpu_count(), python=platform.python_version(),
                          seconds={k: float(f"{v:.6g}") for k, v in s.items()}),
            tolerance=gate.TOLERANCE,
            metrics={k: dict(value=float(f"{v:.4g}"), better="higher", what=WHAT[k])
                     for k, v in m["ratios"].items()})
        args.baseline.write_text(json.dumps(data, indent=1) + "\n")
        print(f"baseline written: {args.baseline}")
        return 0 if m["accurate"] else 1
    base = gate.load_baseline(args.baseline)
    tol = args.tolerance if args.tolerance is not None else base.get("tolerance", gate.TOLERANCE)
    rows = gate.compare(base["metrics"], m["ratios"], tol)
    print(f"\nagainst {args.baseline.name} ({base.get('measured', {}).get('commit', '?')}, "
          f"{base.get('measured', {}).get('date', '?')}):")
    print(gate.render(rows, tol))
    return 1 if gate.failed(rows) or not m["accurate"] else 0


if __name__ == "__main__":
    sys.exit(main())
