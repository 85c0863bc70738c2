"""Adhesive contact fits (issue 34 item 3, issue 35): speed, the optimum and the intervals' coverage,
before and after, on the same curves in the same run.

    python benchmarks/bench_adhesive.py                       # 20 seeds x JKR, DMT, Maugis, 300 samples
    python benchmarks/bench_adhesive.py --samples 1000 --seeds 10
    python benchmarks/bench_adhesive.py --before 92c9cd3      # the tree to compare with (a git revision)
    python benchmarks/bench_adhesive.py --skip-before --seeds 200   # coverage of the current fit alone

Curves: tests/contact/adhesive_curves.py -- the JKR, DMT and Maugis-Dugdale (lambda = 1) laws solved
there with brentq (not afmforce's inversion), E = 2 kPa, w = 0.1 mJ/m^2, R = 5 um, nu = 0.5, the
tip depth over 3.5 um, a contact point drawn per seed in 0.2-0.4 um (off any grid), a baseline
(0.1 nN rms) and white noise of 20 pN.

**before**: ``git archive REV src`` of ``--before`` (default: the commit before the new fit) in a
temporary folder, its ``fit_indentation`` run in a subprocess on the same curves; **after**: this
tree's. Each fit timed in CPU seconds (``time.process_time``; one thread: the machine's other jobs
change it little) and wall seconds. Printed per law: median time, the ratio, the coverage of E's,
w's and the contact point's 95 % intervals (contact: +- 1.97 se), the largest |E_after/E_before - 1|
and |E/E_true - 1|, and the sum of squares of before's optimum over after's (> 1: before missed the
minimum). Then the non-adhesive laws' E before and after (the same code: expected identical), and a
work-of-adhesion map's cost per curve through the pipeline (``fast_modulus`` and
``analyze(steps=["indentation"])``, JKR on the retract, ``indentation.run=retract``, on calibrated raw
curves of 300 + 300 points: an approach without adhesion, a retract with JKR's neck).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "contact"))
import adhesive_curves as ac  # noqa: E402

BEFORE = "92c9cd3"  # the last commit before the adhesive fit of issue 34 item 3
LAWS = ("jkr", "dmt", "maugis")
ELASTIC = (("hertz_paraboloid", {"radius": 5e-6}), ("sneddon_sphere", {"radius": 2e-6}),
           ("hertz_cone", {"half_angle": 0.35}), ("hertz_thin_layer", {"radius": 5e-6, "thickness": 3e-6}))

_RUNNER = r"""
import json, math, sys, time, warnings
import numpy as np
from afmforce.contact.fit import fit_indentation
data = np.load(sys.argv[1], allow_pickle=True)
jobs = json.loads(sys.argv[2])
out = []
warm = set()
for j in jobs:
    u, F = data[j["u"]], data[j["F"]]
    if j["model"] not in warm:  # compiled kernels and tables ready
        warm.add(j["model"])
        fit_indentation(u, F, j["model"], j["geom"], nu=0.5, transition=1.0)
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f = fit_indentation(u, F, j["model"], j["geom"], nu=0.5, transition=1.0)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    out.append(dict(E=f.youngs_modulus, E_low=f.youngs_modulus_low, E_high=f.youngs_modulus_high,
                    w=f.work_of_adhesion, w_se=f.work_of_adhesion_se,
                    w_low=getattr(f, "work_of_adhesion_low", f.work_of_adhesion - 1.97 * f.work_of_adhesion_se),
                    w_high=getattr(f, "work_of_adhesion_high", f.work_of_adhesion + 1.97 * f.work_of_adhesion_se),
                    c=f.contact, c_se=f.contact_se, b=f.baseline, ssr=float(np.sum(f.residuals ** 2)),
                    wall=wall, cpu=cpu))
