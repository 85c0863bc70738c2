"""Where the tests find the real instrument files of ``shared/data/real`` (beside the
repository): there, or their byte-identical copies in ``tests/data`` (some under a name
that says the instrument), so that a checkout without the shared folder still tests them.
Only files too large for ``tests/data`` (the 0.6-1 MB JPK files, the 2 MB Bruker force volume, the
HeLa JPK map, the 5.5 MB Nanosurf map) are skipped without it."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
DATA = TESTS / "data"
#: The shared folder beside the repository, or where ``AFMFORCE_REAL_DATA`` points (a worktree elsewhere).
SHARED = Path(os.environ.get("AFMFORCE_REAL_DATA") or TESTS.parents[1] / "shared" / "data" / "real")

#: shared name -> name of its byte-identical copy in tests/data, where they differ
COPIES = {
    "ForceMetric_X60_3_x4_0100.ibw": "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw",
    "PyFMlab_20200904_Egel4-Z1.0_00025.spm": "bruker-nanoscope_PyFMlab_Egel4_00025.spm",
}


def real_path(name: str) -> Path | None:
    """The shared real file ``name``, or its copy in tests/data; None when neither exists."""
    for path in (SHARED / name, DATA / COPIES.get(name, name)):
        if path.is_file():
            return path
    return None


def real_file(name: str) -> Path:
    """:func:`real_path`, skipping the calling test when the file is in neither place."""
    path = real_path(name)
    if path is None:
        pytest.skip(f"{name} is neither in {SHARED} nor in tests/data (too large to copy)")
    return path


def wave_note(path) -> dict[str, str]:
    """An Igor binary wave's note as ``{Key: value}`` (its ``Key:value`` lines, the first of each key),
    read with igor2, not afmforce: the header values a test checks afmforce's numbers against."""
    from igor2 import binarywave

    note = binarywave.load(str(path))["wave"]["note"].decode("latin-1")
    out: dict[str, str] = {}
    for line in note.replace("\n", "\r").split("\r"):
        key, sep, value = line.partition(":")
        if sep and key not in out:
            out[key] = value.strip()
    return out
