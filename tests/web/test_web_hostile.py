"""Hostile requests, generated from the declarations: every numeric field of every endpoint.

For each field the server takes a number for -- every flat name of a simulation configuration
(:data:`afmforce.dynamics.config.FLAT`, in ``/api/simulate``, ``/api/simulate/raw``, a fit's
``truth`` and a sweep's ``sets``), every numeric field of the request models (``FitRequest``,
``SweepRequest``, the query and form parameters), every probe field
(:class:`~afmforce.analysis.options.ProbeCalibration`) and every numeric option of the analysis
steps (:data:`afmforce.analysis.options.OPTIONS`) -- the values a careless or hostile client
sends: text, ``NaN``/``Infinity`` as JSON literals (Python's and browsers' JSON may send them) and
as strings, huge numbers, a 400-digit integer, numbers below the range, lists, objects and
booleans. Each must be answered ``422 {"error": {"type", "message", "field"}}`` naming the
field, never 500; the server must stay healthy and start no process.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections import Counter

import pytest

fastapi = pytest.importorskip("fastapi")
psutil = pytest.importorskip("psutil")

from afmforce.analysis.options import OPTIONS, ProbeCalibration  # noqa: E402
from afmforce.dynamics.config import FLAT  # noqa: E402
from afmforce.web.routes_fit import FitRequest  # noqa: E402
from afmforce.web.routes_sweep import SweepRequest  # noqa: E402

#: JSON literals sent in the raw body in place of a value (``json.dumps`` cannot write the first three).
LITERALS = ["NaN", "Infinity", "-Infinity", "1e300", "-1e300", "1" + "0" * 400, "-1", '"abc"', '"NaN"',
            '"inf"', '"1e999"', '"-1e300 m"', "[1]", '{"v": 1}', "true", "false", '"' + "9" * 100 + '"']
#: Texts sent where the value is a text (form fields, NAME=VALUE items).
TEXTS = ["abc", "nan", "NaN", "inf", "-inf", "1e300", "-1e300", "1" + "0" * 400, "-1", "[1]", "1 parsec/fortnight",
         "2.5e", ""]
SEEN: Counter = Counter()
STATUS: Counter = Counter()


def _python(literal: str):
    """The value a literal stands for (Python's JSON reads NaN and Infinity)."""
    return json.loads(literal)


def _valid_number(spec, value) -> bool:
    """Whether ``value`` would be a valid number for ``spec`` (then it is not hostile: skipped)."""
    from afmforce.units import parse_typed

    if isinstance(value, bool) or isinstance(value, (list, dict)) or value is None:
        return False
    try:
        v = float(parse_typed(value, spec.dimension, "x")) if isinstance(value, str) else float(value)
    except Exception:
        return False
    if spec.dimension == "integer" and not (math.isfinite(v) and v.is_integer()):
        return False
    return spec.contains(v)


@pytest.fixture(scope="module")
def hostile(tmp_path_factory, workers):
    from fastapi.testclient import TestClient

    from afmforce.web import Settings, create_app

    app = create_app(Settings(data=tmp_path_factory.mktemp("hostile"), spare_job=False))
    with TestClient(app, base_url="http://127.0.0.1") as client:
        before = workers()
        yield client, before
        assert client.get("/api/health").json()["status"] == "ok"
        assert workers() == before
        print(f"\nhostile requests: {sum(SEEN.values())} sent, answers {dict(STATUS)}; by endpoint {dict(SEEN)}")


def _check(client, before, method, url, *, field, body=None, data=None, files=None):
    if body is not None:
        r = client.request(method, url, content=body.encode(), headers={"content-type": "application/json"})
    else:
        r = client.request(method, url, data=data, files=files)
    SEEN[url.split("?")[0]] += 1
    STATUS[r.status_code] += 1
    sent = body if body is not None else (data or url)
    assert r.status_code == 422, (sent, r.status_code, r.text[:300])
    err = r.json()["error"]
    assert set(err) == {"type", "message", "field"}, err
    assert err["type"] in ("invalid_value", "invalid_request") and err["message"], err
    if field is not None:
        assert err["field"] == field, (sent, err)
    assert "Traceback" not in err["message"] and "detail" not in r.json()


def _body(fields: dict, name_path: tuple, literal: str) -> str:
    """``fields`` as JSON with the value at ``name_path`` replaced by the raw ``literal``."""
    mark = "__HOSTILE__"
    d = json.loads(json.dumps(fields))
    target = d
    for key in name_path[:-1]:
        target = target[key]
    target[name_path[-1]] = mark
    return json.dumps(d).replace(json.dumps(mark), literal)


NUMERIC_FLAT = [n for n, w in FLAT.items() if w.spec is not None]


def _model_of(name: str) -> dict:
    models = FLAT[name].models
    return {} if "beam" in models else {"model": models[0]}


@pytest.mark.parametrize("url", ["/api/simulate?max_points=100", "/api/simulate/raw"])
@pytest.mark.parametrize("name", NUMERIC_FLAT)
def test_every_simulation_field_refuses_hostile_values(hostile, url, name):
    client, before = hostile
    spec = FLAT[name].spec
    for literal in LITERALS:
        if _valid_number(spec, _python(literal)):
            continue
        _check(client, before, "POST", url, field=name, body=_body({**_model_of(name), name: 0}, (name,), literal))


@pytest.mark.parametrize("name", NUMERIC_FLAT)
def test_every_fit_truth_field_refuses_hostile_values(hostile, name):
    client, before = hostile
    spec = FLAT[name].spec
    base = {"velocities": [1e-6, 2e-6], "profile": False, "compare": False,
            "truth": {**_model_of(name), name: 0}}
    for literal in LITERALS:
        if _valid_number(spec, _python(literal)):
            continue
        _check(client, before, "POST", "/api/fit", field=f"truth.{name}", body=_body(base, ("truth", name), literal))


def _numeric_fields(model) -> list[str]:
    """The fields of a request model whose values are numbers (int or float, optional or not)."""
    out = []
    for name, info in model.model_fields.items():
        text = str(info.annotation)
        if "int" in text or "float" in text:
            out.append(name)
    return out


@pytest.mark.parametrize("model, url, base", [
    (FitRequest, "/api/fit", {"velocities": [1e-6, 2e-6], "profile": False, "compare": False}),
    (SweepRequest, "/api/sweep", {"grid": ["xi=0.01,0.1"], "executor": "serial"}),
])
def test_every_numeric_field_of_the_request_models_refuses_hostile_values(hostile, model, url, base):
    client, before = hostile
    fields = _numeric_fields(model)
    assert fields, model            # the generation found the declared numbers
    for name in fields:
        info = model.model_fields[name]
        lo = next((m.ge for m in info.metadata if getattr(m, "ge", None) is not None), None)
        for literal in LITERALS + ["2.5"]:
            value = _python(literal)
            if (isinstance(value, int) and not isinstance(value, bool) and lo is not None and value >= lo
                    and all(getattr(m, "le", None) is None or value <= m.le for m in info.metadata)):
                continue            # a valid whole number in the declared range
            _check(client, before, "POST", url, field=name, body=_body({**base, name: 0}, (name,), literal))


def test_every_fit_velocity_refuses_hostile_values(hostile):
    client, before = hostile
    from afmforce._fields import QUANTITIES

    for literal in LITERALS:
        if _valid_number(QUANTITIES["velocity"], _python(literal)):
            continue
        body = _body({"velocities": [0, 1e-6], "profile": False, "compare": False}, ("velocities", 0), literal)
        _check(client, before, "POST", "/api/fit", field="velocities[0]", body=body)


@pytest.mark.parametrize("name", NUMERIC_FLAT)
def test_every_sweep_setting_refuses_hostile_values(hostile, name):
    from dataclasses import replace

    from afmforce.sweep.simulation import simulation_dimensions

    client, before = hostile
    spec = FLAT[name].spec     # read as the sweep's parser reads it (as afmforce sweep --set does)
    spec = replace(spec, dimension=simulation_dimensions()[name]) if spec.dimension == "integer" else spec
    for text in TEXTS:
        if text == "" or _valid_number(spec, text):
            continue
        axis = "hamaker=1e-19,2e-19" if name == "xi" else "xi=0.01,0.1"
        body = json.dumps({"grid": [axis], "sets": [f"{name}={text}"] + (
            [f"model={_model_of(name)['model']}"] if _model_of(name) else []), "executor": "serial"})
        _check(client, before, "POST", "/api/sweep", field="sets[0]", body=body)


@pytest.mark.parametrize("param, url", [("max_points", "/api/simulate"), ("seed", "/api/simulate/raw")])
def test_query_numbers_refuse_hostile_values(hostile, param, url):
    client, before = hostile
    lo, hi = {"max_points": (10, 20_000), "seed": (0, 2**32 - 1)}[param]
    for text in TEXTS + ["2.5", "99999999", str(2**32)]:
        if text == "" or (text.lstrip("-").isdigit() and lo <= int(text) <= hi):
            continue
        _check(client, before, "POST", f"{url}?{param}={text}", field=param, body="{}")


def _probe_fields():
    return [f for f in dataclasses.fields(ProbeCalibration) if f.metadata.get("spec") is not None]


@pytest.mark.parametrize("name", [f.name for f in _probe_fields()])
def test_every_probe_field_of_the_analysis_refuses_hostile_values(hostile, name):
    client, before = hostile
    spec = next(f for f in _probe_fields() if f.name == name).metadata["spec"]
    for text in TEXTS:
        if _valid_number(spec, text):
            continue
        _check(client, before, "POST", "/api/analyze", field=f"probe.{name}",
               data={"example": "asylum-air", "probe": f"{name}={text}"})


NUMERIC_OPTIONS = [(step, f.name) for step, cls in OPTIONS.items() for f in dataclasses.fields(cls)
                   if f.metadata.get("spec") is not None
                   and f.metadata["spec"].dimension not in ("choice", "flag", "text")]


@pytest.mark.parametrize("step, name", NUMERIC_OPTIONS)
def test_every_numeric_analysis_option_refuses_hostile_values(hostile, step, name):
    client, before = hostile
    spec = next(f for f in dataclasses.fields(OPTIONS[step]) if f.name == name).metadata["spec"]
    for text in TEXTS:
        if text == "" or _valid_number(spec, text):
            continue
        _check(client, before, "POST", "/api/analyze", field=f"option.{step}.{name}",
               data={"example": "asylum-air", "option": f"{step}.{name}={text}"})


def test_analysis_max_points_refuses_hostile_values(hostile):
    client, before = hostile
    for text in TEXTS + ["2.5", "99", "20001"]:
        if text == "":
            continue
        _check(client, before, "POST", "/api/analyze", field="max_points",
               data={"example": "asylum-air", "max_points": text})


@pytest.mark.parametrize("body", ["NaN", "[1, 2]", '"abc"', "1e300", "{", "", "null"])
@pytest.mark.parametrize("url", ["/api/simulate", "/api/simulate/raw", "/api/fit", "/api/sweep"])
def test_bodies_that_are_not_objects(hostile, url, body):
    client, before = hostile
    if body in ("", "null") and url.startswith("/api/simulate"):
        return          # no body: the defaults, a valid request
    _check(client, before, "POST", url, field=None, body=body)


def _meta_keys():
    from afmforce._fields import QUANTITIES
    from afmforce.io._meta import METADATA

    return [k for k in METADATA if k in QUANTITIES]


@pytest.mark.parametrize("key", _meta_keys())
@pytest.mark.parametrize("url", ["/api/analyze", "/api/fit"])
def test_every_numeric_metadata_override_refuses_hostile_values(hostile, key, url):
    """``meta`` (KEY=VALUE, as --meta): each key of the shared vocabulary, hostile texts refused by
    field (a sensitivity of 1e300 was read and failed the curve with an OverflowError)."""
    from afmforce._fields import QUANTITIES

    client, before = hostile
    for text in TEXTS:
        if text == "" or _valid_number(QUANTITIES[key], text):
            continue
        if url == "/api/fit":
            body = json.dumps({"velocities": [1e-6, 2e-6], "meta": [f"{key}={text}"]})
            _check(client, before, "POST", url, field="meta[0]", body=body)
        else:
            _check(client, before, "POST", url, field="meta[0]", data={"example": "asylum-air", "meta": f"{key}={text}"})
