"""Fit view: a dynamic fit over several driving speeds, run as a job (progress pushed by SSE)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from pydantic import BaseModel, Field

from ..errors import ParameterError

router = APIRouter(tags=["fit"])


class FitRequest(BaseModel):
    """A fit: uploaded curves (``file_ids``, calibrated; every curve of a file, a map's too) or
    virtual-AFM curves recorded at ``velocities`` from the ``truth`` configuration (flat names, SI)."""

    file_ids: list[str] = Field(default=[], description="this session's uploads (every curve of each file)")
    velocities: list[float] = Field(default=[], description="virtual curves: driving speeds [m/s]")
    truth: dict[str, Any] = Field(default={}, description="model configuration, flat names, SI (fixed values)")
    seed: int = 0
    free: list[str] = Field(default=["hamaker", "xi"], description="global parameters to fit")
    meta: list[str] = Field(default=[], description="KEY=VALUE metadata for uploaded curves")
    starts: int = Field(default=1, ge=1, le=6)
    profile: bool = Field(default=True, description="profile-likelihood intervals")
    compare: bool = Field(default=True, description="model comparison (friction verdict)")


@router.post("/api/fit", status_code=202)
def fit(request: Request, body: FitRequest) -> dict:
    """Start a fit; returns ``{"id"}``. Follow it at ``GET /api/jobs/{id}`` or ``/api/jobs/{id}/events``."""
    from ..dynamics import SimulationConfig
    from ..fit import PARAMETERS
    from ..io._meta import parse_meta_args

    session = request.state.session
    unknown = [n for n in body.free if n not in PARAMETERS]
    if unknown or not body.free:
        raise ParameterError(f"free parameters {unknown or '[]'}: choose among {', '.join(PARAMETERS)}")
    SimulationConfig(**body.truth)      # checks names and ranges before a process starts
    files = [request.app.state.sessions.path(session, fid) for fid in body.file_ids]
    if not files and len(body.velocities) < 2:
        raise ParameterError("give >= 2 uploaded curves (file_ids) or >= 2 velocities for virtual curves")
    if len(body.velocities) > 8:
        raise ParameterError("at most 8 virtual curves")
    params = body.model_dump()
    params["files"] = [(str(p), name) for p, name in files]
    params["meta"] = parse_meta_args(body.meta)
    job = request.app.state.jobs.submit("fit", session, params)
    return {"id": job.id, "state": job.state}
