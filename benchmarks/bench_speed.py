"""Speed of the forward model and its batches (issue 16): ``python benchmarks/bench_speed.py``.

1. First call with an empty numba cache (``NUMBA_CACHE_DIR`` a new temporary
   folder, in a subprocess): import + one ``simulate()``; target < 8 s. Median of
   ``--first N`` runs (default 3) as shipped (a second process compiles part of the
   integrator: ``afmforce.dynamics._helper``), interleaved with runs without it
   (``AFMFORCE_COMPILE_HELPER=0``); wall time and the CPU time of all processes.
2. The Fig-5 cycle: median wall time of ``simulate()`` at default tolerances,
   steps, and its events against the tight reference (atol 1e-14 m): approach
   <= 0.01 nm, pull-off <= 0.5 nm, hysteresis <= 0.005 nm. The same with
   ``spike_window=0`` (the spike not asked for).
3. Per-call overhead of a short run (no contact, 18 steps): ``simulate(config)``
   minus the time inside the compiled integrator (timed around each call, one
   per drive segment); target <= 0.1 ms.
4. ``simulate_many`` vs a loop of ``simulate()`` over N Fig-6-type runs (xi 0.01
   and 0.1 kg/s x 0.1 and 1 um/s, cycled; only the events kept); per-run time
   of both, blocks interleaved; target >= 1.8x. Also ``threads=1`` (no
   parallelism: the hoisted Python alone), and the share of a run that holds the
   GIL (outside the compiled pieces), which bounds the speed-up on 2 free cores.
5. A 10,000-run sweep (``run_sweep(simulate_run, ...)``, executor "auto") over
   xi x velocity; target < 60 s. Run at default settings and with
   ``spike_window=0``.

All timings are wall times on this machine, whatever else runs on it: the
development machine has 2 cores shared with other jobs (the load average is
printed); the thread speed-ups need free cores.

Options: ``--many N`` (default 1000), ``--sweep N`` (default 10000; 0 skips),
``--repeat N`` (Fig 5, default 15), ``--first N`` (default 3), ``--skip-compile``,
``--json FILE``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics as st
import subprocess
import sys
import tempfile
import time
import warnings

import numpy as np

NM = 1e-9
FIRST_CALL = """
import time, warnings
warnings.simplefilter("ignore")
t0 = time.perf_counter()
import afmforce.dynamics as d
t1 = time.perf_counter()
d.simulate()
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""
SHORT = dict(start=-40e-9, turn=-35e-9, end=-40e-9, velocity=1e-6)
FIG6 = [dict(xi=xi, velocity=v) for xi in (0.01, 0.1) for v in (0.1e-6, 1e-6)]


def first_call(helper: bool = True) -> tuple[float, float, float]:
    """(import, first simulate(), CPU time of every process) [s] with an empty numba cache;
    ``helper`` False: without the compile helper process."""
    import resource

    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, AFMFORCE_COMPILE_HELPER="1" if helper else "0")
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        r = subprocess.run([sys.executable, "-c", FIRST_CALL], env=env, check=True,
                           capture_output=True, text=True)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    imp, first = (float(x) for x in r.stdout.split())
    return imp, first, (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)


def fig5(repeat: int) -> dict:
    from afmforce.dynamics import simulate

    tight = simulate(atol=1e-14).events
    out = {}
    for name, kw in (("default", {}), ("no_spike", dict(spike_window=0.0))):
        simulate(**kw)
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            tr = simulate(**kw)
            times.append(time.perf_counter() - t0)
        e = tr.events
        errs = dict(approach=max(abs(e.min_apparent_deflection - tight.min_apparent_deflection),
                                 abs(e.jump_in_position - tight.jump_in_position)),
                    pull_off=abs(e.pull_off_position - tight.pull_off_position),
                    hysteresis=abs(e.hysteresis_offset - tight.hysteresis_offset))
        ok = errs["approach"] <= 0.01 * NM and errs["pull_off"] <= 0.5 * NM and \
            errs["hysteresis"] <= 0.005 * NM
        out[name] = dict(median_s=st.median(times), min_s=min(times), steps=tr.solver.steps,
                         errors_m=errs, equal_accuracy=bool(ok))
    return out


def _time_compiled(inside: list, sampling: bool = True):
    """Time every call of the compiled pieces of a run into ``inside[0]``: the integrator
    (one call per drive segment) and, with ``sampling``, the sampled columns
    (``sample_columns``) and the compliance fits (``fit_compliance``), which release the
    GIL too. Returns the function that restores them."""
    import sys as _sys

    from afmforce.dynamics import radau as R

    S = _sys.modules["afmforce.dynamics.simulate"]
    saved = [(R, "integrate_segment", R.integrate_segment)]
    if sampling:
        saved += [(S, "sample_columns", S.sample_columns), (S, "fit_compliance", S.fit_compliance)]

    def timed(f):
        def g(*a):
            t0 = time.perf_counter()
            r = f(*a)
            inside[0] += time.perf_counter() - t0
            return r
        return g

    for mod, name, f in saved:
        setattr(mod, name, timed(f))
    return lambda: [setattr(mod, name, f) for mod, name, f in saved]


