"""Simulation sweeps end to end: the runner, the CLI, Dask (issue 7, parts 1-2).

Reference numbers: spec section 7 (independent scipy Radau solves of the Fig 5
model): at 1 um/s, xi = 0.01 kg/s gives a minimum apparent deflection before
contact of -1.04 nm, a constant-compliance offset of 0.454 nm and pull-off at
z = -178.0 nm; xi = 0.1 kg/s gives -0.05 nm, 4.54 nm and -120.4 nm. The static
jump-in (R = 100 nm, k = 0.1387 N/m) is at h = 3.92 nm, deflection -1.96 nm.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("afmforce.dynamics")

from afmforce.cli.main import main  # noqa: E402
from afmforce.sweep import build_spec, run_sweep  # noqa: E402
from afmforce.sweep.simulation import simulate_run, simulation_dimensions  # noqa: E402

NM = 1e-9
SPEC7 = {  # xi [kg/s] at 1 um/s -> (min apparent deflection, hysteresis offset, pull-off z) [m]
    0.01: (-1.04 * NM, 0.454 * NM, -178.0 * NM),
    0.1: (-0.05 * NM, 4.54 * NM, -120.4 * NM),
}


def test_cli_sweep_matches_spec_section_7_and_resumes(tmp_path, capsys):
    argv = ["sweep", "--grid", "xi=0.01,0.1", "--grid", "velocity=1um/s,2um/s", "--serial",
            "--out", str(tmp_path), "--plot", "min_apparent_deflection"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "4 runs, 2 x 2 grid (xi, velocity)" in out and "min_apparent_deflection" in out
    folder = next(tmp_path.glob("sweep-*"))
    t = pd.read_parquet(folder / "results.parquet")
    assert t["error"].isna().all() and (t["solver.status"] == "success").all()
    for xi, (min_app, offset, pull_off) in SPEC7.items():
        row = t[(t["xi"] == xi) & np.isclose(t["velocity"], 1e-6)].iloc[0]
        assert row["min_apparent_deflection"] == pytest.approx(min_app, abs=0.01 * NM)
        assert row["hysteresis_offset"] == pytest.approx(offset, abs=0.01 * NM)
        assert row["pull_off.piezo_position"] == pytest.approx(pull_off, abs=0.5 * NM)
    assert t["static_jump_in_separation"].to_numpy() == pytest.approx(3.92 * NM, abs=0.005 * NM)
    assert t["static_jump_in_deflection"].to_numpy() == pytest.approx(-1.96 * NM, abs=0.005 * NM)
    np.testing.assert_allclose(t["attraction_ratio"], t["min_apparent_deflection"] / t["static_jump_in_deflection"])
    # faster driving hides more of the attraction (the paper's conclusion)
    for xi in SPEC7:
        slow, fast = t[t["xi"] == xi].sort_values("velocity")["attraction_error"]
        assert fast > slow > 0
    assert (folder / "results.nc").exists() and (folder / "min_apparent_deflection.png").stat().st_size > 1000
    assert main(argv) == 0  # the same command again: everything is in the store
    assert "all 4 chunks were already in the store" in capsys.readouterr().out


def test_simulation_sweep_on_dask_equals_serial(dask_client):
    spec = build_spec(["xi=0.001,0.01"], sets=["velocity=5um/s", "start=-20nm"],
                      dimensions=simulation_dimensions())
    serial = run_sweep(simulate_run, spec, executor="serial")
    dask = run_sweep(simulate_run, spec, executor=dask_client)
    cols = [c for c in serial.table.columns if c != "solver.wall_time"]
    pd.testing.assert_frame_equal(serial.table[cols], dask.table[cols])


def test_runs_that_fail_are_listed_with_their_parameters(tmp_path, capsys):
    # start above turn is refused by SimulationConfig: that run fails, the other completes
    argv = ["sweep", "--grid", "start=-20nm,30nm", "--set", "velocity=5um/s", "--serial", "--out", str(tmp_path)]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "1 of 2 runs failed" in err and "ParameterError" in err
    errors = pd.read_csv(next(tmp_path.glob("sweep-*")) / "errors.csv")
    assert list(errors["start"]) == pytest.approx([30e-9])


@pytest.mark.parametrize("argv, words", [
    (["--grid", "velocity=5nm:1nm:3"], "--grid velocity expects a speed, got 5nm"),
    (["--grid", "speed=1:2:3"], "unknown parameter 'speed'"),
    (["--grid", "xi=0.01,0.1", "--plot", "nothing"], "--plot nothing: no such numeric output"),
    (["--range", "xi=0.01:0.1"], "needs --n"),
    (["--grid", "xi=0.1", "--serial", "--workers", "2"], "--serial"),
])
def test_cli_bad_input_is_one_line_and_exit_2(argv, words, capsys, tmp_path):
    assert main(["sweep", *argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]
    assert not list(tmp_path.iterdir())  # nothing ran, nothing written


def _unbatched(**parameters):
    """simulate_run without its batch attribute: one simulate() per row."""
    return simulate_run(**parameters)


def test_batched_chunks_give_the_rows_of_separate_runs():
    """The chunk runner uses simulate_run.batch (simulate_many on threads): same table,
    a failing run (start above turn) recorded in its own row."""
    assert callable(simulate_run.batch) and simulate_run.batch_threads() >= 1
    spec = build_spec(["xi=0.001,0.01,0.1", "start=-20nm,30nm"], sets=["velocity=5um/s"],
                      dimensions=simulation_dimensions())
    batched = run_sweep(simulate_run, spec, executor="serial", chunk_size=6)
    single = run_sweep(_unbatched, spec, executor="serial", chunk_size=6)
    cols = [c for c in batched.table.columns if c != "solver.wall_time"]
    pd.testing.assert_frame_equal(batched.table[cols], single.table[cols])
    bad = batched.table[np.isclose(batched.table["start"], 30e-9)]
    assert len(bad) == 3 and bad["error"].str.startswith("ParameterError").all()
    assert batched.table[np.isclose(batched.table["start"], -20e-9)]["error"].isna().all()


def test_static_jump_in_is_solved_for_each_spring_and_surface():
    # the static solution is cached per (k, R, A, z0): a sweep over R must still get each R's own
    # value; checked against an independent root solve of Fs'(h) = k (spec section 2)
    from scipy.optimize import brentq

    from afmforce import forces
    from afmforce.dynamics import SimulationConfig

    spec = build_spec(["radius=100nm,220nm,50nm", "xi=0.01,0.1"], sets=["velocity=5um/s"],
                      dimensions=simulation_dimensions())
    t = run_sweep(simulate_run, spec, executor="serial").table
    assert t["error"].isna().all()
    for _, row in t.iterrows():
        cfg = SimulationConfig(radius=row["radius"], xi=row["xi"], velocity=5e-6)
        k, r, a, z0 = cfg.force_constant, cfg.radius, cfg.hamaker, cfg.z0
        steep = 3 ** (1 / 6) * z0
        h = brentq(lambda x: forces.vdw_force_gradient(x, r, a, z0) - k, steep, 1e-6, xtol=1e-18)
        assert row["static_jump_in_separation"] == pytest.approx(h, rel=1e-9)
        assert row["static_jump_in_deflection"] == pytest.approx(forces.vdw_force(h, r, a, z0) / k, rel=1e-9)
    assert len(set(t["static_jump_in_separation"].round(15))) == 3
