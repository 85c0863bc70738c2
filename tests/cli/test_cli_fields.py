"""Field specs (afmforce._fields) and what the command line derives from them."""

from __future__ import annotations

import dataclasses
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from afmforce import __version__
from afmforce._fields import QUANTITIES, FieldSpec, ranges_markdown, show, spec_of
from afmforce.cli.main import COMMANDS, build_parser, main
from afmforce.errors import ParameterError

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("value, unit, display, text", [
    (1e-8, "kg", "ug", "10 ug"),
    (1e-7, "m/s", "um/s", "0.1 um/s"),
    (math.radians(-15), "rad", "deg", "-15 deg"),
    (200e-6, "m", "", "200 um"),
    (0.35e-9, "m", "", "0.35 nm"),
    (1e-10, "kg", "", "100 ng"),
    (10e3, "Hz", "", "10 kHz"),
    (45e-9, "m/V", "", "45 nm/V"),
    (5e-19, "J", "", "5e-19 J"),
    (2_000_000, "", "", "2000000"),
])
def test_show_in_the_users_units(value, unit, display, text):
    assert show(value, unit, display) == text


def test_check_bounds_open_and_closed():
    spec = FieldSpec("length", "m", "effective radius R", 0.0, 1e-3, lo_open=True)
    assert spec.range_text() == "(0, 1 mm]"
    assert spec.check(1e-3, "radius") == 1e-3  # closed upper bound
    for bad in (0.0, -5e-9, 1.1e-3, math.nan, math.inf):
        with pytest.raises(ParameterError, match=r"radius.* must lie in \(0, 1 mm\]"):
            spec.check(bad, "radius", "--radius")
    assert spec.check(None, "radius") is None  # unset optional values pass


def test_every_quantity_has_a_consistent_spec():
    from afmforce.units import DIMENSIONS

    for name, s in QUANTITIES.items():
        assert s.dimension in DIMENSIONS or s.dimension == "integer", name
        if s.dimension in DIMENSIONS:
            assert DIMENSIONS[s.dimension][0].replace("**", "^").replace("*", " ") in (s.unit, s.unit.replace("/(s N^2)", "/s/N^2")), name
        assert s.lo is None or s.hi is None or s.lo < s.hi, name
        assert s.help and s.help == s.help.strip(), name


def test_simulation_config_fields_carry_the_specs():
    # every numeric field of every part of SimulationConfig carries its vocabulary spec
    from afmforce.dynamics.config import FLAT, PARTS

    classes = [c for kind in PARTS.values() for c in (kind if isinstance(kind, tuple) else (kind,))]
    carried = {f.name: spec_of(f) for c in classes for f in dataclasses.fields(c) if spec_of(f) is not None}
    assert set(carried) == set(FLAT) - {"model", "friction", "ringing", "sampling", "geometry", "double_layer"}
    for name, spec in carried.items():
        assert spec is QUANTITIES[name] is FLAT[name].spec
        default = FLAT[name].default
        assert default is None or spec.contains(default), f"the default of {name} is out of its own range"


def test_simulate_flags_are_the_config_fields():
    # every quantity flag of `simulate` sets a SimulationConfig field (flat name) of the same spec
    from afmforce.dynamics.config import FLAT

    fields = {name: where.field for name, where in FLAT.items() if where.field is not None}
    parser = build_parser("simulate")
    sim = parser._subparsers._group_actions[0].choices["simulate"]
    flags = [a for a in sim._actions if hasattr(a.type, "spec")]
    # every numeric field but contact_separation, jump_factor, spike_window (28); + 2 lever quality
    # factors (issue 23) + 9 liquid ones (issue 25) + the surface force laws' parameters (issue 31)
    from afmforce.surface_laws import PARAMETERS as LAW_PARAMETERS
    assert len(flags) == 28 + 2 + 9 + len(LAW_PARAMETERS)
    for action in flags:
        assert action.dest in fields, action.option_strings
        assert spec_of(fields[action.dest]) is QUANTITIES[action.dest] is action.type.spec


