"""Every declared option reads the same on every face (faces sweep, 2026-11-29): the tests walk the
declarations, so an option added to one of them cannot drift on another.

* each command-line flag of a quantity (every command, sub-commands included): its ``--help`` shows the
  declared range, the quantity is one of :data:`afmforce._fields.QUANTITIES` and docs/ranges.md lists it
  with the same range;
* each web control of the same name (``GET /api/schema``: the simulation, the step options, the probe):
  the same range as the flag;
* each settings-file key: a sweep TOML's parameters are the simulation's flat names (the web's simulation
  controls, ``sweep --list-parameters``); an instrument TOML's ``[component] key`` has its flag
  ``--component-key``; a calibration JSON's probe keys are quantities with the same unit.

Was: ``calibrate virtual --temperature`` defaulted to a literal 295.0 (now the constant every calibration
reads), and ``analyze --channel`` had no web face (tests/web/test_web_channel_field.py)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from afmforce._fields import QUANTITIES
from afmforce.cli.main import build_parser

DOCS = (Path(__file__).parents[2] / "docs" / "ranges.md").read_text()


def _flags():
    """(command, action, spec) for every flag whose type carries a FieldSpec, in every (sub-)command."""
    out = []

    def walk(name, parser):
        for a in parser._actions:
            if isinstance(a, argparse._SubParsersAction):
                for sub, sp in a.choices.items():
                    walk(f"{name} {sub}".strip(), sp)
            spec = getattr(a.type, "spec", None)
            if spec is not None:
                out.append((name, a, spec))

    walk("", build_parser())
    return out


FLAGS = _flags()


def _quantity(spec) -> str | None:
    return next((k for k, s in QUANTITIES.items() if s == spec), None)


def test_the_walk_sees_the_flags():
    commands = {c.split()[0] for c, _, _ in FLAGS}
    assert {"analyze", "simulate", "fit", "statics", "diagnose", "calibrate", "plan"} <= commands
    assert len(FLAGS) > 100


@pytest.mark.parametrize("command,action,spec", FLAGS, ids=[f"{c} {a.option_strings[-1]}" for c, a, _ in FLAGS])
def test_every_quantity_flag_shows_its_declared_range_and_the_docs_list_it(command, action, spec):
    help_text = (action.help or "") + (action.lazy_help() if getattr(action, "lazy_help", None) else "")
    if spec.bounded:
        assert f"range {spec.range_text()}" in help_text, (command, action.option_strings, help_text)
    if spec.unit:                                   # the SI unit a plain number is read in
        assert f"[{spec.unit}]" in help_text, (command, action.option_strings, help_text)
    name = _quantity(spec)
    assert name is not None, f"{command} {action.option_strings[-1]}: a range declared outside QUANTITIES"
    row = re.search(rf"^\| `{re.escape(name)}` \| .* \| (.*) \|$", DOCS, re.M)
    assert row and row.group(1) == spec.range_text(), (name, row and row.group(0))


@pytest.fixture(scope="module")
def web_fields():
    pytest.importorskip("fastapi")
    from afmforce.web.schema import schema

    s = schema()
    out: dict[str, list] = {}
    for f in s["simulation"] + s["calibration"] + [f for fs in s["analysis"].values() for f in fs]:
        out.setdefault(f["name"], []).append(f)
    return out


@pytest.mark.parametrize("command,action,spec", FLAGS, ids=[f"{c} {a.option_strings[-1]}" for c, a, _ in FLAGS])
def test_a_web_control_of_the_same_quantity_has_the_flags_range(web_fields, command, action, spec):
    for f in web_fields.get(_quantity(spec) or "", []):
        if f.get("range") is not None and f.get("unit") == spec.unit:
            assert f["range"] == spec.range_text(), (command, action.option_strings[-1], f)
            assert f["unit"] == spec.unit and f["factor"] > 0
            assert (f["lo"], f["hi"]) == (spec.lo, spec.hi)


def test_sweep_file_keys_are_the_simulations_names_on_every_face(web_fields, capsys):
    from afmforce.cli.main import main
    from afmforce.dynamics.config import FLAT
    from afmforce.sweep.simulation import simulation_dimensions
    from afmforce.web.schema import simulation_fields

    keys = set(simulation_dimensions())
    assert keys == set(FLAT) == {f["name"] for f in simulation_fields()}
    assert main(["sweep", "--list-parameters"]) == 0
    listed = {line.split()[0] for line in capsys.readouterr().out.splitlines()[1:] if line.strip()}
    assert listed == keys


def test_instrument_file_keys_have_their_flags():
    from afmforce.instrument.config import PARAMETERS

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    flags = set(sub.choices["simulate"]._option_string_actions)
    for key, p in PARAMETERS.items():
        assert p.flag == "--" + key.replace(".", "-").replace("_", "-") and p.flag in flags, key


def test_calibration_file_keys_are_quantities_with_their_units():
    from afmforce.calibration.record import ANALYSIS_KEYS, PROBE_KEYS

    for key, unit in PROBE_KEYS.items():
        assert QUANTITIES[key].unit == unit, key
    assert set(ANALYSIS_KEYS) <= set(PROBE_KEYS)


def test_calibrate_reads_one_default_temperature():
    from afmforce.constants import DEFAULT_TEMPERATURE

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    calibrate = next(a for a in sub.choices["calibrate"]._actions if isinstance(a, argparse._SubParsersAction))
    virtual = calibrate.choices["virtual"]._option_string_actions["--temperature"]
    assert virtual.default == DEFAULT_TEMPERATURE


# ---- analyze: every quantity flag is a web control of the analyse view, or declared CLI-only ------------
def _analyze_quantity_flags():
    """(flag, action, spec or None) of every ``analyze`` flag that reads a value with units."""
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    out = []
    for a in sub.choices["analyze"]._actions:
        spec = getattr(a.type, "spec", None)
        if spec is not None or getattr(a.type, "__qualname__", "").startswith("quantity."):
            out.append((a.option_strings[-1], a, spec))
    return out


ANALYZE_FLAGS = _analyze_quantity_flags()


def _web_control(dest: str):
    """The analyse view's control that ``analyze``'s flag ``dest`` sets: a probe field or a step's option."""
    from afmforce.cli._analyze_options import OPTION_FLAGS
    from afmforce.web.schema import analysis_options, calibration_fields

    probe = [f for f in calibration_fields() if f["via"] == "probe" and f["name"] == dest]
    if probe:
        return probe[0]
    if dest in OPTION_FLAGS:
        step, name = OPTION_FLAGS[dest]
        return next((f for f in analysis_options().get(step, []) if f["name"] == name), None)
    return None


