"""Issue 31 item 1: every declared quantity is refused by the records and the command line alike.

For each quantity of :data:`afmforce._fields.QUANTITIES` a value just outside its
declared range is given to every Python record that holds the quantity (the
simulation configuration and its parts, the analysis probe and step options,
the statics and diagnosis functions) and to every command-line flag declared
from it (found by walking the parsers, so a new flag is tested without an
edit here), and to ``sweep --set`` for the simulation's names. Every refusal
carries the same text: "is out of range: NAME, the HELP, must lie in RANGE". The web
(``afmforce serve``) is the third face: the simulation's names in ``/api/simulate``, the probe
fields and step options in ``/api/analyze``, each answered 422 with the same text, and its
OpenAPI document publishes the same ranges.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import pytest

from afmforce._fields import QUANTITIES, FieldSpec
from afmforce.cli.main import build_parser, main
from afmforce.errors import ParameterError

CURVE = str(Path(__file__).parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw")


def _outside(spec: FieldSpec, side: str) -> float | None:
    """A value outside the declared range above it (``hi``) or below it (``lo``); None: no bound there."""
    if side == "hi":
        return None if spec.hi is None else (spec.hi * 2 if spec.hi > 0 else spec.hi + 1.0)
    if spec.lo is None:
        return None
    return spec.lo if spec.lo_open else (spec.lo / 2 if spec.lo > 0 else spec.lo - abs(spec.lo) - 1.0)


def _tail(message: str) -> str:
    assert " is out of range: " in message, message
    return message.split(" is out of range: ", 1)[1]


def _expected(name: str) -> str:
    """The message's tail: ``NAME, the HELP, must lie in RANGE``."""
    spec = QUANTITIES[name]
    return f"{name}, the {spec.help}, must lie in {spec.range_text()}"


def _records(name: str, value: float) -> list:
    """Callables that build each Python record (or call each function) holding quantity ``name``."""
    import dataclasses

    from afmforce.analysis.options import OPTIONS, ProbeCalibration
    from afmforce.cantilever import InclinedCantilever
    from afmforce.diagnostics import diagnose
    from afmforce.dynamics.config import FLAT
    from afmforce.dynamics import SimulationConfig
    from afmforce.statics import static_analysis

    out = []
    if name in FLAT:
        out.append(lambda: SimulationConfig(model=FLAT[name].models[0], **{name: value}))
    if name in {f.name for f in dataclasses.fields(ProbeCalibration)}:
        out.append(lambda: ProbeCalibration(**{name: value}))
    for cls in OPTIONS.values():
        for f in dataclasses.fields(cls):
            spec = f.metadata.get("spec")
            if spec == QUANTITIES[name]:
                out.append(lambda cls=cls, f=f: cls(**{f.name: value}))
    cant = InclinedCantilever(200e-6, 20e-6, 5e-6, math.radians(-15), k0=0.13)
    statics = {"mu": ("constant", {"mu": value}), "lam": ("load", {"lam": value}),
               "gap_deflection": ("load", {"lam": 0.3, "deflection": value})}
    if name in statics:
        friction, kw = statics[name]
        out.append(lambda: static_analysis(cant, friction, **kw))
    if name in ("jump_window", "fringe_period"):
        from afmforce.fit import fit_dynamic

        out.append(lambda: fit_dynamic([], "beam", **{name: value}))
    if name in ("deflection_noise", "force_error"):
        from afmforce.fit.plan import plan_experiment

        out.append(lambda: plan_experiment("beam", **{"noise" if name == "deflection_noise" else name: value}))
    if name in ("deflection_noise", "slip_target"):
        from afmforce.fit.plan_slip import plan_slip

        out.append(lambda: plan_slip("spring", **{"noise" if name == "deflection_noise" else "target": value,
                                                  **({"target": 1e-9} if name == "deflection_noise" else {})}))
    calibration = _calibration_records(name, value)
    if calibration is not None:
        out.append(calibration)
    if name in ("resolution", "separation"):
        out.append(lambda: diagnose(spring_constant=0.2, mass=1e-8, radius=1e-7, velocity=1e-6,
                                    **{name: value}))
    return out


