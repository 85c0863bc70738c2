"""Simulate view: one dynamic cycle from flat configuration names (SI); a raw file from the virtual AFM."""

from __future__ import annotations

import math
import time
from typing import Any

from fastapi import APIRouter, Body, HTTPException, Query, Request
from fastapi.responses import JSONResponse, Response

from .._json import to_jsonable
from ..errors import AfmforceError, ParameterError
from .tasks import decimate

router = APIRouter(tags=["simulate"])

#: Samples one web request may simulate (a cycle of 10 s at 100 kHz: 1e6).
MAX_SAMPLES = 2_000_000


class _PastBudget(AfmforceError):
    """A simulation ran past the request's time budget."""


def build_config(flat: dict[str, Any]):
    """The :class:`~afmforce.dynamics.SimulationConfig` of flat names in SI (None values: defaults);
    ParameterError for unknown names, values out of range or a cycle too long to sample."""
    from ..dynamics import SimulationConfig

    if not isinstance(flat, dict):
        raise ParameterError("the body must be a JSON object of flat configuration names (SI)")
    cfg = SimulationConfig(**{k: v for k, v in flat.items() if v is not None})
    d = cfg.drive
    back = d.retract_velocity or d.velocity
    n = ((d.turn - d.start) / d.velocity + (d.turn - d.end) / back + d.dwell) * cfg.solver.sample_rate
    if not math.isfinite(n) or n > MAX_SAMPLES:
        raise ParameterError(f"the cycle would have about {n:.3g} samples, more than the {MAX_SAMPLES:.0e} a "
                             "request may simulate; lower sample_rate, raise velocity or shorten the drive")
    cfg.validate()
    return cfg


def run(cfg, budget: float, check: str = "off"):
    """Simulate ``cfg``; cancelled (ParameterError-like 504) past ``budget`` [s]."""
    from ..dynamics import simulate

    deadline = time.monotonic() + budget

    def watch(_):
        if time.monotonic() > deadline:
            raise _PastBudget(f"cancelled: the simulation ran past its budget of {budget:g} s")

    return simulate(cfg, progress=watch, check=check)


@router.post("/api/simulate")
def simulate_endpoint(request: Request,
                      config: dict[str, Any] = Body(default={}, examples=[{"xi": 0.01, "velocity": 1e-6}],
                                                    description="flat names of SimulationConfig, SI"),
                      max_points: int | None = Query(None, ge=10, le=MAX_SAMPLES,
                                                     description="at most this many samples (evenly spread)"),
                      check: str = Query("off", pattern="^(off|auto|always)$",
                                         description="convergence guard (afmforce simulate --check)"),
                      columns: str | None = Query(None, description="comma-separated subset of the columns "
                                                                    "(default all)")) -> JSONResponse:
    """One approach-retract cycle: ``summary`` (as ``afmforce simulate --json``), ``columns`` (the
    trajectory, SI, units under ``units``), ``config`` (every flat name, SI), ``spring_constant``,
    ``calibration_factor``, ``n_samples``, ``wall_time`` [s]."""
    from ..dynamics.trajectory import COLUMNS

    t0 = time.perf_counter()
    cfg = build_config(config)
    try:
        traj = run(cfg, request.app.state.settings.request_budget, check)
    except _PastBudget as exc:
        raise HTTPException(504, str(exc)) from None
    wanted = list(COLUMNS) if not columns else [c.strip() for c in columns.split(",") if c.strip()]
    unknown = [c for c in wanted if c not in COLUMNS]
    if unknown:
        raise ParameterError(f"columns {unknown}: unknown; choose among {', '.join(COLUMNS)}")
    idx = decimate(len(traj), max_points)
    out = to_jsonable({"summary": traj.summary(), "units": {c: COLUMNS[c] for c in wanted},
                       "config": cfg.to_dict(), "spring_constant": traj.spring_constant,
                       "calibration_factor": traj.calibration_factor, "n_samples": len(traj)})
    cols = traj.columns()
    out["columns"] = {name: to_jsonable(cols[name][idx]) for name in wanted}   # converted in bulk, once
    out["wall_time"] = time.perf_counter() - t0
    return JSONResponse(out)


@router.post("/api/simulate/raw")
def raw_file(request: Request, config: dict[str, Any] = Body(default={}),
             preset: str = Query("typical", description="virtual-AFM preset (GET /api/schema)"),
             seed: int = Query(0, ge=0)) -> Response:
    """The cycle recorded by the virtual AFM, as an afmforce raw text file (``afmforce analyze`` reads it)."""
    from ..instrument.presets import PRESETS, get_preset
    from ..io.native.rawfile import format_text

    if preset not in PRESETS:
        raise ParameterError(f"preset {preset}: unknown; choose one of {', '.join(PRESETS)}")
    cfg = build_config(config)
    try:
        traj = run(cfg, request.app.state.settings.request_budget)
    except _PastBudget as exc:
        raise HTTPException(504, str(exc)) from None
    curve = get_preset(preset).record(traj, seed=seed)
    return Response(format_text(curve), media_type="text/plain",
                    headers={"content-disposition": f'attachment; filename="virtual-{preset}.raw"'})
