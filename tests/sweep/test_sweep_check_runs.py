"""A sweep none of whose runs is a valid simulation is refused before any work, on every face.

Each value can lie in its own field's range while no run is valid: ``--set start=1um`` with the
default turn at 20 nm (the drive would move the substrate the wrong way). Before, every run
failed one by one into errors.csv (found by the audit). A sweep with some valid runs goes on."""

from __future__ import annotations

import pytest

from afmforce.dynamics import SimulationConfig
from afmforce.errors import ParameterError
from afmforce.sweep import build_spec
from afmforce.sweep.simulation import check_runs, simulation_dimensions


def _spec(grid=(), sets=()):
    return build_spec(list(grid), [], list(sets), dimensions=simulation_dimensions())


def test_no_valid_run_is_refused_with_the_runs_own_error():
    spec = _spec(grid=["velocity=1e-7:1e-6:3"], sets=["start=1um"])
    with pytest.raises(ParameterError) as err:
        check_runs(spec)
    with pytest.raises(ParameterError) as direct:       # the configuration's own words
        SimulationConfig(start=1e-6, velocity=1e-7)
    assert "no run of this sweep is a valid simulation (3 of 3 checked" in str(err.value)
    assert str(direct.value) in str(err.value)


def test_a_sweep_with_one_valid_run_goes_on():
    check_runs(_spec(grid=["start=-20nm:1um:3"]))          # the first run is valid, the others not
    check_runs(_spec(grid=["velocity=1e-7:1e-6:3"]))


def test_the_cli_refuses_it_in_one_line_and_writes_nothing(tmp_path, capsys):
    from afmforce.cli.main import main

    out = tmp_path / "out"
    code = main(["sweep", "--grid", "velocity=1e-7:1e-6:2", "--set", "start=1um", "--serial", "--out", str(out)])
    err = capsys.readouterr().err
    assert code != 0 and err.startswith("error: no run of this sweep is a valid simulation")
    assert err.strip().count("\n") == 0 and "Traceback" not in err
    assert not out.exists()


def test_the_web_answers_422_naming_the_settings():
    pytest.importorskip("fastapi")
    from afmforce.web.validate import FieldError, sweep_spec

    with pytest.raises(FieldError) as err:
        sweep_spec(["velocity=1e-7:1e-6:2"], [], ["start=1um"])
    assert err.value.field == "sets[0]" and "no run of this sweep is a valid simulation" in str(err.value)


@pytest.mark.parametrize("grid, ranges, sets, field, words", [
    (["start=1um:2um:2"], [], [], "grid[0]", "change the grid of start"),
    (["velocity=1e-7:1e-6:2"], ["start=1um:2um"], [], "ranges[0]", "change the range of start"),
    (["velocity=1e-7:1e-6:2"], [], ["start=1um"], "sets[0]", "change the setting start"),
    # each alone valid (start 0-1 nm below the default turn, turn above the default start), together never
    (["start=0nm,1nm"], ["turn=-10nm:-5nm"], [], "grid[0], ranges[0]", "change the grid of start or the range of turn"),
])
def test_the_web_names_the_fields_that_cause_it(grid, ranges, sets, field, words):
    """Before, the web named ``sets`` whatever made every run invalid (the grid or the ranges too)."""
    pytest.importorskip("fastapi")
    from afmforce.web.validate import FieldError, sweep_spec

    with pytest.raises(FieldError) as err:
        sweep_spec(grid, ranges, sets, **({"sample": "random", "n": 2} if ranges else {}))
    assert err.value.field == field
    assert str(err.value).startswith("no run of this sweep is a valid simulation") and str(err.value).endswith(words)
