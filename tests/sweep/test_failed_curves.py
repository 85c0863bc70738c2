"""Maps and batches never drop good curves (issue 32, item 7).

One curve of a force volume fails (here a ZeroDivisionError injected into the analysis of its
third curve, as the fringe fit once raised on curve 23 of the real v9.2 force volume): it gives
one error row, with the exception type and its traceback; every other curve's results are kept,
whether the file is planned curve by curve or read whole as one item; ``errors.csv`` carries the
exception type, and ``--debug`` prints the failed curve's traceback in a batch too. The file is
the trimmed real force volume of tests/data (four curves, 2 x 2)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

import afmforce.analysis.pipeline as pipeline
from afmforce.cli.main import main
from afmforce.sweep.files import CurveAnalysis, CurveRef, analyze_files, failures, plan_curves, summary_table, \
    write_summary

VOLUME = Path(__file__).resolve().parents[1] / "data" / "bruker-nanoscope_force-volume_2x2_trimmed.spm"
STEPS = ("force",)  # contact, drift, compliance, calibration, force
BAD = 2  # the curve that fails


@pytest.fixture
def one_curve_fails(monkeypatch):
    real = pipeline.analyze

    def analyze(curve, *args, **kwargs):
        if curve.metadata.get("curve_index") == BAD:
            return 1 / 0  # what the fringe fit raised
        return real(curve, *args, **kwargs)

    monkeypatch.setattr(pipeline, "analyze", analyze)


def _check(result, path: str) -> None:
    table = summary_table(result)
    assert len(table) == 4
    ok = table[table["error"].isna()]
    assert sorted(ok["curve"]) == [0, 1, 3]  # the good curves' results are all there
    assert ok["sensitivity"].notna().all() and (ok["spring_constant"] == 0.1332).all()
    assert sorted(zip(ok["map_x"], ok["map_y"])) == [(0, 0), (1, 0), (1, 1)]
    bad = table[table["error"].notna()]
    assert list(bad["error_type"]) == ["ZeroDivisionError"]
    assert failures(result) == [(f"{path}#{BAD}", "ZeroDivisionError: division by zero")]


def test_force_volume_is_planned_curve_by_curve():
    refs = plan_curves([VOLUME])
    assert [(r.index, r.format) for r in refs] == [(i, "bruker-nanoscope") for i in range(4)]


@pytest.mark.parametrize("whole", [False, True])
def test_one_failed_curve_keeps_the_others(one_curve_fails, tmp_path, whole):
    refs = [CurveRef(str(VOLUME))] if whole else plan_curves([VOLUME])
    result = analyze_files(refs, CurveAnalysis(steps=STEPS), executor="serial", chunk_size=4)
    _check(result, str(VOLUME))
    paths = write_summary(result, tmp_path)
    errors = pd.read_csv(paths["errors"])
    assert list(errors.columns) == ["source", "error_type", "error"]
    assert list(errors["error_type"]) == ["ZeroDivisionError"] and list(errors["source"]) == [f"{VOLUME}#{BAD}"]
    assert len(pd.read_csv(paths["csv"])) == 4


def test_debug_shows_the_failed_curves_traceback_in_a_batch(one_curve_fails, tmp_path, capsys):
    argv = ["analyze", str(VOLUME), "--steps", "force", "--serial", "--chunk-size", "2", "--out",
            str(tmp_path)]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert f"{VOLUME}#{BAD}" in err and "ZeroDivisionError" in err and "Traceback" not in err
    (errors,) = tmp_path.glob("batch-*/errors.csv")
    assert list(pd.read_csv(errors)["error_type"]) == ["ZeroDivisionError"]
    summary = pd.read_csv(errors.parent / "summary.csv")
    assert sorted(summary.loc[summary["error"].isna(), "curve"]) == [0, 1, 3]  # reported, not dropped
    assert main(["--debug", *argv, "--force"]) == 1
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and "return 1 / 0" in err
