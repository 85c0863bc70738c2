"""A force map's declared curve count is bounded by the bytes its file holds (branch mapcap).

A 68 kB ARDF file whose 1,000 line pointers all named its one line declared 999,001 curves:
``afmforce analyze`` made a work item per curve and analysed on (killed after 90 s, 365 MB). Each map
reader now refuses a count its bytes cannot hold, naming the file and what is wrong, and a batch takes
at most :data:`afmforce.limits.BATCH_MAX_CURVES` curves unless told more. The files are built here byte by
byte (tests/io/_ardf_build.py) or edited from the trimmed real Nanosurf map (tests/data).
"""

from __future__ import annotations

import os
import re
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from _ardf_build import build_ardf, source_curve, write_ardf  # noqa: E402 (tests/io on sys.path)
from afmforce.errors import FileFormatError, ParameterError
from afmforce.io.ardf import count_curves
from afmforce.sweep.files import TooManyCurves, plan_curves

DATA = Path(__file__).resolve().parents[1] / "data"


def _vtoc(raw: bytes) -> tuple[int, int]:
    """(offset of the VTOC record, its entries)."""
    at = raw.index(b"VTOC") - 8
    return at, struct.unpack("<I", raw[at + 24:at + 28])[0]


def _pointers(raw: bytes) -> list[int]:
    at, n = _vtoc(raw)
    return [struct.unpack("<Q", raw[at + 64 + 40 * j:at + 72 + 40 * j])[0] for j in range(n)]


def _set_pointers(path: Path, pointers: list[int]) -> Path:
    raw = bytearray(path.read_bytes())
    at, n = _vtoc(raw)
    assert len(pointers) == n
    for j, p in enumerate(pointers):
        raw[at + 64 + 40 * j:at + 72 + 40 * j] = struct.pack("<Q", p)
    path.write_bytes(bytes(raw))
    return path


def forged_ardf(path: Path, nx: int = 1000, ny: int = 1000) -> Path:
    """One real curve in a map of ``nx`` x ``ny`` whose every line pointer names line 0 (the web audit's file)."""
    data, note = source_curve()
    cols = {c: data[:, j].astype(float) for j, c in enumerate(("Raw", "Defl", "ZSnsr"))}
    write_ardf(path, [(0, 0, cols)], nx=nx, ny=ny, note=note, ends=(224, 1232, 1260))
    first = _pointers(path.read_bytes())[0]
    return _set_pointers(path, [first] * ny)


def test_a_line_table_repeating_one_line_is_refused_naming_the_lines(tmp_path):
    """Before: count_curves gave 999,001 for a 68,684-byte file; now FileFormatError naming the file and
    the two lines that share a byte."""
    path = forged_ardf(tmp_path / "forged.ARDF")
    assert path.stat().st_size < 100_000
    with pytest.raises(FileFormatError, match=re.escape(str(path)) + ".*names byte .* for recorded lines 0 and 1"):
        count_curves(path)


