"""Issue 31 item 6: every size bounded and every output checked before any work.

As in test_cli_ranges, the work itself is replaced by a function that raises
WorkStarted: a case that gets past the checks fails with "unexpected WorkStarted"
instead of exit status 2 and the expected line.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce import limits
from afmforce.cli.main import main
from afmforce.errors import ParameterError

from test_cli_ranges import WorkStarted, _boom, refused  # noqa: F401

CURVE = str(Path(__file__).parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw")


@pytest.fixture
def no_work(monkeypatch):
    import afmforce.dynamics as dynamics
    import afmforce.fit as fit
    import afmforce.fit.plan as plan
    import afmforce.paper.reproduce as reproduce
    import afmforce.sweep as sweep

    monkeypatch.setattr(sweep, "run_sweep", _boom)
    monkeypatch.setattr(plan, "curve_information", _boom)
    monkeypatch.setattr(fit, "fit_dynamic", _boom)
    monkeypatch.setattr(dynamics, "simulate", _boom)
    monkeypatch.setattr(reproduce, "reproduce", _boom)


def started(capsys, argv) -> str:
    """Run ``argv``; assert that it got past every check (the work started)."""
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 1 and "unexpected WorkStarted" in err, err
    return err


def _speeds(n: int) -> str:
    return ",".join(f"{0.1 * (i + 1):.1f}um/s" for i in range(n))


@pytest.mark.parametrize("argv, fragments", [
    (["plan", "--curves", "1000000"], ["--curves: 1,000,000 curves in a design is more than the 20"]),
    (["plan", "--speeds", _speeds(200)], ["--speeds: 200 candidate speeds is more than the 40"]),
    (["plan", "--speeds", _speeds(40), "--curves", "10"], ["make 8,217,822,536 designs to weigh"]),
    (["plan", "--points-per-nm", "1e5"], ["sample_rate", "is out of range", "[1 Hz, 100 MHz]"]),
    (["plan", "--points-per-nm", "1e3", "--start", "-50um"], ["samples together, more than 2e+07"]),
    (["plan", "--start", "-1m"], ["--start -1m is out of range: start, the drive start position"]),
    (["fit", CURVE, "--report", "/proc/x.md"], ["--report /proc/x.md cannot be written"]),
    (["fit", CURVE, "--plots", "/proc/plots"], ["--plots /proc/plots cannot be written"]),
    (["simulate", "--out", "a.csv", "--raw", "a.csv"], ["--out and --raw name the same file a.csv"]),
    (["simulate", "--out", "a.csv", "--plot", "./sub/../a.csv"], ["--out and --plot name the same file"]),
    (["sweep", "--grid", "velocity=1um/s,2um/s", "--scheduler", "not a url"],
     ["--scheduler 'not a url' is not a Dask scheduler address"]),
    (["analyze", CURVE, "--scheduler", "not a url"], ["is not a Dask scheduler address"]),
    (["sweep", "--range", "velocity=1um/s:2um/s", "--sample", "random", "--n", "3", "--seed", "-1"],
     ["--seed must be at least 0, got -1"]),
    (["sweep", "--grid", "velocity=1um/s:2um/s:1000000000000", "--yes"],         # no axis of 1e12 values
     ["--grid velocity: 1,000,000,000,000 values is more than the 5,000,000"]),
    (["sweep", "--range", "velocity=1um/s:2um/s", "--sample", "random", "--n", "1000000000000", "--yes"],
     ["runs: 1,000,000,000,000 runs in one sweep is more than the 5,000,000"]),
    (["sweep", "--grid", "velocity=1um/s:2um/s:3000", "--grid", "xi=0:1:3000", "--yes"],
     ["runs: 9,000,000 runs in one sweep is more than the 5,000,000"]),
])
def test_sizes_and_outputs_are_refused_before_work(capsys, tmp_path, monkeypatch, no_work, argv, fragments):
    monkeypatch.chdir(tmp_path)
    err = refused(capsys, argv)
    for fragment in fragments:
        assert fragment in err, err
    assert not list(tmp_path.rglob("manifest.json")) and not (tmp_path / "a.csv").exists()


def test_plan_caps_are_the_library_s(monkeypatch):
    """The web and Python get the same caps: the library checks them, not only the CLI."""
    import afmforce.fit.plan as plan

    monkeypatch.setattr(plan, "curve_information", _boom)
    with pytest.raises(ParameterError, match="`n_curves`: 21 curves in a design is more than the 20"):
        plan.plan_experiment(n_curves=limits.MAX_DESIGN_CURVES + 1)
    with pytest.raises(WorkStarted):       # at the cap: allowed (the work starts)
        plan.plan_experiment(n_curves=limits.MAX_DESIGN_CURVES, speeds=(1e-6, 2e-6))


def test_fit_plots_does_not_replace_an_earlier_run_s_figures(capsys, tmp_path, monkeypatch, no_work):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "plots").mkdir()
    (tmp_path / "plots" / "fit_curve1_old.png").write_bytes(b"an earlier run")
    err = refused(capsys, ["fit", CURVE, "--plots", "plots"])
    assert "--plots plots holds 1 file(s) this command would replace (e.g. fit_curve1_old.png)" in err
    assert "--force" in err
    assert (tmp_path / "plots" / "fit_curve1_old.png").read_bytes() == b"an earlier run"
    started(capsys, ["fit", CURVE, "--plots", "plots", "--force"])
    started(capsys, ["fit", CURVE, "--plots", "fresh"])          # a new or empty folder needs no --force


def test_reproduce_does_not_replace_an_earlier_run_without_force(capsys, tmp_path, monkeypatch, no_work):
    from afmforce.paper.reproduce import planned_files

    monkeypatch.chdir(tmp_path)
    names = planned_files(["fig5"], svg=True)
    assert names == ["fig5_trajectory.png", "fig5_trajectory.svg", "report.md", "report.json"]
    (tmp_path / "paper").mkdir()
    (tmp_path / "paper" / names[1]).write_text("an earlier run's svg")
    err = refused(capsys, ["reproduce", "--out", "paper", "--only", "fig5", "--svg"])
    assert f"--out paper holds 1 file(s) this command would replace (e.g. {names[1]})" in err
    started(capsys, ["reproduce", "--out", "paper", "--only", "fig5", "--svg", "--force"])
    started(capsys, ["reproduce", "--out", "paper", "--only", "fig5"])   # the PNG does not exist yet
    assert (tmp_path / "paper" / names[1]).read_text() == "an earlier run's svg"


def test_a_sweep_that_fails_to_start_leaves_no_manifest(tmp_path):
    """A Dask sweep whose cluster cannot be reached fails before any work: no store is left."""
    from afmforce.sweep import run_sweep

    with pytest.raises(ParameterError, match="not a Dask scheduler address"):
        run_sweep(_boom, {"x": [1.0, 2.0]}, executor="dask", scheduler="not a url", store=tmp_path / "sw")
    assert not list(tmp_path.rglob("manifest.json")) and not list(tmp_path.rglob("parameters.parquet"))


def test_docs_ranges_lists_the_caps():
    text = (Path(__file__).parents[2] / "docs" / "ranges.md").read_text()
    assert limits.caps_markdown() in text, "docs/ranges.md is stale: regenerate it from afmforce.limits.caps_markdown()"
