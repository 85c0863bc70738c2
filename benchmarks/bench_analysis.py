"""Benchmark: the analysis pipeline per curve against nanite, on the real files and on many synthetic curves.

Run::

    python benchmarks/bench_analysis.py [--real DIR] [--skip-synthetic] [--curves 200] [--points 2000] [--repeat 5]

Real curves (issue 13), first: every file of ``../shared/data/real`` (or ``--real DIR``),
per curve, loading included: afmforce ``load`` + the full default ``analyze`` pipeline
against afmformats ``load_data`` + nanite's preprocessing (``compute_tip_position``,
``correct_force_offset``, ``correct_tip_offset`` with ``fit_line_polynomial``: the
contact-point search). Each side is timed in CPU seconds of this process (the
machine is shared; wall clock varies with the other jobs), best of ``--repeat``,
interleaved. A file afmformats cannot read goes to nanite as afmforce's reading
(marked ``*``: nanite's time then counts afmforce's load). Target: median ratio >= 10x.

Synthetic curves, then: ``--curves`` noisy, drifting variants of one quasi-static curve
(``--points`` samples each) through the product's pipeline
(:func:`afmforce.analysis.pipeline.analyze`, the one implementation of the steps; the
compiled seven-step copy ``analysis.batch`` was removed in issue 11.5), once with
every default step and once with the core steps only (drift, compliance, calibration,
zero, jumps: nanite's preprocessing does no fits either), against nanite's
preprocessing of the same arrays (``compute_tip_position``, ``correct_force_offset``,
``correct_tip_offset`` with the ``fit_line_polynomial`` contact point, as for the real files). Per curve, CPU ms, best of
``--repeat``, the two tools interleaved; the accuracy of the jump-in and pull-off
found against the generator's truth is printed beside it. nanite is a
benchmark-only dependency: ``pip install afmforce[bench]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from afmforce.analysis.synthetic import static_curve

SENSITIVITY = 50e-9  # m/V
SPRING_CONSTANT = 0.21  # N/m


def make_curves(n_curves: int, n_points: int, seed: int = 0):
    """``n_curves`` noisy, drifting variants of one quasi-static curve with ``n_points`` samples."""
    start, turn = -60e-9, 30e-9
    end = -1.3 * 5.6e-8 / SPRING_CONSTANT - 40e-9
    path = (turn - start) + (turn - end)
    velocity = 0.5e-6
    rate = velocity * n_points / path
    base = static_curve(velocity=velocity, sample_rate=rate, start=start, turn=turn, end=end,
                        sensitivity=SENSITIVITY, seed=None)
    n = len(base)
    rng = np.random.default_rng(seed)
    t = base.time
    noise = rng.standard_normal((n_curves, n)) * (0.05e-9 / SENSITIVITY)
    drift = rng.normal(0, 0.02, (n_curves, 1)) * t[None, :]
    offset = rng.normal(0, 0.1, (n_curves, 1))
    signal = base.deflection_signal[None, :] - 0.3 + offset + drift + noise
    z = np.broadcast_to(base.piezo_nominal, (n_curves, n)).copy()
    n_app = int(np.sum(base.segment == 0))
    return t, z, signal, n_app, base


def _curve(t, z, s, base):
    """One synthetic stack row as the RawCurve a reader would give (signal in V, sensitivity known)."""
    from afmforce.io.curve import RawCurve

    meta = dict(base.metadata, sensitivity=SENSITIVITY)
    return RawCurve(time=t, piezo_nominal=z, deflection_signal=s, segment=base.segment, metadata=meta,
                    deflection_unit=base.deflection_unit)


def _analyze_all(curves, steps):
    from afmforce.analysis.pipeline import analyze

    return [analyze(c, steps=steps) for c in curves]


def _nanite_synthetic(t, z, s, n_app, n_curves):
    """A function running nanite's preprocessing over the synthetic stack (None: no nanite)."""
    try:
        import nanite
    except ImportError:
        return None
    seg = np.concatenate([np.zeros(n_app, bool), np.ones(z.shape[1] - n_app, bool)])
    meta = {"spring constant": SPRING_CONSTANT, "sensitivity": SENSITIVITY, "imaging mode": "force-distance",
            "duration": float(t[-1]), "point count": int(t.size), "rate approach": float(1 / (t[1] - t[0])),
            "path": "synthetic", "enum": 0}

    def run():
        for i in range(n_curves):
            data = {"force": s[i] * SENSITIVITY * SPRING_CONSTANT, "height (measured)": -z[i],
                    "segment": seg, "time": t}
            nanite.Indentation(data=data, metadata=dict(meta)).apply_preprocessing(NANITE_STEPS,
                                                                                    options=NANITE_OPTIONS)
    return run


def _jump_index(result, which):
    """Index of the jump-in / pull-off the pipeline found (-1: none)."""
    j = result.details.get("jumps")
    jump = None if j is None else (j.get(which) if hasattr(j, "get") else getattr(j, which, None))
    return int(jump.index) if jump is not None and jump.found else -1


