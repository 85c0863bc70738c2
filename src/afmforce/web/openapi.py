"""The OpenAPI document with typed request and response models built from the declarations.

The routes take flat configuration names as a JSON object and validate them themselves
(:mod:`afmforce.web.validate`, one message for every face), so FastAPI alone would publish
``{"type": "object"}`` for them. :func:`install` replaces ``app.openapi`` by a builder that
adds, from the same declarations the server checks against:

- ``SimulationConfig``: every flat name of :data:`afmforce.dynamics.config.FLAT` with its
  unit, range (``minimum``/``maximum``, exclusive where the range is open), default, and
  the registry's choices for text fields; a number may also be a text with units
  (``"1um/s"``). Used by ``/api/simulate``, ``/api/simulate/raw`` and ``FitRequest.truth``.
- ``ProbeCalibration`` and ``AnalysisOptions``: the names the analyse view's ``probe`` and
  ``option`` form items take (``NAME=VALUE``, ``STEP.NAME=VALUE``), with units and ranges.
- ``SimulateResponse`` (the trajectory's columns with their units) and ``AnalysisResult``
  (each result field with its unit), the 200 answers of ``/api/simulate`` and ``/api/analyze``.
- ``Error``: the one refusal shape ``{"error": {"type", "message", "field"}}`` (422 and others).

Nothing here is written by hand per field: a new declaration appears in the document.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

__all__ = ["install", "number_schema", "config_schema", "build"]


def _finite(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def number_schema(spec, default: Any = None, help: str = "") -> dict[str, Any]:
    """JSON Schema of one declared number: a number in its range [SI], or a text with units."""
    num: dict[str, Any] = {"type": "integer" if spec.dimension == "integer" else "number"}
    if spec.lo is not None:
        num["exclusiveMinimum" if spec.lo_open else "minimum"] = spec.lo
    if spec.hi is not None:
        num["exclusiveMaximum" if spec.hi_open else "maximum"] = spec.hi
    out: dict[str, Any] = {
        "anyOf": [num, {"type": "string", "maxLength": 64, "description": "a number with units, e.g. '200nm'"}],
        "description": f"{help or spec.help} [{spec.unit or '-'}]; range {spec.range_text()}",
        "x-unit": spec.unit,
    }
    if _finite(default):
        out["default"] = default
    return out


def config_schema() -> dict[str, Any]:
    """``SimulationConfig`` as flat names (:data:`afmforce.dynamics.config.FLAT`)."""
    from ..dynamics.config import FLAT

    props: dict[str, Any] = {}
    for name, where in FLAT.items():
        if where.spec is None:
            props[name] = {"type": "string", "enum": sorted(where.choices), "description": name}
            if isinstance(where.default, str):
                props[name]["default"] = where.default
        else:
            props[name] = number_schema(where.spec, where.default)
        props[name]["x-models"] = list(where.models)
    return {"title": "SimulationConfig", "type": "object", "additionalProperties": False, "properties": props,
            "description": "Flat names of afmforce.dynamics.SimulationConfig, SI (or texts with units); "
                           "omitted names take their defaults."}


def _record_schema(cls, title: str, prefix: str = "") -> dict[str, Any]:
    props = {}
    for f in dataclasses.fields(cls):
        spec = f.metadata.get("spec")
        if spec is None:
            continue
        default = f.default if f.default is not dataclasses.MISSING else None
        if spec.dimension in ("choice", "flag", "text"):
            props[prefix + f.name] = {"type": "string", "description": spec.help}
        else:
            props[prefix + f.name] = number_schema(spec, default)
    return {"title": title, "type": "object", "additionalProperties": False, "properties": props}


def _analysis_schemas() -> dict[str, Any]:
    from ..analysis.options import OPTIONS, ProbeCalibration
    from ..analysis.result import AnalysisResult

    options: dict[str, Any] = {"title": "AnalysisOptions", "type": "object", "additionalProperties": False,
                               "properties": {},
                               "description": "Options of the analysis steps, sent as form items "
                                              "option=STEP.NAME=VALUE (as afmforce analyze --option)."}
    for step, cls in OPTIONS.items():
        options["properties"].update(_record_schema(cls, step, f"{step}.")["properties"])
    probe = _record_schema(ProbeCalibration, "ProbeCalibration")
    probe["description"] = "Probe calibration, sent as form items probe=NAME=VALUE (SI or with units)."
    units = dict(getattr(AnalysisResult, "UNITS", {}))
    result = {"title": "AnalysisResult", "type": "object",
              "description": "One curve's result (afmforce analyze --json); numbers SI, null when not "
                             "determined; 'units' repeats each field's unit.",
              "properties": {name: {"type": ["number", "null"], "description": f"[{unit or '-'}]",
                                    "x-unit": unit} for name, unit in units.items()}}
    return {"AnalysisOptions": options, "ProbeCalibration": probe, "AnalysisResult": result}


def _simulate_response() -> dict[str, Any]:
    from ..dynamics.trajectory import COLUMNS

    columns = {name: {"type": "array", "items": {"type": "number"}, "description": f"[{unit or '-'}]",
                      "x-unit": unit} for name, unit in COLUMNS.items()}
    return {"title": "SimulateResponse", "type": "object", "properties": {
        "summary": {"type": "object", "description": "as afmforce simulate --json"},
        "columns": {"type": "object", "properties": columns, "description": "the trajectory, SI, decimated"},
        "units": {"type": "object", "additionalProperties": {"type": "string"}},
        "config": {"$ref": "#/components/schemas/SimulationConfig"},
        "spring_constant": {"type": "number", "description": "[N/m]"},
        "calibration_factor": {"type": "number", "description": "[-]"},
        "n_samples": {"type": "integer"},
        "wall_time": {"type": "number", "description": "[s]"}}}


ERROR = {"title": "Error", "type": "object", "required": ["error"], "properties": {"error": {
    "type": "object", "required": ["type", "message", "field"], "properties": {
        "type": {"type": "string", "description": "invalid_value, invalid_request, too_large, storage_full, forbidden, ..."},
        "message": {"type": "string", "description": "one readable line"},
        "field": {"type": ["string", "null"], "description": "the value refused, as the request spells it"}}}}}


def _json_body(schema_ref: str) -> dict[str, Any]:
    return {"content": {"application/json": {"schema": {"$ref": f"#/components/schemas/{schema_ref}"}}}}


def build(app) -> dict[str, Any]:
    """The application's OpenAPI document with the declared models filled in (cached on the app)."""
    from fastapi.openapi.utils import get_openapi

    if app.openapi_schema is not None:
        return app.openapi_schema
    doc = get_openapi(title=app.title, version=app.version, description=app.description, routes=app.routes)
    schemas = doc.setdefault("components", {}).setdefault("schemas", {})
    schemas["SimulationConfig"] = config_schema()
    schemas.update(_analysis_schemas())
    schemas["SimulateResponse"] = _simulate_response()
    schemas["Error"] = ERROR
    paths = doc.get("paths", {})
    for url in ("/api/simulate", "/api/simulate/raw"):
        op = paths.get(url, {}).get("post")
        if op is not None:
            op["requestBody"] = _json_body("SimulationConfig")
    sim = paths.get("/api/simulate", {}).get("post")
    if sim is not None:
        sim.setdefault("responses", {})["200"] = {"description": "one approach-retract cycle",
                                                  **_json_body("SimulateResponse")}
    ana = paths.get("/api/analyze", {}).get("post")
    if ana is not None:
        ana.setdefault("responses", {})["200"] = {
            "description": "results (one AnalysisResult per curve), failed files, the ids to re-run with",
            "content": {"application/json": {"schema": {"type": "object", "properties": {
                "results": {"type": "array", "items": {"$ref": "#/components/schemas/AnalysisResult"}},
                "failed": {"type": "array", "items": {"type": "object"}},
                "files": {"type": "array", "items": {"type": "object"}},
                "wall_time": {"type": "number", "description": "[s]"}}}}}}
        ana["responses"]["413"] = {"description": "too_large: the body is over --max-upload; storage_full: the "
                                          "session's (or server's) stored uploads and job results would pass "
                                          "--session-storage (--server-storage): delete files or jobs or start a "
                                          "new session",
                                   **_json_body("Error")}
    for job_path in ("/api/fit", "/api/sweep"):    # a job whose results would not fit: the same 413
        op = paths.get(job_path, {}).get("post")
        if op is not None:
            op.setdefault("responses", {})["413"] = {
                "description": "storage_full: its results (at most) would take the session's (or server's) "
                               "stored uploads and job results past --session-storage (--server-storage)",
                **_json_body("Error")}
        form = ana.get("requestBody", {}).get("content", {}).get("multipart/form-data", {}).get("schema", {})
        ref = form.get("$ref", "").rsplit("/", 1)[-1]
        body = schemas.get(ref, {}).get("properties", {})
        for item, target in (("probe", "ProbeCalibration"), ("option", "AnalysisOptions")):
            if item in body:
                body[item]["x-names"] = {"$ref": f"#/components/schemas/{target}"}
        from .._fields import ANALYSIS_CHOICES

        for item, choice in ANALYSIS_CHOICES.items():    # the words --channel takes, from one declaration
            if item in body:
                body[item].update(enum=list(choice.choices), default=choice.default)
    fit = schemas.get("FitRequest", {}).get("properties", {})
    if "truth" in fit:
        fit["truth"] = {"$ref": "#/components/schemas/SimulationConfig",
                        "description": "model configuration, flat names, SI (fixed values)"}
    for methods in paths.values():     # every refusal has one shape
        for op in methods.values():
            responses = op.setdefault("responses", {})
            responses["422"] = {"description": "a value refused (named in error.field)", **_json_body("Error")}
    schemas.pop("HTTPValidationError", None)
    schemas.pop("ValidationError", None)
    app.openapi_schema = doc
    return doc


def install(app) -> None:
    """Serve :func:`build`'s document at ``/openapi.json`` (built on first request, then cached)."""
    app.openapi = lambda: build(app)