def test_the_analyze_walk_sees_the_probe_geometry():
    flags = {f for f, _, _ in ANALYZE_FLAGS}
    assert {"--theta0", "--L0", "--L1", "--L2", "--spring-constant", "--file-timeout"} <= flags


@pytest.mark.parametrize("flag,action,spec", ANALYZE_FLAGS, ids=[f for f, _, _ in ANALYZE_FLAGS])
def test_every_analyze_quantity_flag_has_a_web_control_or_a_reason(web_fields, flag, action, spec):
    from afmforce._fields import ANALYZE_CLI_ONLY

    if action.dest in ANALYZE_CLI_ONLY:
        assert len(ANALYZE_CLI_ONLY[action.dest]) > 20, flag          # a reason, not a placeholder
        assert _web_control(action.dest) is None, f"{flag} has a web control: drop it from ANALYZE_CLI_ONLY"
        return
    control = _web_control(action.dest)
    assert control is not None, (f"analyze {flag} has no control in the web's analyse view: add one or list it in "
                                 "afmforce._fields.ANALYZE_CLI_ONLY with the reason")
    assert spec is not None, flag
    assert control["unit"] == spec.unit and control["range"] == spec.range_text(), (flag, control)
    assert (control["lo"], control["hi"]) == (spec.lo, spec.hi) and control["factor"] > 0


