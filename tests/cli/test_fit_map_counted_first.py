"""``afmforce fit MAP`` on a force map past the fit's cap (:data:`afmforce.fit.core.MAX_CURVES`) is
refused from the map's header, before its curves are read (the walk of 2026-11-29: a 64 x 64
NanoScope force volume of 6201-sample curves was read whole to be refused: peak RSS 995 MB, a
map 4x larger would have needed 4 GB; from the header: 147 MB)."""

from __future__ import annotations

import pytest

import afmforce.io as io
from afmforce.cli.main import main
from afmforce.fit.core import MAX_CURVES
from afmforce.instrument.soft_map import SoftMapConfig, write_soft_map


@pytest.fixture
def reads(monkeypatch):
    """The paths afmforce.io.load is asked to read (the CLI imports it at call time)."""
    seen = []
    real = io.load

    def load(path, *a, **k):
        seen.append(str(path))
        return real(path, *a, **k)

    monkeypatch.setattr(io, "load", load)
    return seen


@pytest.mark.parametrize("fmt,name", [("bruker-fv", "m.spm"), ("jpk-qi", "m.jpk-qi-data")])
def test_map_past_the_cap_refused_before_reading_it(tmp_path, capsys, reads, fmt, name):
    cfg = SoftMapConfig(nx=6, ny=6, seed=1)
    assert cfg.nx * cfg.ny > MAX_CURVES
    path = write_soft_map(cfg, tmp_path / name, format=fmt)
    assert main(["fit", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: a joint fit of 36 curves: the dynamic fit takes at most {MAX_CURVES}")
    assert len(err.strip().splitlines()) == 1
    assert str(path) not in reads     # refused from the header: no curve of the map was read


def test_files_without_a_header_count_stop_at_the_cap(tmp_path, capsys, reads):
    """Single-curve files (a folder of them) are read only until the cap is passed."""
    from afmforce import datasets
    import shutil

    src = datasets.fit_example("speeds")[0]
    folder = tmp_path / "many"
    folder.mkdir()
    for i in range(MAX_CURVES + 5):
        shutil.copy(src, folder / f"c{i:03d}{src.suffix}")
    assert main(["fit", str(folder)]) == 2
    err = capsys.readouterr().err
    assert f"a joint fit of {MAX_CURVES + 1} curves" in err
    assert len(reads) == MAX_CURVES + 1
