"""Fit view: a dynamic fit over several driving speeds, run as a job (progress pushed by SSE)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request
from pydantic import BaseModel, ConfigDict, Field

from ..errors import AfmforceError
from . import validate
from .jobs import fit_reserve
from ..limits import MAX_STARTS
from .limits import MAX_CURVES, MAX_ITEMS
from .schema import fit_defaults

router = APIRouter(tags=["fit"])
#: ``afmforce fit``'s defaults (:func:`afmforce.web.schema.fit_defaults`, from fit_dynamic's signature).
_DEFAULTS = fit_defaults()


class FitRequest(BaseModel):
    """A fit: uploaded curves (``file_ids``, calibrated; every curve of a file, a map's too) or
    virtual-AFM curves recorded at ``velocities`` from the ``truth`` configuration (flat names, SI).
    Numbers are JSON numbers (SI) or texts with units (``"1um/s"``); each is checked against its
    declared range before a process starts (:mod:`afmforce.web.validate`)."""

    model_config = ConfigDict(extra="forbid")

    file_ids: list[str] = Field(default=[], max_length=MAX_ITEMS,
                                description="this session's uploads (every curve of each file)")
    velocities: list[Any] = Field(default=[], max_length=MAX_CURVES,
                                  description="virtual curves: driving speeds [m/s] (or texts with units)")
    truth: dict[str, Any] = Field(default={}, description="model configuration, flat names, SI (fixed values)")
    seed: int = Field(default=0, ge=0, le=2**32 - 1, strict=True)
    free: list[str] = Field(default=_DEFAULTS["free"], max_length=16, description="global parameters to fit")
    meta: list[str] = Field(default=[], max_length=MAX_ITEMS, description="KEY=VALUE metadata for uploaded curves")
    starts: int = Field(default=_DEFAULTS["starts"], ge=1, le=MAX_STARTS, strict=True,
                        description="local fits from the best points of the search")
    profile: bool = Field(default=_DEFAULTS["profile"], strict=True, description="profile-likelihood intervals")
    compare: bool = Field(default=_DEFAULTS["compare"], strict=True,
                          description="model comparison (friction verdict)")


@router.post("/api/fit", status_code=202)
def fit(request: Request, body: FitRequest) -> dict:
    """Start a fit; returns ``{"id"}``. Follow it at ``GET /api/jobs/{id}`` or ``/api/jobs/{id}/events``."""
    from ..fit import PARAMETERS

    session = request.state.session
    unknown = [n for n in body.free if n not in PARAMETERS]
    if unknown or not body.free:
        raise validate.FieldError("free", f"free parameters {unknown[:5] or '[]'}: choose among "
                                          f"{', '.join(PARAMETERS)}")
    if body.file_ids and body.velocities:      # never one of them ignored silently
        raise validate.FieldError("velocities", "velocities are the speeds of virtual curves; with file_ids the "
                                                "uploaded curves are fitted at their own speeds: give one or the other")
    velocities = validate.velocities(body.velocities)
    truth = validate.flat_config(body.truth, "truth.")
    for name in ("velocity", "sample_rate"):     # each virtual curve's own (fit.virtual_curves)
        if name in truth:
            raise validate.FieldError(f"truth.{name}", f"truth.{name}: each virtual curve's {name} is set by "
                                      "velocities (sample rate: 2 samples per nm of travel); drop it from truth")
    cfg = validate.build_config(truth, "truth.")     # names, ranges and their combination
    from ..fit.params import check_free

    try:     # as `afmforce fit` before loading: a combination the model cannot fit, before a process starts
        check_free(body.free, cfg.model, cfg.friction.law if cfg.model == "beam" else None)
    except AfmforceError as exc:
        raise validate.FieldError("free", str(exc)) from None
    twice = sorted({fid for fid in body.file_ids if body.file_ids.count(fid) > 1})
    if twice:       # one measurement twice counts as two (fit.data: the same samples are refused)
        raise validate.FieldError("file_ids", f"file_ids: {twice[0]} is listed twice; give each upload once")
    files = []
    for i, fid in enumerate(body.file_ids):
        try:
            files.append(request.app.state.sessions.path(session, fid))
        except validate.FieldError:
            raise
        except AfmforceError as exc:
            raise validate.FieldError(f"file_ids[{i}]", str(exc)) from None
    meta = validate.metadata(body.meta)      # each item named when refused, then: dropped silently? never
    if meta and not files:
        raise validate.FieldError("meta", "meta overrides the metadata of uploaded curves (file_ids); virtual curves "
                                          "take their values from truth: drop meta, or give file_ids")
    if files:       # every curve of each upload (a map's too): the fit's cap, before a job starts
        sessions = request.app.state.sessions
        read = all(sessions.was_read(session, fid) for fid in body.file_ids)
        validate.fit_curve_count(files, None if read else request.app.state.settings.request_budget, meta)
    if not files and len(velocities) < 2:
        raise validate.FieldError("velocities", "give >= 2 uploaded curves (file_ids) or >= 2 velocities "
                                                "for virtual curves")
    if not files:
        from ..fit.core import check_speeds

        try:     # xi from virtual curves at one speed: refused now, not by the job after its curves
            check_speeds(body.free, velocities)
        except AfmforceError as exc:
            raise validate.FieldError("velocities", str(exc)) from None
        for i, v in enumerate(velocities):      # every virtual curve within the sample cap
            try:
                validate.build_config({**truth, "velocity": v})
            except validate.FieldError as exc:
                raise validate.FieldError(f"velocities[{i}]", f"velocities[{i}]: {exc}") from None
    params = body.model_dump()
    params.update(velocities=velocities, truth=truth)
    params["files"] = [(str(p), name) for p, name in files]
    params["meta"] = meta
    request.app.state.sessions.touch(session)
    job = request.app.state.jobs.submit("fit", session, params,    # 413 storage_full past the totals
                                        reserve=fit_reserve(len(files) or len(velocities)))
    return {"id": job.id, "state": job.state}