def _calibration_records(name: str, value: float):
    """The probe calibration's functions (issue 34) that take quantity ``name``, or None."""
    import numpy as np

    from afmforce.calibration.sader import general_constant, sader_rectangular
    from afmforce.calibration.thermal import fit_thermal

    f, p = np.linspace(1e3, 1e5, 50), np.ones(50)
    thermal = {"temperature": "temperature", "equipartition_correction": "correction", "lever_tilt": "tilt"}
    if name in thermal:
        return lambda: fit_thermal(f, p, **{thermal[name]: value})
    if name in ("frequency_min", "frequency_max"):
        return lambda: fit_thermal(f, p, f_range=(value, 1e5) if name == "frequency_min" else (1e3, value))
    if name in ("lever_length", "lever_width"):
        kw = {"length": 100e-6, "width": 30e-6, name.split("_")[1]: value}
        return lambda: sader_rectangular(kw["length"], kw["width"], 2e4, 50.0)
    if name == "density":
        return lambda: sader_rectangular(100e-6, 30e-6, 2e4, 50.0, density=value)
    reference = {"reference_spring_constant": 0, "reference_frequency": 1, "reference_quality_factor": 2}
    if name in reference:
        args = [0.1, 2e4, 50.0]
        args[reference[name]] = value
        return lambda: general_constant(*args, exponent=0.5)
    if name == "sader_exponent":
        return lambda: general_constant(0.1, 2e4, 50.0, exponent=value)
    return None


def _flags() -> dict[str, list[tuple[str, str]]]:
    """Quantity name -> every (command, flag) whose value is declared by it."""
    parser = build_parser(None)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    found: dict[str, list] = {}

    def walk(command: str, p) -> None:      # sub-commands too (``calibrate thermal``)
        for action in p._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    walk(f"{command} {name}", child)
                continue
            spec = getattr(action.type, "spec", None)
            for name, q in QUANTITIES.items():
                if spec is q:
                    found.setdefault(name, []).append((command, action.option_strings[0]))

    for command, p in sub.choices.items():
        walk(command, p)
    return found


FLAGS = _flags()


@pytest.fixture(scope="module")
def web(tmp_path_factory):
    """A test client of the web application (fastapi is a dependency, httpx a test extra: never
    skipped, so the web face is always compared)."""
    from fastapi.testclient import TestClient

    from afmforce.web import Settings, create_app

    app = create_app(Settings(data=tmp_path_factory.mktemp("web"), spare_job=False))
    # no lifespan (no ``with``): its warm-up would compile the integrator in a thread, whose
    # first-run notice lands on the stderr of whichever CLI test runs then; every value here is
    # refused before any computation, which is the point
    yield TestClient(app, base_url="http://127.0.0.1")


def _web_requests(name: str, text: str) -> list[tuple[str, dict]]:
    """(url, request keyword arguments) of every web field declared by quantity ``name``."""
    import dataclasses

    from afmforce.analysis.options import OPTIONS, ProbeCalibration
    from afmforce.dynamics.config import FLAT

    out = []
    if name in FLAT and FLAT[name].spec is QUANTITIES[name]:
        models = FLAT[name].models
        out.append(("/api/simulate", {"json": {name: float(text), **({} if "beam" in models
                                                                      else {"model": models[0]})}}))
    if name in {f.name for f in dataclasses.fields(ProbeCalibration)}:
        out.append(("/api/analyze", {"data": {"example": "asylum-air", "probe": f"{name}={text}"}}))
    for step, cls in OPTIONS.items():
        for f in dataclasses.fields(cls):
            if f.metadata.get("spec") == QUANTITIES[name]:
                out.append(("/api/analyze", {"data": {"example": "asylum-air",
                                                      "option": f"{step}.{f.name}={text}"}}))
    return out


def _cli(capsys, argv) -> str:
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("error: "), (argv, err)
    return err