def overhead(n: int = 2000) -> dict:
    from afmforce.dynamics import SimulationConfig, simulate

    cfg = SimulationConfig(**SHORT)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        simulate(cfg)
        inside = [0.0]
        restore = _time_compiled(inside, sampling=False)
        try:
            rows = []
            for _ in range(n):
                inside[0] = 0.0
                t0 = time.perf_counter()
                tr = simulate(cfg)
                rows.append((time.perf_counter() - t0, inside[0]))
            t_cfg = []
            for _ in range(n // 4):
                t0 = time.perf_counter()
                SimulationConfig(**SHORT)
                t_cfg.append(time.perf_counter() - t0)
        finally:
            restore()
    total = np.array([r[0] for r in rows])
    integ = np.array([r[1] for r in rows])
    return dict(steps=tr.solver.steps, total_median_s=float(np.median(total)),
                integrator_median_s=float(np.median(integ)),
                overhead_median_s=float(np.median(total - integ)),
                overhead_min_s=float(np.min(total - integ)),
                config_median_s=float(np.median(t_cfg)))


def many(n: int, blocks: int = 4) -> dict:
    from afmforce.dynamics import SimulationConfig, simulate, simulate_many
    from afmforce.dynamics.batch import default_threads

    cfgs = [SimulationConfig(**FIG6[i % len(FIG6)]) for i in range(n)]
    keep = lambda tr: tr.events  # noqa: E731
    simulate_many(cfgs[:8], reduce=keep)
    size = max(1, n // blocks)
    t = {"loop": 0.0, "many": 0.0, "many_1thread": 0.0}
    same = True
    for b in range(0, n, size):              # interleaved blocks: the same load for all three
        part = cfgs[b:b + size]
        t0 = time.perf_counter()
        loop = [keep(simulate(c)) for c in part]
        t["loop"] += time.perf_counter() - t0
        t0 = time.perf_counter()
        batch = simulate_many(part, reduce=keep)
        t["many"] += time.perf_counter() - t0
        t0 = time.perf_counter()
        one = simulate_many(part, reduce=keep, threads=1)
        t["many_1thread"] += time.perf_counter() - t0
        same &= loop == batch == one
    return dict(n=n, threads=default_threads(), per_run_s={k: v / n for k, v in t.items()},
                speedup=t["loop"] / t["many"], speedup_1thread=t["loop"] / t["many_1thread"],
                identical_events=bool(same))


def spin_ratio(n: int = 60_000_000) -> float:
    """What 2 threads get on this machine now: a compiled ``nogil`` loop run twice in one
    thread against once on each of 2 threads (1.0-2.0; the ceiling of any thread
    speed-up measured beside it)."""
    import threading

    from numba import njit

    @njit(nogil=True)
    def spin(m):
        s = 0.0
        for i in range(m):
            s += (i % 7) * 1e-9
        return s

    spin(10)
    t0 = time.perf_counter()
    spin(n)
    spin(n)
    serial = time.perf_counter() - t0
    th = [threading.Thread(target=spin, args=(n,)) for _ in range(2)]
    t0 = time.perf_counter()
    for t in th:
        t.start()
    for t in th:
        t.join()
    return serial / (time.perf_counter() - t0)


def gil_share(n: int = 100) -> dict:
    """Share of a Fig-6-type run (loop of ``simulate()``, one thread) spent inside the
    compiled pieces, which release the GIL; the rest holds it. Bound on the speed-up of
    ``simulate_many`` on 2 free cores (Amdahl): ``1 / (held + (1 - held) / 2)``."""
    from afmforce.dynamics import SimulationConfig, simulate

    inside = [0.0]
    for kw in FIG6:
        simulate(**kw)
    total = 0.0
    restore = _time_compiled(inside)
    try:
        for i in range(n):
            cfg = SimulationConfig(**FIG6[i % len(FIG6)])     # a new configuration per run
            t0 = time.perf_counter()
            simulate(cfg).events
            total += time.perf_counter() - t0
    finally:
        restore()
    held = (total - inside[0]) / total
    return dict(n=n, per_run_s=total / n, gil_held_per_run_s=(total - inside[0]) / n,
                gil_held_share=held, bound_2_cores=1.0 / (held + (1.0 - held) / 2.0))


def sweep(n: int, **fixed) -> dict:
    from afmforce.sweep import run_sweep
    from afmforce.sweep.simulation import simulate_run

    k = int(round(n ** 0.5))
    xi = np.geomspace(0.005, 0.2, k)
    v = np.geomspace(0.1e-6, 2e-6, max(1, n // k))
    table = [dict(xi=float(a), velocity=float(b), **fixed) for a in xi for b in v]
    t0 = time.perf_counter()
    res = run_sweep(simulate_run, table)
    wall = time.perf_counter() - t0
    failed = int(res.table["error"].notna().sum())
    return dict(runs=len(table), wall_s=wall, per_run_s=wall / len(table), failed=failed,
                executor=res.executor)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--many", type=int, default=1000)
    ap.add_argument("--sweep", type=int, default=10000)
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--skip-compile", action="store_true")
    ap.add_argument("--first", type=int, default=3, help="first-call runs of each kind")
    ap.add_argument("--json", metavar="FILE")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    rep: dict = {"cpus": os.cpu_count(), "load_average_start": os.getloadavg()}
    print(f"afmforce speed benchmark (issue 16); {os.cpu_count()} CPUs, "
          f"load average {os.getloadavg()[0]:.2f}")
    targets = []
    if not args.skip_compile:
        runs = {True: [], False: []}
        for _ in range(args.first):
            for helper in (True, False):
                runs[helper].append(first_call(helper))
        med = {h: [st.median(x[i] for x in runs[h]) for i in range(3)] for h in runs}
        rep["first_call"] = {("helper" if h else "one_process"): dict(
            import_s=m[0], first_simulate_s=m[1], cpu_s=m[2],
            totals_s=[x[0] + x[1] for x in runs[h]]) for h, m in med.items()}
        print(f"\n1. first call, empty numba cache (median of {args.first}): import + simulate()")
        for h, m in med.items():
            tot = [x[0] + x[1] for x in runs[h]]
            print(f"   {'as shipped (helper process)' if h else 'one process (no helper)':28s} "
                  f"{m[0]:.2f} s + {m[1]:.2f} s = {m[0] + m[1]:.2f} s wall "
                  f"(range {min(tot):.2f}-{max(tot):.2f} s), {m[2]:.1f} s CPU")
        imp, first = med[True][0], med[True][1]
        targets.append(("first call < 8 s", imp + first < 8.0, f"{imp + first:.2f} s"))
    r = fig5(args.repeat)
    rep["fig5"] = r
    print("\n2. Fig-5 cycle (median of %d)" % args.repeat)
    for name, x in r.items():
        e = x["errors_m"]
        print(f"   {name:9s} {x['median_s'] * 1e3:7.2f} ms  {x['steps']:5d} steps  vs tight: approach "
              f"{e['approach'] / NM:.1e} nm, pull-off {e['pull_off'] / NM:.1e} nm, hysteresis "
              f"{e['hysteresis'] / NM:.1e} nm  ({'equal accuracy' if x['equal_accuracy'] else 'NOT within'})")
    o = overhead()
    rep["overhead"] = o
    print(f"\n3. short run ({o['steps']} steps): {o['total_median_s'] * 1e3:.3f} ms, integrator "
          f"{o['integrator_median_s'] * 1e3:.3f} ms, overhead {o['overhead_median_s'] * 1e3:.3f} ms "
          f"(min {o['overhead_min_s'] * 1e3:.3f} ms); SimulationConfig() {o['config_median_s'] * 1e3:.3f} ms")
    targets.append(("per-call overhead <= 0.1 ms", o["overhead_median_s"] <= 1e-4,
                    f"{o['overhead_median_s'] * 1e3:.3f} ms"))
    if args.many:
        m = many(args.many)
        rep["simulate_many"] = m
        p = m["per_run_s"]
        print(f"\n4. {m['n']} Fig-6-type runs: loop {p['loop'] * 1e3:.2f} ms/run, simulate_many "
              f"({m['threads']} threads) {p['many'] * 1e3:.2f} ms/run = {m['speedup']:.2f}x, "
              f"threads=1 {p['many_1thread'] * 1e3:.2f} ms/run = {m['speedup_1thread']:.2f}x; "
              f"identical events: {m['identical_events']}")
        g = gil_share()
        rep["gil_share"] = g
        print(f"   GIL held {g['gil_held_per_run_s'] * 1e3:.3f} ms of a {g['per_run_s'] * 1e3:.2f} ms "
              f"run ({g['gil_held_share'] * 100:.1f} %): speed-up bound on 2 free cores "
              f"{g['bound_2_cores']:.2f}x")
        spin = spin_ratio()
        rep["spin_2_threads"] = spin
        print(f"   a 2-thread nogil spin loop gets {spin:.2f}x on this machine now (the ceiling)")
        targets.append(("simulate_many >= 1.8x", m["speedup"] >= 1.8, f"{m['speedup']:.2f}x"))
    if args.sweep:
        rep["sweep"] = {}
        print(f"\n5. {args.sweep}-run sweep over xi x velocity (executor auto)")
        for name, fixed in (("default", {}), ("no_spike", dict(spike_window=0.0))):
            s = sweep(args.sweep, **fixed)
            rep["sweep"][name] = s
            print(f"   {name:9s} {s['wall_s']:7.1f} s ({s['per_run_s'] * 1e3:.2f} ms/run, "
                  f"{s['failed']} failed) on {s['executor']}")
            targets.append((f"{args.sweep}-run sweep ({name}) < 60 s", s["wall_s"] < 60.0,
                            f"{s['wall_s']:.1f} s"))
    rep["load_average_end"] = os.getloadavg()
    rep["targets"] = [dict(target=t, met=bool(ok), value=v) for t, ok, v in targets]
    print(f"\ntargets (load average now {os.getloadavg()[0]:.2f}):")
    for t, ok, v in targets:
        print(f"   {'met    ' if ok else 'NOT met'}  {t}: {v}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rep, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
