"""The web fit takes every curve of an uploaded file, as `afmforce fit` does (a force map too)."""

from __future__ import annotations

import pytest

from afmforce.errors import AfmforceError
from afmforce.web.tasks import fit_task
from realdata import real_file


def test_a_map_upload_gives_one_fit_curve_per_cell():
    """The JPK 2x2 map: four curves named FILE#1..#4 (it refused "holds 4 curves" before); its
    cells are soft, so the fit stops at the first with the analysis's reason, as the CLI does."""
    path = real_file("afmformats_jpk-fd_map2x2_extracted.jpk-force-map")
    with pytest.raises(AfmforceError) as exc:
        fit_task({"files": [(str(path), path.name)], "free": ["hamaker"]}, lambda p: None)
    msg = str(exc.value)
    assert msg.startswith(f"{path.name}#1: soft contact (") and "holds" not in msg


def test_every_curve_of_an_upload_is_fitted(monkeypatch, tmp_path):
    """Without the shared real files too: a file whose reader returns two virtual curves (1 and
    4 um/s) is fitted as two curves, FILE#1 and FILE#2, and the fit finds the friction."""
    import afmforce.io

    from afmforce.fit import virtual_curves

    curves = virtual_curves([1e-6, 4e-6], seed=3, xi=0.005, noise=0.01e-9, start=-30e-9, turn=10e-9,
                            end=-230e-9, sample_rates=[2e3, 8e3])
    monkeypatch.setattr(afmforce.io, "load", lambda path, meta_override=None: list(curves))
    out = fit_task({"files": [(str(tmp_path / "two.txt"), "two.txt")], "profile": False,
                    "compare": False}, lambda p: None)
    assert [c["name"] for c in out["curves"]] == ["two.txt#1", "two.txt#2"]
    assert out["parameters"]["xi"]["value"] == pytest.approx(0.005, rel=0.3)
