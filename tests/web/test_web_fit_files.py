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
