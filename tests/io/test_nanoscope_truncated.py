"""A NanoScope force volume whose file was cut short, or whose channel holds fewer curves than its
grid: the complete curves are read (byte for byte those of the whole file), the rest are said in one
line and never made up; a file without one complete curve is refused in one line.

The whole file is the trimmed 2 x 2 v9.2 force volume of tests/data (int32 samples, 2048 a curve,
deflection data at byte 80960, 8192 bytes a curve); its copies are cut here."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.state import prepare
from afmforce.errors import FileFormatError
from afmforce.io import load
from afmforce.io.map_curves import open_map
from afmforce.io.nanoscope import NanoscopeFile, count_curves

DATA = Path(__file__).resolve().parents[1] / "data"
WHOLE = DATA / "bruker-nanoscope_force-volume_2x2_trimmed.spm"
SINGLE = DATA / "bruker-nanoscope_sapphire_TAP525.001"
OFFSET, CURVE = 80960, 2048 * 4  # the deflection channel's data offset and one curve's bytes


def _cut(tmp_path: Path, size: int, name: str = "cut.spm") -> Path:
    path = tmp_path / name
    path.write_bytes(WHOLE.read_bytes()[:size])
    return path


@pytest.mark.parametrize("extra", [0, 1, CURVE // 2, CURVE - 1])
def test_a_cut_force_volume_gives_its_complete_curves_and_says_so(tmp_path, extra):
    """Cut inside the third curve (or at its first byte): curves 0 and 1, equal to the whole file's."""
    whole = load(WHOLE)
    cut = _cut(tmp_path, OFFSET + 2 * CURVE + extra)
    curves = load(cut)
    assert len(curves) == 2
    for mine, ref in zip(curves, whole):
        np.testing.assert_array_equal(mine.deflection_signal, ref.deflection_signal)
        np.testing.assert_array_equal(mine.piezo_nominal, ref.piezo_nominal)
        assert (mine.metadata["map_x"], mine.metadata["map_y"]) == (ref.metadata["map_x"], ref.metadata["map_y"])
        note = mine.metadata["file_truncated"]
        assert "\n" not in note and "curves 0-1 read" in note and "curves 2-3 not read" in note
    assert "file_truncated" not in whole[0].metadata
    assert count_curves(cut) == 2 and count_curves(WHOLE) == 4  # what the batch engine plans on
    m = open_map(cut, "bruker-nanoscope")  # the batch engine's way in: curve by curve
    try:
        assert len(m) == 2
        with pytest.raises(FileFormatError, match="no curve 2"):
            m.read(2)
    finally:
        m.close()
    assert any("curves 2-3 not read" in w for w in prepare(curves[0]).warnings)  # the analysis says it


@pytest.mark.parametrize("size", [OFFSET + 10, OFFSET + CURVE - 1])
def test_a_force_volume_cut_inside_its_first_curve_is_refused_in_one_line(tmp_path, size):
    with pytest.raises(FileFormatError, match="truncated: no complete curve") as err:
        load(_cut(tmp_path, size))
    assert "\n" not in str(err.value)


def test_a_single_curve_file_cut_short_is_refused(tmp_path):
    data = SINGLE.read_bytes()
    path = tmp_path / "sapphire.001"
    path.write_bytes(data[:-100])
    with pytest.raises(FileFormatError, match=r"ends inside its curve's data; truncated"):
        load(path)


def test_a_channel_holding_fewer_curves_than_the_grid_reads_those_it_holds(tmp_path):
    """The header's Data length says 3 curves of 4-byte samples (24576 bytes), not the grid's 4: read as
    2-byte samples it would be 6 curves, more than the grid holds (the reader made 6 of them before)."""
    data = WHOLE.read_bytes()
    assert data.count(b"\\Data length: 32768") == 1
    path = tmp_path / "partial.spm"
    path.write_bytes(data.replace(b"\\Data length: 32768", b"\\Data length: 24576"))
    whole = load(WHOLE)
    curves = load(path)
    assert len(curves) == 3
    for mine, ref in zip(curves, whole):
        np.testing.assert_array_equal(mine.deflection_signal, ref.deflection_signal)
    assert "3 of the 2 x 2 grid's 4 curves" in curves[0].metadata["file_truncated"]
    assert count_curves(path) == 3


def test_the_file_object_counts_only_complete_curves(tmp_path):
    with NanoscopeFile(_cut(tmp_path, OFFSET + 3 * CURVE + 5)) as f:
        assert len(f) == 3