@pytest.mark.parametrize("side", ["hi", "lo"])
@pytest.mark.parametrize("name", list(QUANTITIES))
def test_python_and_cli_refuse_the_same_value_with_the_same_message(capsys, tmp_path, monkeypatch, web, name,
                                                                    side):
    monkeypatch.chdir(tmp_path)
    spec = QUANTITIES[name]
    value = _outside(spec, side)
    if value is None:
        assert spec.hi is None if side == "hi" else spec.lo is None
        return
    assert not spec.contains(value)
    messages = []
    records = _records(name, value)
    assert records, f"no Python record holds {name}: declare where it is used"
    for build in records:
        with pytest.raises(ParameterError) as info:
            build()
        messages.append(("python", str(info.value)))
    text = repr(int(value)) if spec.dimension == "integer" else repr(value)
    routes = [[*command.split(), *([CURVE] if command in ("analyze", "fit") else []), f"{flag}={text}"]
              for command, flag in FLAGS.get(name, [])]
    from afmforce.dynamics.config import FLAT

    if name in FLAT:
        routes.append(["sweep", "--grid", "friction=viscous,none", "--set", f"{name}={text}", "--out", "s"])
    assert routes, f"no command-line route sets {name}"
    for argv in routes:
        messages.append((" ".join(argv), _cli(capsys, argv)))
    for url, request in _web_requests(name, text):
        r = web.post(url, **request)
        assert r.status_code == 422, (url, request, r.status_code, r.text[:300])
        messages.append((f"{url} {request}", r.json()["error"]["message"]))
    for where, message in messages:   # the name (or the field that holds it), the meaning, the range
        assert _tail(message).endswith(f", the {spec.help}, must lie in {spec.range_text()}"), (where, message)
        assert _tail(message) == _tail(messages[0][1]), (where, message, messages[0])
    assert _tail(messages[0][1]) == _expected(name) or name == "compliance_separation"  # field contact_separation


def test_the_simulation_record_and_the_cli_give_the_issue_s_message(capsys):
    """``SimulationConfig(hamaker=5e-17)`` and ``simulate --hamaker 5e-17J``: the same ParameterError text."""
    from afmforce.dynamics import SimulationConfig

    with pytest.raises(ParameterError) as info:
        SimulationConfig(hamaker=5e-17)
    assert str(info.value) == ("hamaker = 5e-17 J is out of range: hamaker, the Hamaker constant A, must lie "
                               "in [1e-22 J, 1e-17 J]")
    assert _cli(capsys, ["simulate", "--hamaker", "5e-17J"]) == (
        "error: --hamaker 5e-17J is out of range: hamaker, the Hamaker constant A, must lie in [1e-22 J, 1e-17 J]")


def test_cross_field_rules_live_in_the_records():
    """L1 < L0 (Fig 2) in the beam probe and the analysis probe, not only on the command line."""
    from afmforce.analysis.options import ProbeCalibration
    from afmforce.dynamics import BeamProbe, SimulationConfig

    for build in (lambda: BeamProbe(L0=100e-6, L1=200e-6), lambda: SimulationConfig(L0=100e-6, L1=200e-6),
                  lambda: ProbeCalibration(L0=100e-6, L1=200e-6)):
        with pytest.raises(ParameterError, match=r"^L1 200 um is not shorter than the flexible beam L0 100 um"):
            build()
    with pytest.raises(ParameterError, match="L2 .* is not shorter than the flexible beam L0"):
        BeamProbe(L0=100e-6, L1=10e-6, L2=100e-6)
    assert BeamProbe(L0=100e-6, L1=99e-6).L1 == 99e-6