def test_instrument_components_share_the_meta_helper():
    from afmforce.instrument.config import PARAMETERS
    from afmforce.instrument.instrument import COMPONENTS

    for cls in COMPONENTS.values():
        for f in dataclasses.fields(cls):
            assert isinstance(spec_of(f), FieldSpec), f"{cls.__name__}.{f.name}"
    assert PARAMETERS["photodiode.sensitivity"].unit == "m/V"


def test_docs_ranges_table_is_the_registry():
    text = (ROOT / "docs" / "ranges.md").read_text()
    assert ranges_markdown() in text, "docs/ranges.md is stale: regenerate it from afmforce._fields.ranges_markdown()"


@pytest.mark.parametrize("command, shown", [
    ("statics", ["default -15 deg", "default 200 um", "range [-89 deg, 89 deg]"]),
    ("diagnose", ["default 10 ug", "default 10 um/s", "default 0.35 nm"]),
    ("simulate", ["default 0.1 um/s", "default 10 ug", "default -15 deg", "default 10 kHz", "viscous: Fy"]),
])
def test_help_shows_defaults_in_the_users_units(capsys, command, shown):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    out = " ".join(capsys.readouterr().out.split())
    for text in shown:
        assert text in out
    assert "1e-08 kg" not in out and "np.float64" not in out


def test_version(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"afmforce {__version__}"


def test_commands_table_help_is_the_modules_help():
    full = build_parser()._subparsers._group_actions[0]
    helps = {a.dest: a.help for a in full._choices_actions}
    assert list(helps) == list(COMMANDS)
    for name, (_, help_) in COMMANDS.items():
        assert helps[name] == help_, f"COMMANDS[{name!r}] and cli/{name}.py disagree on the help"


_PROBE = """
import sys
from afmforce.cli.main import build_parser, main
{body}
heavy = sorted(m for m in ("numpy", "numba", "dask", "matplotlib", "pandas", "scipy", "afmforce.dynamics",
                           "afmforce.analysis", "afmforce.analysis.pipeline") if m in sys.modules)
print(heavy)
"""


def _modules_after(body: str) -> list[str]:
    out = subprocess.run([sys.executable, "-c", _PROBE.format(body=body)], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1].replace("'", '"'))


def test_top_level_help_loads_nothing_heavy():
    # `afmforce --help` (and --version) answer without numpy: the command modules are not imported
    assert _modules_after("build_parser('').format_help()") == []


@pytest.mark.parametrize("command", list(COMMANDS))
def test_registering_a_command_loads_no_numba_dask_matplotlib_dynamics(command):
    heavy = _modules_after(f"build_parser({command!r})")
    assert not set(heavy) & {"numba", "dask", "matplotlib", "afmforce.dynamics", "afmforce.analysis.pipeline"}, heavy


def test_sweep_lists_parameters_in_the_users_units(capsys):
    from afmforce.sweep.simulation import parameter_units, simulation_dimensions

    assert main(["sweep", "--list-parameters"]) == 0
    out = capsys.readouterr().out
    assert "10 ug" in out and "-15 deg" in out and "0.1 um/s" in out and "[-89 deg, 89 deg]" in out
    # the sweep's dimensions and units are the field metadata
    dims = simulation_dimensions()
    assert dims["velocity"] == "velocity" and dims["model"] is None and dims["max_steps"] == "dimensionless"
    assert parameter_units(["B", "zeta", "theta0"]) == {"B": "N m^2", "zeta": "kg/(s N^2)", "theta0": "rad"}


def test_probe_dataclasses_carry_the_specs():
    from afmforce.cantilever import InclinedCantilever, SimpleSpring

    for cls in (InclinedCantilever, SimpleSpring):
        for f in dataclasses.fields(cls):
            assert spec_of(f) is QUANTITIES[f.name]
