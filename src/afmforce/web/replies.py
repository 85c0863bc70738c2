"""Every refusal of the server in one shape: ``{"error": {"type", "message", "field"}}``.

``type`` says what kind of refusal it is (``invalid_value``, ``invalid_request``,
``too_large``, ``storage_full``, ``forbidden``, ``unauthorized``, ``not_found``, ``past_budget``, ``job_failed``;
a library error's class in snake case, e.g. ``parameter_error``), ``message`` is one readable
line in the words of the command line, ``field`` names the value refused as the request spells
it (``velocity``, ``truth.xi``, ``velocities[0]``, ``max_points``; several, comma-separated, when
they cause it together: ``grid[0], ranges[1]``) or is null. FastAPI's own
``{"detail": [...]}`` never reaches a client: :func:`install` replaces its handlers.
"""

from __future__ import annotations

import json
import logging
import re
from typing import Any

from ..errors import AfmforceError, render_keys

__all__ = ["error_body", "error_bytes", "install", "JobStartError", "PastBudget", "TooManyJobs"]

_STATUS_TYPES = {400: "invalid_request", 401: "unauthorized", 403: "forbidden", 404: "not_found",
                 405: "method_not_allowed", 413: "too_large", 422: "invalid_value", 429: "too_many_jobs",
                 504: "past_budget"}
_LOG = logging.getLogger("afmforce.web")


def error_body(type: str, message: str, field: str | None = None) -> dict[str, Any]:
    """``{"error": {"type", "message", "field"}}``; the quantities a library message names
    (`` `key` ``) are shown as the web's field names (the keys themselves)."""
    return {"error": {"type": type, "message": render_keys(message, lambda key: key), "field": field}}


def error_bytes(type: str, message: str, field: str | None = None) -> bytes:
    """:func:`error_body` as JSON bytes (for the ASGI middleware)."""
    return json.dumps(error_body(type, message, field)).encode()


def _snake(name: str) -> str:
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower()


def _loc(loc) -> str | None:
    """``("body", "velocities", 0)`` -> ``"velocities[0]"``; ``("query", "max_points")`` -> ``"max_points"``."""
    parts = [p for p in loc if p not in ("body", "query", "path", "header", "cookie", "form")] \
        if loc and loc[0] in ("body", "query", "path", "header", "cookie", "form") else list(loc or ())
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or None


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


#: FastAPI's reply to a body its JSON reader raised on (not a JSONDecodeError: 400, this detail).
_UNPARSED = "There was an error parsing the body"


def _unparsed(cause: BaseException | None) -> str:
    """Why a JSON body could not be read, in the client's terms: nested too deeply (a RecursionError of
    the parser: ``[[[[...`` 100,000 deep) or a number of more digits than Python converts (4,300)."""
    if isinstance(cause, RecursionError):
        why = "it is nested too deeply"
    elif isinstance(cause, ValueError) and "digits" in str(cause):
        why = "it holds an integer of more than 4,300 digits"
    else:
        why = f"{type(cause).__name__ if cause is not None else 'unreadable'}"
    return (f"the body could not be read as JSON ({why}); send a JSON object of the request's fields "
            "(numbers as SI values or texts with units), with content-type application/json")


class PastBudget(AfmforceError):
    """A request ran past its time budget and was cancelled, its computation included (504)."""


class Busy(AfmforceError):
    """The server computes and queues as many requests as it may (429; raised by :mod:`.compute`)."""


class ClientGone(AfmforceError):
    """The client left before its computation ended (nobody reads the reply; raised by :mod:`.compute`)."""


class TooManyJobs(AfmforceError):
    """A fit or sweep asked for while the server (or the session) runs as many as it may (429)."""


class JobStartError(Exception):
    """A job could not be started or saved (a fault of the server, not of the request)."""


def install(app) -> None:
    """Install the handlers that give every refusal the one shape."""
    from fastapi.exceptions import RequestValidationError
    from fastapi.responses import JSONResponse
    from starlette.exceptions import HTTPException

    from .sessions import StorageFull
    from .validate import FieldError

    @app.exception_handler(AfmforceError)
    async def _library(request, exc: AfmforceError):   # one readable line, as the CLI prints
        field = exc.field if isinstance(exc, FieldError) else None
        kind = "invalid_value" if isinstance(exc, FieldError) else _snake(type(exc).__name__)
        return JSONResponse(error_body(kind, str(exc), field), status_code=422)

    @app.exception_handler(RequestValidationError)
    async def _request(request, exc: RequestValidationError):
        errors = exc.errors()
        first = errors[0] if errors else {}
        field = _loc(first.get("loc"))
        msg = first.get("msg", "invalid request")
        if first.get("type") == "json_invalid":
            field, msg = None, "the body is not valid JSON"
        elif "Expected UploadFile" in msg:   # a part without a file name: pydantic's words name its classes
            msg = ("a form value, not a file: send each file as a multipart/form-data file part with its "
                   "file name")
        elif isinstance(first.get("input"), (bytes, bytearray)) and first.get("type") in (
                "dict_type", "model_attributes_type"):  # a form or text body where JSON is read
            field, msg = None, "the body must be a JSON object, sent with content-type application/json"
        elif "input" in first and first.get("type") != "missing":
            msg = f"{msg}, got {_shown(first['input'])}"
        return JSONResponse(error_body("invalid_request", f"{field}: {msg}" if field else msg, field),
                            status_code=422)

    @app.exception_handler(HTTPException)
    async def _http(request, exc: HTTPException):
        if exc.status_code == 400 and exc.detail == _UNPARSED:     # FastAPI's words, whatever the cause
            return JSONResponse(error_body("invalid_request", _unparsed(exc.__cause__)), status_code=422)
        return JSONResponse(error_body(_STATUS_TYPES.get(exc.status_code, "error"), str(exc.detail)),
                            status_code=exc.status_code, headers=getattr(exc, "headers", None))

    @app.exception_handler(StorageFull)
    async def _full(request, exc: StorageFull):   # the session's (or server's) stored uploads: 413, nothing evicted
        return JSONResponse(error_body("storage_full", str(exc)), status_code=413)

    @app.exception_handler(PastBudget)
    async def _budget(request, exc: PastBudget):
        return JSONResponse(error_body("past_budget", str(exc)), status_code=504)

    @app.exception_handler(TooManyJobs)
    async def _busy(request, exc: TooManyJobs):
        return JSONResponse(error_body("too_many_jobs", str(exc)), status_code=429, headers={"retry-after": "10"})

    @app.exception_handler(Busy)
    async def _computing(request, exc: Busy):   # every slot to compute taken, and the queue full
        return JSONResponse(error_body("busy", str(exc)), status_code=429, headers={"retry-after": "5"})

    @app.exception_handler(ClientGone)
    async def _gone(request, exc: ClientGone):    # nobody reads it (nginx's "client closed request")
        return JSONResponse(error_body("client_gone", str(exc)), status_code=499)

    @app.exception_handler(JobStartError)
    async def _job(request, exc: JobStartError):
        return JSONResponse(error_body("job_failed", str(exc)), status_code=503)

    @app.exception_handler(Exception)
    async def _fault(request, exc: Exception):    # a fault of the server: logged, no traceback to the client
        _LOG.exception("unexpected error in %s %s", request.method, request.url.path)
        return JSONResponse(error_body("internal", f"unexpected {type(exc).__name__}; the server logged it"),
                            status_code=500)
