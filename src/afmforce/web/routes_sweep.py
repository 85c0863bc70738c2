"""Sweep view: a parameter sweep of the simulation on the local Dask cluster, as a resumable job."""

from __future__ import annotations

from fastapi import APIRouter, Request
from pydantic import BaseModel, ConfigDict, Field

from . import validate
from .jobs import sweep_reserve
from .limits import MAX_ITEMS, MAX_RUNS

router = APIRouter(tags=["sweep"])


class SweepRequest(BaseModel):
    """A sweep in the words of ``afmforce sweep`` (values take units: ``xi=0.001:0.1:5:log``); at most
    :data:`~afmforce.web.limits.MAX_RUNS` runs, every value in its declared range."""

    model_config = ConfigDict(extra="forbid")

    grid: list[str] = Field(default=[], max_length=MAX_ITEMS, description="NAME=LO:HI:N[:log] or NAME=V1,V2,...")
    ranges: list[str] = Field(default=[], max_length=MAX_ITEMS, description="NAME=LO:HI[:log], sampled by `sample`")
    sets: list[str] = Field(default=[], max_length=MAX_ITEMS, description="NAME=VALUE fixed for every run")
    sample: str | None = Field(default=None, pattern="^(random|lhs)$")
    n: int | None = Field(default=None, ge=1, le=MAX_RUNS, strict=True)
    seed: int | None = Field(default=None, ge=0, le=2**32 - 1, strict=True)
    executor: str = Field(default="auto", pattern="^(auto|serial|dask)$",
                          description="auto: serial when quicker than starting the local cluster")
    chunk_size: int | None = Field(default=None, ge=1, le=MAX_RUNS, strict=True)


@router.post("/api/sweep", status_code=202)
def sweep(request: Request, body: SweepRequest) -> dict:
    """Start a sweep; returns ``{"id"}``. Chunks are stored as they finish; a server restart resumes it.
    Bad names and values, too many runs or samples: 422 before a process starts; results that would
    not fit in the session's or the server's storage (at most :func:`~.jobs.sweep_reserve`): 413."""
    spec = validate.sweep_spec(body.grid, body.ranges, body.sets, sample=body.sample, n=body.n, seed=body.seed)
    sessions, session = request.app.state.sessions, request.state.session
    sessions.touch(session)
    params = {**body.model_dump(), "max_runs": MAX_RUNS}
    n_parameters = len(spec.grid) + len(spec.ranges) + len(spec.fixed)
    job = request.app.state.jobs.submit("sweep", session, params,      # 413 storage_full past the totals
                                        reserve=sweep_reserve(spec.n_runs, n_parameters),
                                        store=sessions.sweeps(session))
    return {"id": job.id, "state": job.state}
