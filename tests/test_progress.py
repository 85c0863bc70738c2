"""One progress contract (issue 11, item 9): simulate, load, sweeps and reproduce report
:class:`afmforce.progress.Progress` records."""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce.progress import Progress

DATA = Path(__file__).parent / "data"


def test_fraction_and_unknown_total():
    assert Progress(done=3, total=12, unit="chunk").fraction == 0.25
    assert Progress(done=5, total=None).fraction is None
    assert Progress(done=2.0, total=1.0).fraction == 1.0
    assert Progress(done=1, total=1).finished and not Progress(done=0, total=1).finished


def test_load_reports_the_file_it_reads():
    from afmforce.io import load

    path = next(p for p in sorted(DATA.glob("*.jpk-force")))
    seen = []
    curves = load(path, progress=seen.append)
    assert curves and seen
    assert seen[-1].fraction == 1.0
    assert all(isinstance(p, Progress) and p.unit == "file" and p.what == path.name for p in seen)


def test_reproduce_reports_figures(tmp_path):
    from afmforce.paper.reproduce import reproduce

    seen = []
    reproduce(tmp_path / "out", only=["fig1"], fast=True, progress=seen.append)
    assert seen and {p.unit for p in seen} == {"figure"}
    assert seen[-1].fraction == 1.0 and seen[0].what == "fig1"


def test_cli_bar_takes_every_unit():
    from afmforce.cli.common import progress_bar

    for unit, p in (("s", Progress(0.5, 2.0, "s")), ("chunk", Progress(3, 7, "chunk", failed=1)),
                    ("figure", Progress(1, 4, "figure", what="fig5")), ("file", Progress(0.3, 1.0, "file"))):
        bar, update = progress_bar("x", p.total, unit=unit)
        update(p)          # off a terminal the bar is disabled but takes the record
        bar.close()
    with pytest.raises(AttributeError):
        update(0.5)        # a bare float is not the contract