def test_the_cli_only_set_names_only_analyze_flags():
    from afmforce._fields import ANALYZE_CLI_ONLY

    assert set(ANALYZE_CLI_ONLY) <= {a.dest for _, a, _ in ANALYZE_FLAGS}


def test_every_probe_field_is_a_flag_and_a_control_of_one_declaration():
    """The API's ``probe=`` (ProbeCalibration) has a flag and a web control for each field, with the declared
    quantity's unit, range and shown unit (theta0 in deg, the beam's lengths in um as on the simulation view)."""
    import dataclasses

    from afmforce.analysis.options import ProbeCalibration
    from afmforce.web.schema import calibration_fields

    dests = {a.dest: spec for _, a, spec in ANALYZE_FLAGS}
    web = {f["name"]: f for f in calibration_fields() if f["via"] == "probe"}
    for f in dataclasses.fields(ProbeCalibration):
        spec = QUANTITIES[f.name]
        assert f.metadata["spec"] == spec and dests[f.name] == spec, f.name
        assert web[f.name]["range"] == spec.range_text() and web[f.name]["unit"] == spec.unit, f.name
    assert web["theta0"]["shown"] == "deg" and {web[n]["shown"] for n in ("L0", "L1", "L2")} == {"um"}


# ---- one room temperature: every kT default, every face ----------------------------------------------------
#: Literal temperature defaults that are not the room's, with the reason (module path -> function).
NOT_THE_ROOM = {
    ("analysis/synthetic.py", "tether_curve"): "a synthetic file's own recorded temperature (its metadata), off the "
                                               "room's so that the tests see the file's value read, not the default",
}


def test_every_temperature_default_in_the_source_is_a_declared_name():
    """No function of afmforce defaults a ``temperature`` to a number of its own: the room
    (``DEFAULT_TEMPERATURE``) or the tabulated water data's 25 C (``STANDARD_TEMPERATURE``), by name."""
    import ast

    root = Path(__file__).parents[2] / "src" / "afmforce"
    found = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        for node in ast.walk(tree):
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            args = node.args.args + node.args.kwonlyargs
            defaults = [None] * (len(node.args.args) - len(node.args.defaults)) + node.args.defaults + \
                node.args.kw_defaults
            for a, d in zip(args, defaults):
                if a.arg == "temperature" and isinstance(d, ast.Constant) and d.value is not None:
                    found.append((str(path.relative_to(root)), node.name, d.value))
    assert {(p, f) for p, f, _ in found} == set(NOT_THE_ROOM), found


def test_every_face_reads_the_one_room_temperature(web_fields):
    from afmforce.constants import DEFAULT_TEMPERATURE, PAPER_ROOM_TEMPERATURE
    from afmforce.surface_laws import LAWS

    assert abs(DEFAULT_TEMPERATURE - PAPER_ROOM_TEMPERATURE) < 1.0        # the paper's lab: 22.7 C (section 3)
    room = f"{DEFAULT_TEMPERATURE:g} K"
    temperature_flags = [(c, a) for c, a, _ in FLAGS if a.dest == "temperature"]
    assert {c for c, _ in temperature_flags} >= {"simulate", "fit", "plan", "calibrate thermal", "calibrate virtual"}
    for command, action in temperature_flags:      # the flag's help shows the room as its default
        help_text = (action.help or "") + (action.lazy_help() if getattr(action, "lazy_help", None) else "")
        assert action.default in (None, DEFAULT_TEMPERATURE) and room in help_text, (command, help_text)
    for law in LAWS.values():                       # the simulation's laws (capillary, steric)
        for p in law.parameters:
            if p.name == "temperature":
                assert p.default == DEFAULT_TEMPERATURE, law.name
    (web,) = [f for f in web_fields["temperature"] if f.get("part") == "surface"]
    assert web["default"] == DEFAULT_TEMPERATURE
    assert "default of every `temperature` not given or stored in a file" in DOCS and f": {room} (" in DOCS
