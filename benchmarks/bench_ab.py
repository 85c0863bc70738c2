"""A/B check of an integrator change, in one run.

``python benchmarks/bench_ab.py --before DIR [--rounds N] [--dump-only]``.

(Until issue 16 an in-process mode also compared against a frozen copy of the integrator
before issue 11.8, ``benchmarks/_radau_before.py``; that gate has served, and the copy no
longer matched the pieces it imported, so both are gone: compare against a checkout of the
commit before a change instead.)

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
# the terms beyond the paper's (compiled only where a run uses them, issue 35)
runs["damped"] = dict(quality_factor=300.0)
runs["damped_spring"] = dict(model="spring", quality_factor=30.0, velocity=10e-6, start=-5e-6,
                             turn=100e-9, end=-5e-6)
runs["liquid"] = dict(model="spring", spring_constant=0.1, mass=1e-11, radius=2e-6,
                      geometry="sphere-flat", hamaker=1e-20, viscosity=0.89e-3, permittivity=78.5,
                      double_layer="constant_potential", surface_potential=-0.04,
                      debye_length=9.6e-9, slip_length=5e-9, lever_drag=5e-5, velocity=10e-6,
                      start=-500e-9, turn=30e-9, end=-500e-9, sample_rate=20e3)
runs["hydration"] = dict(hydration_pressure=3e7, hydration_length=0.5e-9)
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
    ap.add_argument("--before", type=Path, required=True,
                    help="another checkout, e.g. git archive <commit> | tar -x -C DIR")
    ap.add_argument("--after", type=Path, default=HERE)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--dump-only", action="store_true")
    ap.add_argument("--skip-dump", action="store_true")
    args = ap.parse_args(argv)
    ok = True
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
