"""Jobs: state, progress pushed as server-sent events, cancel."""

from __future__ import annotations

import asyncio
import json

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import StreamingResponse

from .jobs import FINISHED

router = APIRouter(tags=["jobs"])


def _job(request: Request, job_id: str):
    job = request.app.state.jobs.get(job_id, request.state.session)
    if job is None:   # another session's job looks like no job
        raise HTTPException(404, f"no job {job_id} in this session")
    return job


@router.get("/api/jobs")
def jobs(request: Request) -> list[dict]:
    """This session's jobs, newest first (without results)."""
    return [j.public(result=False) for j in request.app.state.jobs.list(request.state.session)]


@router.get("/api/jobs/{job_id}")
def job(request: Request, job_id: str) -> dict:
    """``{"id", "kind", "state", "progress", "result", "error", ...}``; state is queued, running, done,
    failed, cancelled or interrupted."""
    return _job(request, job_id).public()


@router.post("/api/jobs/{job_id}/cancel")
def cancel(request: Request, job_id: str) -> dict:
    """Stop a running job (its process is terminated)."""
    request.app.state.jobs.cancel(job_id, request.state.session) or _job(request, job_id)
    return {"id": job_id, "cancel": True}


@router.delete("/api/jobs/{job_id}")
def delete(request: Request, job_id: str) -> dict:
    """Remove a finished job: its record, its result and its sweep's store (their bytes are freed from
    the session's storage at once). A running job: 422, cancel it first."""
    if request.app.state.jobs.delete(job_id, request.state.session) is None:
        _job(request, job_id)        # 404
    return {"id": job_id, "deleted": True}


@router.get("/api/jobs/{job_id}/events")
async def events(request: Request, job_id: str) -> StreamingResponse:
    """Server-sent events: one ``progress`` event per change, then ``end`` with the job (and result)."""
    job = _job(request, job_id)

    async def stream():
        last = None
        while True:
            if await request.is_disconnected():
                return
            state, progress = job.state, json.dumps(job.progress)
            if progress != last:        # the last stage too, before the end
                last = progress
                yield f"event: progress\ndata: {json.dumps({'state': state, 'progress': job.progress})}\n\n"
            if state in FINISHED:
                yield f"event: end\ndata: {json.dumps(job.public())}\n\n"
                return
            await asyncio.sleep(0.2)

    return StreamingResponse(stream(), media_type="text/event-stream", headers={"cache-control": "no-cache"})
