"""A/B check of an integrator change, in one run.

``python benchmarks/bench_ab.py [--inprocess-rounds N]`` (in-process only), or
``python benchmarks/bench_ab.py --before DIR [--rounds N] [--dump-only]`` (against a tree).

0. **In process** (always): ``simulate()`` with the package's integrator and with the one
   before issue 11.8 (``benchmarks/_radau_before.py``, the same records unpacked into its 31
   positional arguments) on the Fig-5 cycle, the four Fig-6 runs and two long ramps,
   alternating call by call; trajectories, events and counters compared bitwise, CPU
   time of this thread (robust to the load of a shared machine) as medians, ratio
   after/before per case. (The short run times the whole call, Python included; the
   "before" side pays ~1 us more for unpacking the records in Python.)

``DIR`` is another checkout of the project (e.g. ``git archive <commit> | tar -x -C DIR``).
1. **Same answers**: both trees simulate a fixed set of runs (Fig 5, the Fig-6 runs, the
   issue-12 cases, averaged sampling, a turn at a load, ``spike_window=0``, the ringing
   resolved, a fixed-step window) in subprocesses; every sampled column, every event and
   every solver counter is compared (bitwise, and the largest difference printed).
2. **Same speed**: ``benchmarks/bench_dynamics.py --skip-compile`` of each tree, run in
   alternating subprocesses (``--rounds`` each, interleaved so that the load of a shared
   machine hits both alike); the medians of every timing and their ratio after/before.

Exit status 1 if an answer differs or a timing is more than 5 % slower (median).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics as st
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]

DUMP = r"""
import sys, warnings, numpy as np, dataclasses
warnings.simplefilter("ignore")
sys.path.insert(0, sys.argv[2] + "/benchmarks")
from afmforce.dynamics import simulate
from issue12_cases import CASES
runs = dict(CASES)
runs.pop("fig9_1nms", None)        # slow (max_steps on old trees)
for xi in (0.01, 0.1):
    for v in (0.1e-6, 1e-6):
        runs[f"fig6_{xi}_{v}"] = dict(xi=xi, velocity=v)
runs["average"] = dict(sampling="average")
runs["turn_force"] = dict(turn_force=20e-9, turn=60e-9)
runs["no_spike"] = dict(spike_window=0.0)
runs["tight"] = dict(atol=1e-14)
runs["resolve"] = dict(ringing="resolve", model="spring", end=-60e-9)
runs["spring_fig1"] = dict(model="spring", velocity=10e-6, start=-5e-6, turn=100e-9, end=-5e-6)
out = {}
for name, kw in runs.items():
    try:
        tr = simulate(**kw)
    except Exception as exc:
        out[name + "/error"] = np.array(str(exc))
        continue
    for f in dataclasses.fields(tr):
        val = getattr(tr, f.name)
        if isinstance(val, np.ndarray):
            out[f"{name}/{f.name}"] = val
    for f in dataclasses.fields(tr.events):
        val = getattr(tr.events, f.name)
        if isinstance(val, (float, int, bool)) and val is not None:
            out[f"{name}/events.{f.name}"] = np.array(float(val))
    s = tr.solver
    for f in ("steps", "accepted", "rejected", "rhs_evaluations", "jacobian_evaluations",
              "lu_decompositions", "damping_steps", "newton_failures"):
        out[f"{name}/solver.{f}"] = np.array(getattr(s, f))
