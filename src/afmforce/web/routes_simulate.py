"""Simulate view: one dynamic cycle from flat configuration names (SI); a raw file from the virtual AFM."""

from __future__ import annotations

import time
from typing import Any

from fastapi import APIRouter, Body, Query, Request
from fastapi.responses import JSONResponse, Response
from starlette.concurrency import run_in_threadpool

from .._json import to_jsonable
from . import validate
from .limits import RAW_SAMPLES, RESPONSE_POINTS
from .warm import wait_until_warm
from .compute import compute
from .replies import PastBudget
from .tasks import decimate

router = APIRouter(tags=["simulate"])


class _PastBudget(PastBudget):
    """A simulation ran past the request's time budget."""


def build_config(flat: dict[str, Any]):
    """The :class:`~afmforce.dynamics.SimulationConfig` of flat names (SI, or texts with units): every
    value checked against its declaration, the cycle at most :data:`~.limits.MAX_SAMPLES` samples
    (:func:`afmforce.web.validate.build_config`). FieldError (422) otherwise."""
    return validate.build_config(flat)


def run(cfg, budget: float, check: str = "off", stop=None):
    """Simulate ``cfg``; cancelled past ``budget`` [s], or once ``stop`` (a :class:`threading.Event`) is
    set (its client left, :func:`~.compute.compute`): the integrator's progress callback raises, so the
    computation stops too (504)."""
    from ..dynamics import simulate

    deadline = time.monotonic() + budget

    def watch(_):
        if time.monotonic() > deadline:
            raise _PastBudget(f"cancelled: the simulation ran past its budget of {budget:g} s")
        if stop is not None and stop.is_set():
            raise _PastBudget("cancelled: the request ended before the simulation (its client left)")

    return simulate(cfg, progress=watch, check=check)


@router.post("/api/simulate")
async def simulate_endpoint(request: Request,
                      config: dict[str, Any] = Body(default={}, examples=[{"xi": 0.01, "velocity": 1e-6}],
                                                    description="flat names of SimulationConfig, SI"),
                      max_points: int = Query(RESPONSE_POINTS, ge=10, le=RESPONSE_POINTS,
                                              description="at most this many samples per column (evenly "
                                                          "spread; the response's size cap)"),
                      check: str = Query("off", pattern="^(off|auto|always)$",
                                         description="convergence guard (afmforce simulate --check)"),
                      columns: str | None = Query(None, max_length=400,
                                                  description="comma-separated subset of the columns "
                                                              "(default all)")) -> JSONResponse:
    """One approach-retract cycle: ``summary`` (as ``afmforce simulate --json``), ``columns`` (the
    trajectory, SI, units under ``units``), ``config`` (every flat name, SI), ``spring_constant``,
    ``calibration_factor``, ``n_samples``, ``wall_time`` [s]."""
    from ..dynamics.trajectory import COLUMNS

    t0 = time.perf_counter()
    cfg = await run_in_threadpool(build_config, config)    # the unit parser: never on the event loop
    wanted = list(COLUMNS) if not columns else [c.strip() for c in columns.split(",") if c.strip()]
    unknown = [c for c in wanted if c not in COLUMNS]
    if unknown:
        raise validate.FieldError("columns", f"columns {unknown[:5]}: unknown; choose among {', '.join(COLUMNS)}")
    await run_in_threadpool(wait_until_warm, request.app)        # the budget starts after the server's warm-up
    budget = request.app.state.settings.request_budget

    def work(stop):
        traj = run(cfg, budget, check, stop)
        idx = decimate(len(traj), max_points)
        out = to_jsonable({"summary": traj.summary(), "units": {c: COLUMNS[c] for c in wanted},
                           "config": cfg.to_dict(), "spring_constant": traj.spring_constant,
                           "calibration_factor": traj.calibration_factor, "n_samples": len(traj)})
        cols = traj.columns()
        out["columns"] = {name: to_jsonable(cols[name][idx]) for name in wanted}   # converted in bulk, once
        return out

    out = await compute(request, work, budget, "simulation")     # a slot of MAX_COMPUTING
    out["wall_time"] = time.perf_counter() - t0
    return JSONResponse(out)


@router.post("/api/simulate/raw")
async def raw_file(request: Request, config: dict[str, Any] = Body(default={}),
             preset: str = Query("typical", description="virtual-AFM preset (GET /api/schema)"),
             seed: int = Query(0, ge=0, le=2**32 - 1)) -> Response:
    """The cycle recorded by the virtual AFM, as an afmforce raw text file (``afmforce analyze`` reads it)."""
    from ..instrument.presets import PRESETS, get_preset
    from ..io.native.rawfile import format_text

    if preset not in PRESETS:
        raise validate.FieldError("preset", f"preset {preset[:40]}: unknown; choose one of {', '.join(PRESETS)}")
    cfg = await run_in_threadpool(build_config, config)    # the unit parser: never on the event loop
    n = validate.cycle_samples(cfg)
    if n > RAW_SAMPLES:     # the response's size cap: about 100 bytes a row
        raise validate.FieldError("sample_rate", f"the raw file would have about {n:.3g} rows, more than the "
                                  f"{RAW_SAMPLES:,} an export may carry; lower sample_rate or raise velocity")
    await run_in_threadpool(wait_until_warm, request.app)
    budget = request.app.state.settings.request_budget

    def work(stop):
        return format_text(get_preset(preset).record(run(cfg, budget, stop=stop), seed=seed))

    text = await compute(request, work, budget, "simulation")     # a slot of MAX_COMPUTING
    return Response(text, media_type="text/plain",
                    headers={"content-disposition": f'attachment; filename="virtual-{preset}.raw"'})