#: The pipeline's core steps (no fits), comparable to nanite's preprocessing.
CORE_STEPS = ("drift", "compliance", "calibration", "zero", "jumps")


def bench_synthetic(n_curves, n_points, repeat):
    """Per-curve CPU time of the pipeline (all steps, core steps) and of nanite, interleaved rounds."""
    t, z, s, n_app, base = make_curves(n_curves, n_points)
    curves = [_curve(t, z[i], s[i], base) for i in range(n_curves)]
    print(f"\nSynthetic curves: {n_curves} x {t.size} points, per curve, CPU ms (best of {repeat} interleaved "
          "rounds); afmforce analyze (the product's pipeline) vs nanite preprocessing of the same arrays "
          "(fit_line_polynomial contact point)")
    sides = {"all default steps": lambda: _analyze_all(curves, None),
             "core steps " + "+".join(CORE_STEPS): lambda: _analyze_all(curves, CORE_STEPS)}
    nanite_run = _nanite_synthetic(t, z, s, n_app, n_curves)
    if nanite_run is not None:
        sides["nanite"] = nanite_run
    for fn in sides.values():  # imports and compiled kernels, not timed
        fn()
    best = {k: math.inf for k in sides}
    results = {}
    for _ in range(repeat):
        for name, fn in sides.items():
            cpu, results[name] = _cpu(fn, 1)
            best[name] = min(best[name], cpu / n_curves)
    nan = best.get("nanite")
    truth = base.truth
    for name in sides:
        if name == "nanite":
            continue
        res, per = results[name], best[name]
        ji = np.array([_jump_index(r, "jump_in") for r in res])
        po = np.array([_jump_index(r, "pull_off") for r in res])
        ok_ji = np.mean(np.abs(ji - truth["jump_in_index"]) <= 1)
        ok_po = np.mean(np.abs(po - truth["pull_off_index"]) <= 1)
        cal = np.nanmedian(np.abs(np.array([r.sensitivity_fit for r in res]) / SENSITIVITY - 1))
        nan_txt = f"nanite {nan * 1e3:.1f} ms, ratio {nan / per:.1f}x" if nan else "nanite not installed"
        print(f"  afmforce {name}: {per * 1e3:.2f} ms/curve; {nan_txt}")
        print(f"    jump-in within one sample {ok_ji:.1%}, pull-off {ok_po:.1%}, "
              f"median calibration error {cal:.2%}")


#: metadata a user gives for files that lack it (as the README's commands do)
REAL_META = {
    "afmformats_afm-workshop-fd_single_2018-08-01.csv": {"spring_constant": 0.1, "sensitivity": 50e-9},
    "afmformats_jpk-fd_single-modified_2023.jpk-force": {"spring_constant": 12.0},
    "ntmdt_gel-in-water.txt": {"spring_constant": 0.1, "sensitivity": 50e-9},
}
NANITE_STEPS = ["compute_tip_position", "correct_force_offset", "correct_tip_offset"]
NANITE_OPTIONS = {"correct_tip_offset": {"method": "fit_line_polynomial"}}


def _loadavg() -> tuple[float, ...]:
    """The machine's load average (1, 5, 15 min; NaN where the OS has none)."""
    import os

    try:
        return os.getloadavg()
    except (AttributeError, OSError):
        return (math.nan,) * 3


def _cpu(fn, repeat):
    """Best CPU seconds (this process, all threads) of ``repeat`` calls, and the last result."""
    best, res = math.inf, None
    for _ in range(repeat):
        c0 = time.process_time()
        res = fn()
        best = min(best, time.process_time() - c0)
    return best, res


def _ours(path, meta):
    from afmforce.errors import AfmforceError
    from afmforce.io import load
    from afmforce.analysis.pipeline import analyze

    curves = load(path, meta_override=meta)
    verdicts = []
    for c in curves:
        try:
            verdicts.append(analyze(c).contact_kind)
        except AfmforceError as exc:
            verdicts.append(f"error: {exc}"[:40])
    return len(curves), verdicts


def _nanite_afmformats(path, meta):
    import afmformats
    import nanite

    from afmforce.io._meta import afmformats_override

    n = 0
    for dd in afmformats.load_data(path, meta_override=afmformats_override(meta)):
        idnt = nanite.Indentation(data=dd._raw_data, metadata=dd.metadata)
        idnt.apply_preprocessing(NANITE_STEPS, options=NANITE_OPTIONS)
        n += 1
    return n


