"""Analyse view: upload force-curve files (or pick an example) and analyse them."""

from __future__ import annotations

import time
from typing import Annotated

from fastapi import APIRouter, File, Form, HTTPException, Request, UploadFile
from fastapi.responses import JSONResponse
from starlette.concurrency import run_in_threadpool

from .._fields import ANALYSIS_CHOICES
from ..errors import ParameterError
from .analysis import check_inputs, run_analysis
from .warm import wait_until_warm
from .limits import CALIBRATION_BYTES, MAX_ITEMS, RESPONSE_POINTS
from .compute import compute
from .validate import FieldError, calibration_file

router = APIRouter(tags=["analyse"])


@router.post("/api/analyze")
async def analyze(request: Request,
                  file: Annotated[list[UploadFile], File(description="force-curve files or force maps")] = [],
                  file_id: Annotated[list[str], Form(description="files uploaded before in this session")] = [],
                  example: Annotated[list[str], Form(description="shipped example files (GET /api/schema)")] = [],
                  option: Annotated[list[str], Form(description="STEP.NAME=VALUE with units, as "
                                                                "afmforce analyze --option")] = [],
                  step: Annotated[list[str], Form(description="analysis steps to run (GET /api/schema 'steps'; "
                                                              "their requirements are added), as --steps; "
                                                              "none: all")] = [],
                  meta: Annotated[list[str], Form(description="KEY=VALUE file metadata, as --meta")] = [],
                  probe: Annotated[list[str], Form(description="NAME=VALUE probe calibration (radius, "
                                                               "spring_constant, theta0, sensitivity, ...)")] = [],
                  calibration: Annotated[UploadFile | None, File(description="probe calibration file (afmforce "
                                                                    "calibrate --out): k, InvOLS, f0 where "
                                                                    "'probe' gives none")] = None,
                  calibration_keys: Annotated[list[str], Form(description="with calibration: the probe values "
                                                                          "to take from it (default: all it "
                                                                          "holds that 'probe' does not give)")] = [],
                  format: Annotated[str | None, Form(description="reader instead of detection")] = None,
                  channel: Annotated[str, Form(description=ANALYSIS_CHOICES["channel"].help + ", as --channel")
                                     ] = ANALYSIS_CHOICES["channel"].default,
                  arrays: Annotated[bool, Form(description="add per-sample arrays, raw signals, maps")] = False,
                  max_points: Annotated[int, Form(ge=100, le=RESPONSE_POINTS)] = 4000,
                  curve: Annotated[list[str], Form(description="with arrays: the curves whose arrays and raw "
                                                               "signal to send (names as returned; the first "
                                                               "when none matches); default: every curve")] = []
                  ) -> JSONResponse:
    """The JSON of ``afmforce analyze FILE --json`` (``results``, ``failed``, ``oscillation_origin``)
    plus ``files`` (the ids to re-run with ``file_id`` after an option change) and ``wall_time`` [s];
    with ``arrays`` also ``raw`` and ``maps``. A file that cannot be read is listed under ``failed``.
    ``calibration`` gives what ``--probe-calibration`` gives; a ``probe`` value wins over it."""
    from ..datasets import DATASETS, path as example_path

    settings, sessions = request.app.state.settings, request.app.state.sessions
    session = request.state.session
    for name, items in (("file", file), ("file_id", file_id), ("example", example), ("option", option),
                        ("step", step), ("meta", meta), ("probe", probe), ("curve", curve),
                        ("calibration_keys", calibration_keys)):
        if len(items) > MAX_ITEMS:
            raise FieldError(name, f"{name}: at most {MAX_ITEMS} per request, got {len(items)}")
    from_file = None
    if calibration_keys:      # never ignored silently: a key the file cannot give, or no file to take it from
        from ..calibration.record import ANALYSIS_KEYS

        if calibration is None:
            raise FieldError("calibration_keys", "calibration_keys names the values to take from a calibration "
                                                 "file: send the file as 'calibration' too, or drop calibration_keys")
        for i, key in enumerate(calibration_keys):
            if key not in ANALYSIS_KEYS:
                raise FieldError(f"calibration_keys[{i}]", f"calibration_keys[{i}] {key[:40]!r}: not a value a "
                                 f"calibration file gives the analysis; choose among {', '.join(ANALYSIS_KEYS)}")
    if calibration is not None:     # as `afmforce analyze --probe-calibration`: the typed value wins
        from ..calibration.record import calibration_basis

        given = {str(t).partition("=")[0].strip() for t in probe}
        data = await calibration.read(CALIBRATION_BYTES + 1)     # a bigger one is refused: never read whole
        values = calibration_file(data, calibration.filename or "calibration", size=calibration.size)
        taken = {k: v for k, v in values.items() if k not in given and (not calibration_keys or k in calibration_keys)}
        probe = list(probe) + [f"{k}={v!r}" for k, v in taken.items()]
        # its values named as the calibration file's in the warnings, a thermal k rescaled with a refitted InvOLS
        from_file = (tuple(taken), *calibration_basis(data.decode("utf-8")))
    # every typed value checked before an upload is stored: a request refused for a typo leaves no file
    await run_in_threadpool(check_inputs, option, meta, probe, calibration=from_file, steps=step or None,
                            format=format, channel=channel)
    # copied from the request's spooled parts to the session's folder, never read whole into memory (each
    # upload of 200 MB held 200 MB of the server's memory until its analysis ended, however many came at once)
    uploads = [(up.filename or "upload", up.file) for up in file]
    stored = await run_in_threadpool(sessions.save_all, session, uploads)   # all or none; 413 storage_full past the totals
    paths = [sessions.path(session, s["id"]) for s in stored]
    fields = [f"file[{i}]" for i in range(len(stored))]     # how the request names each file
    for i, fid in enumerate(file_id):
        try:
            paths.append(sessions.path(session, fid))
        except ParameterError as exc:
            raise FieldError(f"file_id[{i}]", str(exc)) from None
        fields.append(f"file_id[{i}]")
    for i, name in enumerate(example):
        if name not in DATASETS:
            raise FieldError(f"example[{i}]", f"example {name[:60]!r}: unknown; choose one of {', '.join(DATASETS)}")
        paths.append((example_path(name), name))
        fields.append(f"example[{i}]")
    if not paths:
        raise FieldError("file", "give a file (field 'file'), an uploaded file's id ('file_id') or an example")
    await run_in_threadpool(wait_until_warm, request.app)    # the budget starts after the warm-up
    guard = bool(stored) or not all(sessions.was_read(session, fid) for fid in file_id)

    def work(stop):      # stops after the curve it is on: past its deadline, or its client gone (stop)
        return run_analysis(paths, option, meta, probe, calibration=from_file, steps=step or None,
                            format=format, channel=channel, arrays=arrays, max_points=max_points,
                            budget=settings.request_budget, guard=guard,
                            deadline=time.monotonic() + settings.request_budget, curves=curve, stop=stop.is_set,
                            fields=fields)

    payload = await compute(request, work, settings.request_budget, "analysis")   # a slot of MAX_COMPUTING
    payload["files"] = stored + [{"id": fid, "name": sessions.path(session, fid)[1]} for fid in file_id]
    bad = {f["file"] for f in payload["failed"]}
    sessions.mark_read(session, [f["id"] for f in payload["files"] if f["name"] not in bad])
    return JSONResponse(payload)   # plain JSON already: no second walk through every value


@router.post("/api/calibration")
async def calibration(file: Annotated[UploadFile, File(description="the JSON of afmforce calibrate --out")]) -> dict:
    """The probe values [SI] the analyse view takes from a calibration file: ``{"source", "values"}``
    with ``values`` the spring constant, sensitivity (InvOLS) and resonance frequency it holds,
    each checked as its field; 422 naming ``calibration`` for a file that is not one."""
    name = file.filename or "calibration"
    return {"source": name, "values": calibration_file(await file.read(CALIBRATION_BYTES + 1), name, size=file.size)}


@router.get("/api/files")
def files(request: Request) -> list[dict]:
    """This session's uploads: ``[{"id", "name", "size"}]`` (other sessions' are never listed)."""
    return request.app.state.sessions.files(request.state.session)


@router.delete("/api/files/{file_id}")
def delete_file(request: Request, file_id: str) -> dict:
    """Remove one of this session's uploads (404: no upload of this session has that id)."""
    try:
        request.app.state.sessions.remove(request.state.session, file_id)
    except ParameterError as exc:       # as a job of no session's: not found, whatever the id looks like
        raise HTTPException(404, str(exc)) from None
    return {"id": file_id, "deleted": True}
