"""What a job runs, in its own process: a dynamic fit or a parameter sweep.

:func:`run_task` is the child process's entry point; it reports to the server through
a queue: ``("progress", {...})``, then ``("result", {...})`` or ``("error", "message")``.
Values are SI, as in the library.
"""

from __future__ import annotations

import math
import warnings
from typing import Any, Callable

import numpy as np

from .._json import to_jsonable
from ..errors import AfmforceError

__all__ = ["run_task", "standby", "decimate"]


def decimate(n: int, max_points: int | None) -> np.ndarray:
    """Indices of at most ``max_points`` evenly spread samples of ``n`` (all when None)."""
    if not max_points or n <= max_points:
        return np.arange(n)
    return np.unique(np.linspace(0, n - 1, int(max_points)).round().astype(int))


def _progress_dict(p) -> dict[str, Any]:
    return {"done": float(p.done), "total": None if p.total is None else float(p.total), "unit": p.unit,
            "what": p.what, "fraction": p.fraction, "failed": p.failed, "skipped": p.skipped}


def fit_task(params: dict[str, Any], progress: Callable) -> dict[str, Any]:
    """A dynamic fit of uploaded curves (``files``: [(path, name)]; every curve of a file, named
    ``NAME#i`` where it holds several) or of virtual-AFM curves
    recorded at ``velocities`` [m/s] from the ``truth`` configuration (flat names, SI)."""
    from ..dynamics import SimulationConfig
    from ..fit import fit_dynamic, virtual_curves
    from ..fit.core import lever_sources
    from ..io import load

    truth = dict(params.get("truth") or {})
    files = params.get("files") or []
    if files:
        curves, names = [], []
        for path, name in files:
            got = load(path, meta_override=params.get("meta") or None)
            curves += list(got)      # every curve of a file with several (a map), as `afmforce fit`
            names += [name] if len(got) == 1 else [f"{name}#{i + 1}" for i in range(len(got))]
    else:
        velocities = [float(v) for v in params.get("velocities") or ()]
        curves = virtual_curves(velocities, seed=int(params.get("seed", 0)), **truth)
        names = [f"virtual {v * 1e6:.3g} um/s" for v in velocities]
    free = list(params.get("free") or ("hamaker", "xi"))
    model = SimulationConfig(**{k: v for k, v in truth.items() if k not in free})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = fit_dynamic(curves, model, free=free, names=names,
                          **({"starts": int(params["starts"])} if "starts" in params else {}),
                          profile=None if params.get("profile", True) else (),
                          compare=bool(params.get("compare", True)), progress=progress,
                          # the files' lever and mass unless the form gives one, as `afmforce fit` (issue 34)
                          **lever_sources(truth))
    out = res.to_dict()
    out["markdown"] = res.markdown()
    out["verdict"] = _verdict(res)
    plots = []
    for c, cf, m in zip(res._problem.ev.curves, res.curves, res.predictions()):
        idx = decimate(len(c.position), 1500)
        plots.append({"name": c.name, "position": (c.position[idx] - cf.shift).tolist(),
                      "data": c.deflection[idx].tolist(), "used": c.mask[idx].tolist(),
                      "model": None if m is None else m[idx].tolist()})
    out["plots"] = plots
    return to_jsonable(out)


def _verdict(res) -> str:
    if res.friction_detected is None:
        return "friction not tested (model comparison skipped)"
    p = res.p_value
    word = "detected" if res.friction_detected else "not detected"
    return f"friction {word} (likelihood-ratio p = {p:.3g})" if math.isfinite(p) else f"friction {word}"


def sweep_task(params: dict[str, Any], progress: Callable) -> dict[str, Any]:
    """A parameter sweep of the simulation on the local Dask cluster (serial when small),
    stored under ``store``: the same command resumes from the chunks already stored."""
    from ..sweep import build_spec, run_sweep
    from ..sweep.page import sweep_payload
    from ..sweep.simulation import OUTPUT_UNITS, parameter_units, simulate_run, simulation_dimensions

    spec = build_spec(list(params.get("grid") or ()), list(params.get("ranges") or ()),
                      list(params.get("sets") or ()), sample=params.get("sample"), n=params.get("n"),
                      seed=params.get("seed"), dimensions=simulation_dimensions())
    from .limits import MAX_RUNS

    most = int(params.get("max_runs", MAX_RUNS))
    if spec.n_runs > most:
        raise AfmforceError(f"the sweep has {spec.n_runs:,} runs; the web page runs at most "
                            f"{most:,} (use afmforce sweep for more)")
    result = run_sweep(simulate_run, spec, chunk_size=params.get("chunk_size"),
                       executor=params.get("executor", "auto"), workers=params.get("workers"),
                       store=params["store"], progress=progress)
    units = {**parameter_units(result.parameter_names), **OUTPUT_UNITS}
    result.write(result.store.root, units)
    return to_jsonable({"store": str(result.store.root),
                        **sweep_payload(result, units, max_rows=int(params.get("max_rows", 2000)))})


TASKS = {"fit": fit_task, "sweep": sweep_task}


def run_task(kind: str, params: dict[str, Any], queue) -> None:
    """Child-process entry point: run the task, report progress and the outcome on ``queue``."""
    def progress(p) -> None:
        queue.put(("progress", _progress_dict(p)))

    try:
        queue.put(("result", TASKS[kind](params, progress)))
    except AfmforceError as exc:
        queue.put(("error", str(exc)))
    except Exception as exc:  # reported to the page, the server keeps running
        queue.put(("error", f"unexpected {type(exc).__name__}: {exc}"))


def standby(inbox, queue, parent: int, warm: bool = True) -> None:
    """A spare job process: load the compiled integrator now (about 5 s: numba's cache), then wait
    for one task on ``inbox`` and run it. It leaves when the server (``parent``) is gone."""
    import os
    import queue as _queue

    if warm:
        try:
            from ..dynamics import simulate

            simulate(velocity=1e-5)
        except Exception as exc:   # noqa: BLE001 -- a warm-up only: logged, the spare still takes its job
            import logging

            logging.getLogger("afmforce.web").warning(
                "warm-up of a spare job process failed (%s: %s); it takes its job unwarmed", type(exc).__name__, exc)
    while True:
        try:
            kind, params = inbox.get(timeout=1.0)
        except _queue.Empty:
            if os.getppid() != parent:
                return
            continue
        return run_task(kind, params, queue)
