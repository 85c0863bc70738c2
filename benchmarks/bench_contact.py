"""Young's modulus speed (issue 26, item 4): one QI curve against nanite, and a 64 x 64 map.

    python benchmarks/bench_contact.py            # both
    python benchmarks/bench_contact.py --part qi  # the curve only (needs nanite: pip install -e .[bench])
    python benchmarks/bench_contact.py --part map --workers 2
    python benchmarks/bench_contact.py --part map-cpu --curves 512   # CPU time per curve, serial

**qi**: a 300 + 300-point curve (the PyFMlab gel curve, Bruker, read by afmforce and thinned
to 300 samples per run, as a QI pixel) analysed from the raw curve to the modulus --
afmforce: ``fast_modulus(curve)`` (calibration, tip depth, the fit: nanite's work) and, for
reference, ``analyze(curve, steps=["indentation"])`` (smoothing, regions, drift, calibration,
contact kind, force, the fit; its drift line changes E by ~6 % on this tilted baseline); nanite:
``Indentation`` on the force and height of the file's calibration (as fast_modulus's input),
its preprocessing (tip position, force offset, contact point by its default method,
deviation_from_baseline; also timed with fit_line_polynomial) and its fit of the same model
(Hertz paraboloid, R = 5 um, nu = 0.5, whole approach). Best of N each,
interleaved; prints both moduli and the ratio (target: afmforce >= 5x faster).

**map**: 4,096 such curves (the gel curve with a stiffness pattern, a tilted topography and
noise, written once to an afmforce map file in the system's temporary folder) through
``analyze_files`` on a local Dask cluster (``--workers``, default 2), steps indentation and
adhesion; prints the wall time (target: < 60 s on 2 cores) and the modulus range.
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
GEL = ROOT / "tests" / "data" / "bruker-nanoscope_PyFMlab_Egel4_00025.spm"


def qi_curve(n: int = 300):
    """The gel curve thinned to ``n`` samples per run."""
    from afmforce.io import load

    c = load(GEL)[0]
    seg = np.asarray(c.segment)
    idx = np.concatenate([np.flatnonzero(seg == s)[np.linspace(0, (seg == s).sum() - 1, n).astype(int)]
                          for s in (0, 1)])
    kw = {f.name: getattr(c, f.name)[idx] for f in dataclasses.fields(c)
          if isinstance(getattr(c, f.name), np.ndarray) and getattr(c, f.name).shape == seg.shape}
    return dataclasses.replace(c, **kw)


def _nanite_inputs(curve):
    """nanite's input: the file's calibration (deflection x sensitivity x k) and the height, as fast_modulus's."""
    md = curve.metadata
    seg = np.asarray(curve.segment)
    z = np.asarray(curve.piezo_measured if curve.piezo_measured is not None else curve.piezo_nominal)
    d = np.asarray(curve.deflection_signal) * (md["sensitivity"] if curve.deflection_unit == "V" else 1.0)
    k = float(md["spring_constant"])
    data = {"force": d * k, "height (measured)": -z, "segment": seg.astype(bool), "time": np.asarray(curve.time)}
    meta = {"spring constant": k, "sensitivity": 1.0, "path": "bench", "enum": 0,
            "imaging mode": "force-distance", "duration": 1.0, "point count": int(seg.size)}
    return data, meta


def bench_qi(repeat: int) -> None:
    import nanite

    from afmforce.analysis.indentation import fast_modulus
    from afmforce.analysis.options import IndentationOptions
    from afmforce.analysis.pipeline import analyze

    curve = qi_curve()
    data, md = _nanite_inputs(curve)
    opts = [IndentationOptions(tip_radius=5e-6, poisson=0.5)]

    def ours():  # the fast path: calibration, tip depth, the fit
        return fast_modulus(curve, opts[0]).youngs_modulus

    def pipeline():  # the whole analysis pipeline up to the modulus (drift, contact kind, ...)
        return analyze(curve, steps=["indentation"], options=opts).youngs_modulus

    def theirs(poc="deviation_from_baseline"):  # nanite's default contact-point method
        idnt = nanite.Indentation(data=dict(data), metadata=dict(md))
        idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset", "correct_tip_offset"],
                                 options={"correct_tip_offset": {"method": poc}})
        p = idnt.get_initial_fit_parameters(model_key="hertz_para")
        p["R"].set(value=5e-6)
        p["nu"].set(value=0.5)
        idnt.fit_model(model_key="hertz_para", params_initial=p, weight_cp=0, range_x=(0, 0),
                       range_type="absolute", segment="approach")
        return idnt.fit_properties["params_fitted"]["E"].value

    ours(), pipeline(), theirs(), theirs("fit_line_polynomial")  # warm: numba caches, imports
    cases = {"fast": ours, "pipeline": pipeline, "nanite": theirs, "nanite_poly": lambda: theirs("fit_line_polynomial")}
    times = {name: [] for name in cases}
    value = {}
    for _ in range(repeat):  # interleaved: the same load for all
        for name, func in cases.items():
            t = time.perf_counter()
            value[name] = func()
            times[name].append(time.perf_counter() - t)
    best = {name: min(t) for name, t in times.items()}
    med = {name: float(np.median(t)) for name, t in times.items()}
    print(f"qi curve 300+300 (best of {repeat}; medians in brackets), nanite {nanite.__version__}:")
    print(f"  afmforce fast_modulus   {best['fast'] * 1e3:7.2f} ms ({med['fast'] * 1e3:.2f})  E {value['fast']:.5g} Pa")
    print(f"  afmforce analyze(...)   {best['pipeline'] * 1e3:7.2f} ms ({med['pipeline'] * 1e3:.2f})  "
          f"E {value['pipeline']:.5g} Pa")
    print(f"  nanite (default poc)    {best['nanite'] * 1e3:7.2f} ms ({med['nanite'] * 1e3:.2f})  "
          f"E {value['nanite']:.5g} Pa")
    print(f"  nanite (fit_line_poly.) {best['nanite_poly'] * 1e3:7.2f} ms ({med['nanite_poly'] * 1e3:.2f})  "
          f"E {value['nanite_poly']:.5g} Pa")
    print(f"  ratio nanite / fast_modulus: {best['nanite'] / best['fast']:.1f}x (medians "
          f"{med['nanite'] / med['fast']:.1f}x; target >= 5x); nanite / analyze: "
          f"{best['nanite'] / best['pipeline']:.1f}x")


