"""``afmforce analyze MAP --fast-map`` writes each curve's warnings, in the column the full analysis writes them
(``warnings``, joined by `` | ``, the same words): faces audit 2026-11-29, the fast map's summary table had no
warnings column while the full path's per-curve table had one (a 200 N/m lever, warned about by ``analyze``,
was mapped without a word)."""

from __future__ import annotations

import csv

import pytest

from afmforce.cli.main import main
from afmforce.instrument.soft_map import SoftMapConfig, write_soft_map
from afmforce.sweep.map_fast import PixelAnalysis
from afmforce.analysis.options import ProbeCalibration


@pytest.fixture(scope="module")
def soft_map(tmp_path_factory):
    return write_soft_map(SoftMapConfig(nx=2, ny=1, seed=4), tmp_path_factory.mktemp("map") / "soft.jpk-qi-data",
                          format="jpk-qi")


def _rows(out):
    (summary,) = out.rglob("summary.csv")
    return {r["name"]: r for r in csv.DictReader(summary.open())}


def test_the_fast_map_table_has_the_full_paths_warnings_column(soft_map, tmp_path, capsys):
    flags = ["--serial", "--radius", "5um", "--spring-constant", "200N/m"]
    assert main(["analyze", str(soft_map), "--fast-map", "--out", str(tmp_path / "fast"), *flags]) == 0
    printed = capsys.readouterr().out
    assert main(["analyze", str(soft_map), "--no-plot", "--out", str(tmp_path / "full"), *flags]) == 0
    fast, full = _rows(tmp_path / "fast"), _rows(tmp_path / "full")
    assert set(fast) == set(full) and len(fast) == 2
    k_warning = [w for w in next(iter(full.values()))["warnings"].split(" | ") if w.startswith("spring constant")]
    assert len(k_warning) == 1 and "200 N/m" in k_warning[0]
    for name, row in fast.items():
        warnings = row["warnings"].split(" | ")
        assert k_warning[0] in warnings, (name, row["warnings"])      # the same words, the same column
        assert set(warnings) <= set(full[name]["warnings"].split(" | ")) | {w for w in warnings
                                                                            if w.startswith("indentation")}
    assert "warning (2 of 2 curves): spring constant 200 N/m" in printed


def test_a_plausible_lever_gives_no_spring_constant_warning():
    from afmforce.instrument.soft_map import soft_map_curves

    cfg = SoftMapConfig(nx=1, ny=1, seed=4)
    c = next(iter(soft_map_curves(cfg)))
    row = PixelAnalysis(probe=ProbeCalibration(radius=cfg.radius)).row(c)
    assert "warnings" in row and "spring constant" not in row["warnings"]
    row = PixelAnalysis(probe=ProbeCalibration(radius=cfg.radius, spring_constant=500.0)).row(c)
    assert row["warnings"].startswith("spring constant 500 N/m of the file or the user is outside")