def test_a_line_pointing_into_another_is_refused_and_any_order_is_read(tmp_path):
    """A pointer into the middle of the line before leaves room for fewer curves than a line holds: refused,
    saying how many fit. The lines in reverse order (a map scanned downward) are no damage: 12 curves read."""
    path = tmp_path / "map.ARDF"
    build_ardf(path, nx=4, ny=3)
    starts = _pointers(path.read_bytes())
    assert count_curves(path) == 12 and starts == sorted(starts)
    line = starts[1] - starts[0]                      # bytes of one line of 4 curves
    _set_pointers(path, [starts[0], starts[0] + line // 4, starts[2]])
    with pytest.raises(FileFormatError, match=r"recorded lines 0 and 1 .* both start at a curve of map line 0 "
                                              r"\(bytes \d+ and \d+\): overlapping"):
        count_curves(path)
    _set_pointers(path, [starts[0], starts[1], path.stat().st_size - 300])   # a line in the last curve's bytes
    with pytest.raises(FileFormatError):
        count_curves(path)
    data, note = source_curve()                       # three lines of one curve each, in a map of 1000 points
    cols = {c: data[:, j].astype(float) for j, c in enumerate(("Raw", "Defl", "ZSnsr"))}
    sparse = tmp_path / "sparse.ARDF"
    write_ardf(sparse, [(0, y, cols) for y in range(3)], nx=1000, ny=3, note=note, ends=(224, 1232, 1260))
    with pytest.raises(FileFormatError, match=r"recorded line 0 .* room for at most \d+ of its 1000 curves before "
                                              r"the next line at byte \d+; the line table is damaged"):
        count_curves(sparse)                          # before: 2,001 curves declared in 47 kB
    _set_pointers(path, starts[::-1])
    assert count_curves(path) == 12


def test_a_nid_block_of_lines_without_points_is_refused(tmp_path):
    """Before: a .nid whose blocks declared 10^8 lines of 0 points (0 bytes of data) was a map of 10^8 curves."""
    from afmforce.io.nanosurf import count_curves as nid_curves

    raw = (DATA / "nanosurf-nid_spectroscopy-map_2x2_trimmed.nid").read_bytes()
    end = raw.index(b"\r\n#!") + 4
    head = re.sub(rb"\nPoints=\d+", b"\nPoints=0", raw[:end])
    head = re.sub(rb"\nLines=\d+", b"\nLines=100000000", head).replace(b";2;2;0;1", b";10000;10000;0;1")
    path = tmp_path / "forged.nid"
    path.write_bytes(head)
    with pytest.raises(FileFormatError, match=re.escape(str(path)) + ".* declares 100000000 lines of 0 points"):
        nid_curves(path)


def test_a_batch_takes_at_most_its_cap_from_the_headers(tmp_path):
    """plan_curves (and analyze_files, afmforce analyze) count a map's curves before making its items: past
    ``max_curves`` TooManyCurves names the file; the default is limits.BATCH_MAX_CURVES (65,536 x 16)."""
    from afmforce.limits import BATCH_MAX_CURVES, SERVER_MAX_CURVES

    assert BATCH_MAX_CURVES == 16 * SERVER_MAX_CURVES           # a user's 256 x 256 map runs, sixteen of them
    path = tmp_path / "map.ARDF"
    build_ardf(path, nx=4, ny=3)
    assert len(plan_curves([path])) == 12
    with pytest.raises(TooManyCurves, match=re.escape(str(path)) + r": 12 curves .* more than the 11 taken"):
        plan_curves([path], max_curves=11)
    forged = forged_ardf(tmp_path / "forged.ARDF")
    assert len(plan_curves([forged])) == 1                     # a damaged file: one item, its error reported


def _limit_memory() -> None:  # pragma: no cover (runs in the child)
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))


@pytest.mark.skipif(sys.platform != "linux", reason="RLIMIT_AS")
def test_cli_answers_a_forged_map_in_one_line_in_bounded_memory(tmp_path):
    """``afmforce analyze forged.ARDF`` in 1 GiB of address space: exit 1 and one line naming the file and
    its line table. Before: 999,001 items, analysed on past the guard (killed after 90 s, 365 MB)."""
    path = forged_ardf(tmp_path / "forged.ARDF")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1", PYTHONPATH=os.pathsep.join(
        [str(Path(__file__).resolve().parents[2] / "src"), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run([sys.executable, "-m", "afmforce.cli.main", "analyze", str(path), "--serial"],
                          capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300,  # a hang guard
                          preexec_fn=_limit_memory)
    lines = [line for line in done.stderr.splitlines() if line.strip()]
    assert done.returncode == 1 and "Traceback" not in done.stderr, done.stderr[-2000:]
    assert len(lines) == 1 and str(path) in lines[0] and "line table names byte" in lines[0], lines


def test_cli_max_curves_is_checked_and_named(tmp_path, capsys):
    from afmforce.cli.main import main

    path = tmp_path / "map.ARDF"
    build_ardf(path, nx=4, ny=3)
    assert main(["analyze", str(path), "--max-curves", "11"]) != 0
    err = capsys.readouterr().err
    assert "12 curves" in err and "--max-curves" in err and "Traceback" not in err
    assert main(["analyze", str(path), "--max-curves", "0"]) != 0
    assert "--max-curves must be positive" in capsys.readouterr().err
    assert issubclass(TooManyCurves, ParameterError)