def _nanite_ours(path, meta):
    """nanite on afmforce's reading (a file afmformats cannot read): force [N], height = -z."""
    import nanite

    from afmforce.io import load

    n = 0
    for c in load(path, meta_override=meta):
        md = c.metadata
        k, sens = md.get("spring_constant"), md.get("sensitivity")
        if c.deflection_unit == "N":
            force = c.deflection_signal
        elif k and (c.deflection_unit == "m" or sens):
            force = c.deflection_signal * k * (1.0 if c.deflection_unit == "m" else sens)
        else:
            raise ValueError("no spring constant")
        z = c.piezo_measured if c.piezo_measured is not None else c.piezo_nominal
        keep = np.isin(c.segment, (0, 1))
        seg = (c.segment[keep] == 1)
        data = {"force": force[keep], "height (measured)": -z[keep], "segment": seg, "time": c.time[keep]}
        meta_n = {"spring constant": float(k or 1.0), "sensitivity": float(sens or 1.0),
                  "imaging mode": "force-distance", "duration": float(np.ptp(c.time)),
                  "point count": int(keep.sum()), "rate approach": float(md.get("sample_rate", 1.0) or 1.0),
                  "path": str(path), "enum": n}
        nanite.Indentation(data=data, metadata=meta_n).apply_preprocessing(NANITE_STEPS, options=NANITE_OPTIONS)
        n += 1
    return n


def bench_real(folder, repeat):
    """Per-curve CPU time of afmforce (load + analyze) and nanite (load + preprocessing) on real files."""
    import warnings
    from pathlib import Path

    from afmforce.errors import AfmforceError
    from afmforce.io import load

    warnings.simplefilter("ignore")
    files = sorted(p for p in Path(folder).iterdir() if p.is_file() and p.suffix.lower() != ".md")
    try:
        import nanite  # noqa: F401
    except ImportError:
        nanite = None
    print(f"load average (1, 5, 15 min) at the start: {', '.join(f'{x:.2f}' for x in _loadavg())}")
    print(f"Real curves in {folder}: per curve, loading included, CPU ms (best of {repeat}); "
          "afmforce load+analyze vs afmformats load + nanite preprocessing with the fit_line_polynomial "
          "contact point")
    print(f"  {'file':<52} {'curves':>6} {'points':>7} {'afmforce':>9} {'nanite':>9} {'ratio':>7}  kinds")
    ratios = []
    for path in files:
        meta = REAL_META.get(path.name, {})
        try:
            load(path, meta_override=meta)  # warm up: imports, compiled kernels
            _ours(path, meta)
        except AfmforceError as exc:
            print(f"  {path.name:<52} afmforce: {str(exc)[:70]}")
            continue
        t_ours, (n, kinds) = _cpu(lambda: _ours(path, meta), repeat)
        points = load(path, meta_override=meta)[0].time.size
        t_nan, mark, why = math.nan, " ", ""
        if nanite is not None:
            for fn, m in ((_nanite_afmformats, " "), (_nanite_ours, "*")):
                try:
                    fn(path, meta)
                    t_nan, nn = _cpu(lambda: fn(path, meta), repeat)
                    mark = m
                    break
                except BaseException as exc:  # afmformats raises BaseException subclasses
                    if isinstance(exc, KeyboardInterrupt):
                        raise
                    why = f"{type(exc).__name__}: {str(exc)[:40]}"
            else:
                nn = 0
            t_nan = t_nan / nn if nn else math.nan
        ratio = t_nan / (t_ours / n)
        if math.isfinite(ratio):
            ratios.append(ratio)
        nan_txt = f"{t_nan * 1e3:8.1f}{mark}" if math.isfinite(t_nan) else f"{'-':>9}"
        print(f"  {path.name:<52} {n:>6} {points:>7} {t_ours / n * 1e3:9.1f} {nan_txt} "
              f"{ratio:7.1f}  {','.join(sorted(set(kinds)))}" + (f"  (nanite: {why})" if not math.isfinite(t_nan)
                                                                else ""))
    if ratios:
        med = float(np.median(ratios))
        print(f"  median ratio nanite/afmforce over {len(ratios)} files: {med:.1f}x (min {min(ratios):.1f}x) "
              f"-- target >= 10x: {'met' if med >= 10 else 'NOT met'}; load average at the end: "
              f"{', '.join(f'{x:.2f}' for x in _loadavg())}")
    elif nanite is None:
        print("  nanite not installed: no ratio. Install the benchmark extra: pip install 'afmforce[bench]'")


def main(argv=None) -> int:
    from pathlib import Path

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--real", default=str(Path(__file__).resolve().parents[1].parent / "shared" / "data" / "real"),
                    help="folder of real force-curve files (default ../shared/data/real)")
    ap.add_argument("--skip-synthetic", action="store_true", help="only the real curves")
    ap.add_argument("--curves", type=int, default=200, help="synthetic curves")
    ap.add_argument("--points", type=int, default=2000, help="samples per synthetic curve")
    ap.add_argument("--repeat", type=int, default=5,
                    help="best of this many runs per side (the machine is shared: 5 steadies the best)")
    args = ap.parse_args(argv)
    if Path(args.real).is_dir():
        bench_real(args.real, args.repeat)
    else:
        print(f"no folder {args.real}: real-curve benchmark skipped (give --real DIR)")
    if not args.skip_synthetic:
        bench_synthetic(args.curves, args.points, args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