def make_map(path: Path, n: int = 64, step: float = 0.5e-6) -> Path:
    """A 64 x 64 afmforce map: the gel curve with a stiffness pattern, topography and noise."""
    from afmforce.io.native.rawmap import write_map

    base = qi_curve()
    rng = np.random.default_rng(0)
    seg = np.asarray(base.segment)
    d0 = np.asarray(base.deflection_signal)
    noise = 0.02 * float(np.std(d0[seg == 0][:50]) + 1e-12) + 1e-4 * float(np.ptp(d0))

    def curves():
        for y in range(n):
            for x in range(n):
                stiff = 1.0 + 0.5 * np.sin(x / 8.0) * np.cos(y / 11.0)  # the deflection scaled in contact
                top = 0.2e-6 * (x + y) / (2 * n)  # a tilted sample
                d = d0 - d0[0]
                d = d0[0] + d * stiff + rng.normal(0, noise, d.size)
                z = {f: getattr(base, f) + top for f in ("piezo_nominal", "piezo_measured")
                     if getattr(base, f) is not None}
                md = {**base.metadata, "map_x": x, "map_y": y, "position_x": x * step, "position_y": y * step}
                yield dataclasses.replace(base, deflection_signal=d, metadata=md, **z)

    return write_map(curves(), path, shape=(n, n), force=True)


def bench_map(workers: int) -> None:
    from afmforce.analysis.options import IndentationOptions
    from afmforce.sweep.files import CurveAnalysis, analyze_files, summary_table

    path = Path(tempfile.gettempdir()) / "afmforce-bench-contact-map64.h5"
    if not path.exists():
        t = time.perf_counter()
        make_map(path)
        print(f"wrote {path} in {time.perf_counter() - t:.1f} s")
    analysis = CurveAnalysis(steps=("indentation", "adhesion"),
                             options=(IndentationOptions(tip_radius=5e-6, poisson=0.5),))
    t = time.perf_counter()
    result = analyze_files([path], analysis, workers=workers)
    wall = time.perf_counter() - t
    table = summary_table(result)
    ok = table["error"].isna()
    E = table.loc[ok, "youngs_modulus"].to_numpy(float)
    print(f"map 64 x 64 ({len(table)} curves, {int(ok.sum())} analysed) on {result.executor} with {workers} "
          f"workers: {wall:.1f} s (target < 60 s; includes starting the cluster); E {np.nanmin(E):.4g} to "
          f"{np.nanmax(E):.4g} Pa, {int(np.isfinite(E).sum())} finite")


def bench_map_cpu(n_curves: int) -> None:
    """CPU time of the map's curves in this process (serial): the cost on an idle machine, whatever the load."""
    from afmforce.analysis.options import IndentationOptions
    from afmforce.sweep.files import CurveAnalysis, analyze_files, plan_curves

    path = Path(tempfile.gettempdir()) / "afmforce-bench-contact-map64.h5"
    if not path.exists():
        make_map(path)
    refs = plan_curves([path])[:n_curves]
    analysis = CurveAnalysis(steps=("indentation", "adhesion"),
                             options=(IndentationOptions(tip_radius=5e-6, poisson=0.5),))
    analyze_files(refs[:8], analysis, executor="serial")  # warm
    c, t = time.process_time(), time.perf_counter()
    analyze_files(refs, analysis, executor="serial", chunk_size=64)
    cpu, wall = time.process_time() - c, time.perf_counter() - t
    per = cpu / len(refs)
    print(f"map curves, serial, {len(refs)} curves: CPU {per * 1e3:.1f} ms per curve (wall "
          f"{wall / len(refs) * 1e3:.1f} ms): 4,096 curves on 2 cores = {4096 * per / 2:.1f} s of CPU each "
          "(target < 60 s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--part", choices=("qi", "map", "map-cpu", "all"), default="all")
    ap.add_argument("--curves", type=int, default=512, help="curves of the map-cpu part")
    ap.add_argument("--repeat", type=int, default=10)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    if args.part in ("qi", "all"):
        bench_qi(args.repeat)
    if args.part in ("map-cpu", "all"):
        bench_map_cpu(args.curves)
    if args.part in ("map", "all"):
        bench_map(args.workers)


if __name__ == "__main__":
    main()