def test_the_sample_cap_is_one_constant_for_every_face(capsys):
    """``afmforce.limits.MAX_SAMPLES``: the record refuses the cycle, the CLI uses the same cap."""
    from afmforce import limits
    from afmforce.cli import _validate
    from afmforce.dynamics import SimulationConfig

    assert _validate.MAX_SAMPLES is limits.MAX_SAMPLES == 10_000_000
    # start -40 nm, turn 20 nm, end -230 nm at 1 nm/s: 310 s of drive; 40 kHz gives 1.24e7 samples
    n = limits.simulation_samples(-40e-9, 20e-9, -230e-9, 1e-9, None, 0.0, 40e3)
    assert n == pytest.approx(310.0 * 40e3, rel=1e-12)
    with pytest.raises(ParameterError, match=r"about 1.24e\+07 samples .* more than the 1e\+07 a run may have"):
        SimulationConfig(velocity=1e-9, sample_rate=40e3)
    SimulationConfig(velocity=1e-9, sample_rate=30e3)      # 9.3e6 samples: allowed
    err = _cli(capsys, ["simulate", "--velocity", "1nm/s", "--sample-rate", "40kHz"])
    assert "about 1.24e+07 samples" in err and "more than the 1e+07" in err


def test_the_fit_searches_inside_the_declared_ranges():
    """The fit's bounds come from the declarations: the issue's hamaker searched up to 1e-16 J."""
    from afmforce.fit.params import PARAMETERS

    for p in PARAMETERS.values():
        spec = QUANTITIES[p.name]
        assert p.unit == spec.unit
        for bound, declared in ((p.lower, spec.lo), (p.upper, spec.hi)):
            assert spec.contains(bound) or bound == declared, (p.name, bound, spec.range_text())
    assert PARAMETERS["hamaker"].upper == QUANTITIES["hamaker"].hi == 1e-17
    assert PARAMETERS["lever_drag"].unit == "kg/s"


def test_the_openapi_document_publishes_the_declared_ranges(web):
    """``/openapi.json``: every simulation name, probe field and step option typed, with the
    declared unit and range; every result field with its unit; refusals in one shape."""
    import dataclasses

    from afmforce.analysis.options import OPTIONS, ProbeCalibration
    from afmforce.analysis.result import AnalysisResult
    from afmforce.dynamics.config import FLAT

    doc = web.get("/openapi.json").json()
    schemas = doc["components"]["schemas"]

    def check(prop, spec):
        number = prop["anyOf"][0]
        lo = number.get("exclusiveMinimum" if spec.lo_open else "minimum")
        hi = number.get("exclusiveMaximum" if spec.hi_open else "maximum")
        assert (lo, hi) == (spec.lo, spec.hi) and prop["x-unit"] == spec.unit, (prop, spec)
        assert spec.range_text() in prop["description"]

    config = schemas["SimulationConfig"]["properties"]
    assert set(config) == set(FLAT)
    for name, where in FLAT.items():
        if where.spec is not None:
            check(config[name], where.spec)
        else:
            assert config[name]["enum"], name
    probe = schemas["ProbeCalibration"]["properties"]
    for f in dataclasses.fields(ProbeCalibration):
        spec = f.metadata.get("spec")
        if spec is not None and spec.dimension not in ("choice", "flag", "text"):
            check(probe[f.name], spec)
    options = schemas["AnalysisOptions"]["properties"]
    for step, cls in OPTIONS.items():
        for f in dataclasses.fields(cls):
            spec = f.metadata.get("spec")
            if spec is not None and spec.dimension not in ("choice", "flag", "text"):
                check(options[f"{step}.{f.name}"], spec)
    result = schemas["AnalysisResult"]["properties"]
    assert {k: v["x-unit"] for k, v in result.items()} == dict(AnalysisResult.UNITS)
    for url in ("/api/simulate", "/api/simulate/raw"):
        assert doc["paths"][url]["post"]["requestBody"]["content"]["application/json"]["schema"] == {
            "$ref": "#/components/schemas/SimulationConfig"}
    assert schemas["FitRequest"]["properties"]["truth"]["$ref"] == "#/components/schemas/SimulationConfig"
    for methods in doc["paths"].values():
        for op in methods.values():
            assert op["responses"]["422"]["content"]["application/json"]["schema"] == {
                "$ref": "#/components/schemas/Error"}
    assert "HTTPValidationError" not in schemas