print(json.dumps(out))
"""


def _tree(rev: str, dest: Path) -> Path:
    """``src`` of git revision ``rev`` under ``dest``."""
    blob = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src"], check=True, capture_output=True).stdout
    dest.mkdir(parents=True, exist_ok=True)
    tar = dest / "src.tar"
    tar.write_bytes(blob)
    with tarfile.open(tar) as t:
        t.extractall(dest, filter="data")
    return dest / "src"


def _run(src: Path, npz: Path, jobs: list[dict]) -> list[dict]:
    env = {**os.environ, "PYTHONPATH": str(src), "NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    out = subprocess.run([sys.executable, "-c", _RUNNER, str(npz), json.dumps(jobs)], env=env, check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _coverage(res: list[dict], truth: list[dict]) -> dict:
    cE = sum(r["E_low"] <= t["E"] <= r["E_high"] for r, t in zip(res, truth))
    cw = sum(r["w_low"] <= t["w"] <= r["w_high"] for r, t in zip(res, truth))
    cc = sum(abs(r["c"] - t["c"]) <= 1.97 * r["c_se"] for r, t in zip(res, truth))
    return {"E": cE, "w": cw, "c": cc}


def adhesive_part(args, tmp: Path) -> None:
    arrays, jobs, truth = {}, [], []
    t0 = time.perf_counter()
    for law in LAWS:
        for s in range(args.seeds):
            u, F, tr = ac.curve(law, s, n=args.samples)
            arrays[f"u{law}{s}"], arrays[f"F{law}{s}"] = u, F
            jobs.append({"u": f"u{law}{s}", "F": f"F{law}{s}", "model": law, "geom": {"radius": ac.R_TIP},
                         "law": law})
            truth.append(tr)
    npz = tmp / "curves.npz"
    np.savez(npz, **arrays)
    print(f"{len(jobs)} curves of {args.samples} samples from the independent solver in "
          f"{time.perf_counter() - t0:.1f} s; load average {os.getloadavg()[0]:.2f}", flush=True)
    after = _run(ROOT / "src", npz, jobs)
    before = None if args.skip_before else _run(_tree(args.before, tmp / "before"), npz, jobs)
    print(f"load average {os.getloadavg()[0]:.2f}")
    head = f"{'law':8s} {'median CPU / wall [ms]':>26s}"
    if before:
        head += f" {'before [ms]':>18s} {'speed-up':>9s} {'coverage before E/w/c':>22s}"
    head += f" {'coverage E/w/c':>15s} {'max|E/E_true-1|':>16s}"
    if before:
        head += f" {'max|E/E_before-1|':>18s} {'max SSR before/after':>21s}"
    print(head)
    for law in LAWS:
        idx = [i for i, j in enumerate(jobs) if j["law"] == law]
        a = [after[i] for i in idx]
        tr = [truth[i] for i in idx]
        ca = _coverage(a, tr)
        line = (f"{law:8s} {np.median([r['cpu'] for r in a]) * 1e3:12.2f} / "
                f"{np.median([r['wall'] for r in a]) * 1e3:9.2f}")
        if before:
            b = [before[i] for i in idx]
            cb = _coverage(b, tr)
            tb, ta = np.median([r["cpu"] for r in b]), np.median([r["cpu"] for r in a])
            line += (f" {tb * 1e3:18.1f} {tb / ta:8.0f}x {cb['E']:>10d}/{cb['w']}/{cb['c']} of {len(idx)}")
        line += f" {ca['E']:>7d}/{ca['w']}/{ca['c']} of {len(idx)}"
        line += f" {max(abs(r['E'] / t['E'] - 1) for r, t in zip(a, tr)):16.2e}"
        if before:
            line += f" {max(abs(r['E'] / q['E'] - 1) for r, q in zip(a, b)):18.2e}"
            line += f" {max(q['ssr'] / r['ssr'] for r, q in zip(a, b)):21.3g}"
        print(line)
    if before:
        _elastic_part(args, tmp, tmp / "before" / "src")


def _elastic_part(args, tmp: Path, src_before: Path) -> None:
    """The non-adhesive laws: E before and after on the same noisy curves (the same code path)."""
    arrays, jobs = {}, []
    rng = np.random.default_rng(3)
    from afmforce.contact.fit import model_force

    for key, geom in ELASTIC:
        for s in range(5):
            u = np.linspace(-2e-6, 1.5e-6, args.samples)
            F = model_force(key, u - 0.3e-6 - 1e-8 * s, 2e3, geom, 0.5) + 1e-11 + rng.normal(0, 2e-11, u.size)
            arrays[f"u{key}{s}"], arrays[f"F{key}{s}"] = u, F
            jobs.append({"u": f"u{key}{s}", "F": f"F{key}{s}", "model": key, "geom": geom})
    npz = tmp / "elastic.npz"
    np.savez(npz, **arrays)
    a, b = _run(ROOT / "src", npz, jobs), _run(src_before, npz, jobs)
    dev = max(abs(x["E"] / y["E"] - 1) for x, y in zip(a, b))
    dse = max(abs(x["E_high"] / y["E_high"] - 1) for x, y in zip(a, b))
    print(f"non-adhesive laws ({', '.join(k for k, _ in ELASTIC)}; 5 curves each): largest |E_after/E_before - 1| "
          f"= {dev:.1e}, of the interval's upper end {dse:.1e}")


def map_part(args) -> None:
    """A work-of-adhesion map's cost per curve: JKR on the retract through fast_modulus and analyze."""
    import warnings

    from afmforce.analysis.indentation import fast_modulus
    from afmforce.analysis.options import IndentationOptions
    from afmforce.analysis.pipeline import analyze
    from afmforce.io.curve import RawCurve

    from afmforce.contact.models import hertz_paraboloid

    k, sens, n = 0.05, 40e-9, 300
    curves = []
    for s in range(args.map_curves):  # the approach without adhesion (no jump-in: a soft contact), the
        rng = np.random.default_rng(s)  # retract with JKR's neck down to the pull-off
        c = float(rng.uniform(0.2e-6, 0.4e-6))
        u = np.linspace(-2e-6, 1.5e-6, n)
        Fa = hertz_paraboloid(u - c, ac.E_TRUE, ac.R_TIP, ac.NU) + rng.normal(0, ac.NOISE, n)
        Fr = ac.jkr_force(u - c, ac.E_TRUE, ac.W_TRUE, ac.R_TIP, retract=True) + rng.normal(0, ac.NOISE, n)
        z = 5e-6 + np.concatenate((u + Fa / k, (u + Fr / k)[::-1]))  # the piezo adds the lever's deflection
        volts = np.concatenate((Fa, Fr[::-1])) / k / sens + 0.3
        curves.append(RawCurve(time=np.arange(2 * n) * 1e-3, piezo_nominal=z, deflection_signal=volts,
                               segment=np.repeat(np.array([0, 1], dtype=np.int8), n), deflection_unit="V",
                               metadata={"spring_constant": k, "sensitivity": sens}))
    opts = IndentationOptions(model="jkr", tip_radius=ac.R_TIP, run="retract")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast_modulus(curves[0], opts)
        analyze(curves[0], steps=["indentation"], options=[opts])
        for name, fn in (("fast_modulus", lambda c: fast_modulus(c, opts)),
                         ("analyze(steps=['indentation'])", lambda c: analyze(c, steps=["indentation"],
                                                                              options=[opts]))):
            c0, t0 = time.process_time(), time.perf_counter()
            res = [fn(c) for c in curves]
            cpu, wall = (time.process_time() - c0) / len(curves), (time.perf_counter() - t0) / len(curves)
            w = [r.work_of_adhesion for r in res]
            print(f"JKR map, {name}: {cpu * 1e3:.2f} ms CPU ({wall * 1e3:.2f} wall) per curve of {n} + {n} points "
                  f"-> 64 x 64: {4096 * cpu / 2:.0f} s, 128 x 128: {16384 * cpu / 2:.0f} s on 2 cores; "
                  f"w {np.median(w):.4g} J/m^2 (truth {ac.W_TRUE:g})")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=20)
    p.add_argument("--samples", type=int, default=300)
    p.add_argument("--before", default=BEFORE, help="git revision to compare with")
    p.add_argument("--skip-before", action="store_true")
    p.add_argument("--map-curves", type=int, default=50)
    p.add_argument("--part", choices=("all", "fit", "map"), default="all")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        if args.part in ("all", "fit"):
            adhesive_part(args, Path(tmp))
        if args.part in ("all", "map"):
            map_part(args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
