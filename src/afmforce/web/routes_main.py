"""The page, its static files (Plotly.js from the installed ``plotly`` package), health and schema."""

from __future__ import annotations

from functools import lru_cache
from importlib import resources
from pathlib import Path

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import FileResponse, HTMLResponse, Response

from .. import __version__
from .schema import schema

router = APIRouter()
STATIC = Path(__file__).with_name("static")
_TYPES = {".js": "text/javascript", ".css": "text/css", ".html": "text/html", ".png": "image/png"}


@lru_cache(maxsize=1)
def plotly_js() -> bytes:
    """``plotly.min.js`` as shipped in the ``plotly`` wheel (package data; no CDN)."""
    return resources.files("plotly").joinpath("package_data", "plotly.min.js").read_bytes()


@router.get("/", response_class=HTMLResponse, include_in_schema=False)
def index() -> HTMLResponse:
    return HTMLResponse((STATIC / "index.html").read_text(encoding="utf-8"))


@router.get("/static/plotly.min.js", include_in_schema=False)
def plotly() -> Response:
    return Response(plotly_js(), media_type="text/javascript",
                    headers={"cache-control": "public, max-age=86400"})


@router.get("/static/{name}", include_in_schema=False)
def static(name: str) -> FileResponse:
    # only a file listed in the folder: a name is never handed to the file system (a name too long
    # for it, a NUL byte or a path trick answered 500 or could leave the folder)
    if name not in _static_files():
        raise HTTPException(404, "no such file")
    path = STATIC / name
    return FileResponse(path, media_type=_TYPES.get(path.suffix, "application/octet-stream"))


@lru_cache(maxsize=1)
def _static_files() -> frozenset[str]:
    """The names of the page's static files (the folder's plain files, none hidden)."""
    return frozenset(p.name for p in STATIC.iterdir() if p.is_file() and not p.name.startswith("."))


@router.get("/api/health", tags=["server"])
def health(request: Request) -> dict:
    """``{"status": "ok", "version", "token_required", "max_upload", "jobs_running", "warm"}`` (warm: the
    simulator is loaded; until then the first simulation waits for it)."""
    s = request.app.state.settings
    return {"status": "ok", "version": __version__, "token_required": s.token is not None,
            "max_upload": s.max_upload, "jobs_running": request.app.state.jobs.running(),
            "warm": request.app.state.warm.is_set()}


@router.get("/api/session", tags=["server"])
def session(request: Request) -> dict:
    """This browser's session, for the page to restore after a reload: ``files`` (the uploads, as
    ``GET /api/files``), ``jobs`` (as ``GET /api/jobs``), ``ttl`` [s] and ``expires`` (s since the
    epoch; null while the session has stored nothing), ``stored`` (bytes of its uploads) and
    ``max_stored`` (the bytes it may keep, ``--session-storage``). Reading it stores nothing."""
    sid = request.state.session
    sessions, jobs = request.app.state.sessions, request.app.state.jobs
    used = sessions.last_used(sid)
    return {"files": sessions.files(sid), "jobs": [j.public(result=False) for j in jobs.list(sid)],
            "ttl": sessions.ttl, "expires": None if used is None else used + sessions.ttl,
            "stored": sessions.stored_bytes(sid), "max_stored": sessions.session_bytes}


@router.get("/api/schema", tags=["server"])
def get_schema() -> dict:
    """Every control of the page: simulation fields (flat names, SI unit, shown unit, range, default),
    the analysis steps' options, the fit's parameters, the example files, the instrument presets."""
    return schema()