np.savez(sys.argv[1], **out)
"""


INPROCESS_CASES = {
    "short run, no contact (18 steps)": dict(start=-40e-9, turn=-35e-9, end=-40e-9,
                                             velocity=1e-6),
    "Fig 5 (beam, xi 0.1, 0.1 um/s)": {},
    "Fig 6 xi 0.01, 0.1 um/s": dict(xi=0.01),
    "Fig 6 xi 0.01, 1 um/s": dict(xi=0.01, velocity=1e-6),
    "Fig 6 xi 0.1, 1 um/s": dict(velocity=1e-6),
    "Fig 5, averaged samples": dict(sampling="average"),
    "spring 1 ug, 7.2 um/s, 2 um ramps": dict(
        model="spring", mass=1e-9, spring_constant=0.21, radius=220e-9, velocity=7.2e-6,
        start=-2e-6, turn=50e-9, end=-2e-6, sample_rate=1.6e3),
    "beam xi 0.01, 20 um/s, 5 um ramps": dict(xi=0.01, velocity=20e-6, start=-5e-6,
                                              turn=100e-9, end=-5e-6, sample_rate=50e3),
}


def _before_integrator():
    """The integrator before issue 11.8, called with the records of the current one."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import _radau_before as B

    def call(model, p, drive, tol, control, sampling, state):
        kind, t_a, z_a, v, t_end, term_kind, term_level = drive
        rtol, rtolv, atol = tol
        hmax_frac, hmax_dz, damp_cycles, damp_kappa, h_fixed, max_steps, chunk = control
        s_t0, s_dt, average, s_next, ybuf = sampling
        y, ev, work, Q, y_old, J, stats = state
        return B.integrate_segment(model, p, kind, t_a, z_a, v, t_end, y, rtol, rtolv, atol,
                                   hmax_frac, hmax_dz, damp_cycles, damp_kappa, term_kind,
                                   term_level, s_t0, s_dt, s_next, ybuf, ev, work, Q, y_old,
                                   J, stats, max_steps, chunk, h_fixed,
                                   1.0 if average else 0.0)
    return call


def _same(a, b) -> bool:
    import dataclasses
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            if not np.array_equal(x, y, equal_nan=x.dtype.kind == "f"):
                return False
    ea, eb = dataclasses.asdict(a.events), dataclasses.asdict(b.events)
    for k in ea:
        if ea[k] != eb[k] and not (isinstance(ea[k], float) and np.isnan(ea[k])
                                   and np.isnan(eb[k])):
            return False
    sa, sb = a.solver, b.solver
    return all(getattr(sa, k) == getattr(sb, k) for k in (
        "steps", "accepted", "rejected", "rhs_evaluations", "jacobian_evaluations",
        "lu_decompositions", "damping_steps", "newton_failures"))


def inprocess(rounds: int) -> bool:
    """Section 0 of the module docstring; True if all answers are identical and no case
    is more than 5 % slower."""
    import time
    import warnings

    from afmforce.dynamics import radau as R
    from afmforce.dynamics import simulate

    new, old = R.integrate_segment, _before_integrator()
    ok = True
    print(f"in-process A/B, CPU time of this thread, medians of {rounds} alternating calls"
          f" (load {os.getloadavg()[0]:.2f})")
    print(f"  {'case':36s} {'before':>9s} {'after':>9s} {'after/before':>13s}  answers")
    ratios = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, kw in INPROCESS_CASES.items():
            times = {"before": [], "after": []}
            last = {}
            for r in range(rounds + 1):
                for side, fn in (("before", old), ("after", new)) if r % 2 else \
                        (("after", new), ("before", old)):
                    R.integrate_segment = fn
                    try:
                        t0 = time.thread_time()
                        last[side] = simulate(**kw)
                        dt = time.thread_time() - t0
                    finally:
                        R.integrate_segment = new
                    if r:                      # round 0 compiles / warms up
                        times[side].append(dt)
            b0, a0 = st.median(times["before"]), st.median(times["after"])
            same = _same(last["before"], last["after"])
            ratios.append(a0 / b0)
            slow = a0 / b0 > 1.05
            ok &= same and not slow
            print(f"  {name:36s} {b0 * 1e3:7.2f}ms {a0 * 1e3:7.2f}ms {a0 / b0:12.3f}"
                  f"{'  > 5 %' if slow else ''}  {'identical' if same else 'DIFFER'}")
    print(f"  geometric mean after/before: {float(np.exp(np.mean(np.log(ratios)))):.3f}")
    return ok


def env_for(tree: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree / "src"), MPLBACKEND="Agg")
    env.pop("NUMBA_CACHE_DIR", None)
    return env


