"""Sweep view: a parameter sweep of the simulation on the local Dask cluster, as a resumable job."""

from __future__ import annotations

from fastapi import APIRouter, Request
from pydantic import BaseModel, Field

router = APIRouter(tags=["sweep"])


class SweepRequest(BaseModel):
    """A sweep in the words of ``afmforce sweep`` (values take units: ``xi=0.001:0.1:5:log``)."""

    grid: list[str] = Field(default=[], description="NAME=LO:HI:N[:log] or NAME=V1,V2,...")
    ranges: list[str] = Field(default=[], description="NAME=LO:HI[:log], sampled by `sample`")
    sets: list[str] = Field(default=[], description="NAME=VALUE fixed for every run")
    sample: str | None = Field(default=None, pattern="^(random|lhs)$")
    n: int | None = Field(default=None, ge=1, le=20_000)
    seed: int | None = None
    executor: str = Field(default="auto", pattern="^(auto|serial|dask)$",
                          description="auto: serial when quicker than starting the local cluster")
    chunk_size: int | None = Field(default=None, ge=1)


@router.post("/api/sweep", status_code=202)
def sweep(request: Request, body: SweepRequest) -> dict:
    """Start a sweep; returns ``{"id"}``. Chunks are stored as they finish; a server restart resumes it."""
    from ..sweep import build_spec
    from ..sweep.simulation import simulation_dimensions

    build_spec(body.grid, body.ranges, body.sets, sample=body.sample, n=body.n, seed=body.seed,
               dimensions=simulation_dimensions())      # bad names and values: 422 before a process starts
    job = request.app.state.jobs.submit("sweep", request.state.session, body.model_dump())
    return {"id": job.id, "state": job.state}