def dump(tree: Path, path: str) -> dict:
    subprocess.run([sys.executable, "-c", DUMP, path, str(tree)], env=env_for(tree),
                   check=True, cwd=tree)
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


#: Computed after the integrator by a changed fit (compiled least squares instead of
#: ``np.polyfit`` since this benchmark was written): equal to rounding, 1e-9 relative.
ROUNDING_ONLY = ("events.hysteresis_offset", "events.compliance_slope")


def compare(a: dict, b: dict) -> bool:
    same = True
    for k in sorted(set(a) | set(b)):
        if k not in a or k not in b:
            print(f"  only in {'after' if k not in a else 'before'}: {k}")
            same = False
            continue
        x, y = a[k], b[k]
        if x.dtype.kind in "US" or y.dtype.kind in "US":
            if str(x) != str(y):
                print(f"  {k}: {x} != {y}")
                same = False
            continue
        if x.shape != y.shape:
            print(f"  {k}: shape {x.shape} != {y.shape}")
            same = False
            continue
        eq = np.array_equal(x, y, equal_nan=x.dtype.kind == "f")
        if not eq and k.endswith(ROUNDING_ONLY) and np.allclose(x, y, rtol=1e-9, atol=0.0):
            print(f"  {k}: equal to rounding (|diff| = {np.nanmax(np.abs(x - y)):.2g})")
            continue
        if not eq:
            d = np.nanmax(np.abs(x.astype(float) - y.astype(float))) if x.size else 0.0
            print(f"  {k}: differs, max |diff| = {d:.3g}")
            same = False
    return same


def bench(tree: Path, repeat: int) -> dict:
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        path = f.name
    try:
        subprocess.run([sys.executable, str(tree / "benchmarks" / "bench_dynamics.py"),
                        "--skip-compile", "--repeat", str(repeat), "--json", path],
                       env=env_for(tree), check=True, cwd=tree, capture_output=True)
        with open(path) as f:
            return json.load(f)
    finally:
        os.unlink(path)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path)
    ap.add_argument("--inprocess-rounds", type=int, default=30)
    ap.add_argument("--after", type=Path, default=HERE)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--dump-only", action="store_true")
    ap.add_argument("--skip-dump", action="store_true")
    args = ap.parse_args(argv)
    ok = inprocess(args.inprocess_rounds) if args.inprocess_rounds else True
    if args.before is None:
        return 0 if ok else 1
    if not args.skip_dump:
        with tempfile.TemporaryDirectory() as tmp:
            a = dump(args.before, f"{tmp}/before.npz")
            b = dump(args.after, f"{tmp}/after.npz")
        same = compare(a, b)
        print(f"answers: {len(a)} arrays/values compared; "
              f"{'all identical' if same else 'DIFFERENCES (above)'}")
        ok &= same
    if args.dump_only:
        return 0 if ok else 1
    res = {"before": [], "after": []}
    for r in range(args.rounds):
        order = ("before", "after") if r % 2 == 0 else ("after", "before")
        for side in order:
            res[side].append(bench(getattr(args, side), args.repeat))
        print(f"  round {r + 1}/{args.rounds} done (load {os.getloadavg()[0]:.2f})", flush=True)
    keys = [k for k, v in res["before"][0].items()
            if isinstance(v, float) and k.endswith("_s") or k.startswith("long:")]
    print(f"\nbench_dynamics.py, medians of {args.rounds} interleaved runs per tree")
    print(f"  {'timing':60s} {'before':>10s} {'after':>10s} {'after/before':>13s}")
    for k in keys:
        b0 = st.median(x[k] for x in res["before"])
        a0 = st.median(x[k] for x in res["after"])
        ratio = a0 / b0
        flag = "" if ratio <= 1.05 or "scipy" in k else "  > 5 % slower"
        if flag:
            ok = False
        print(f"  {k[:60]:60s} {b0 * 1e3:8.2f}ms {a0 * 1e3:8.2f}ms {ratio:12.3f}{flag}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
