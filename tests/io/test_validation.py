"""Bad input: raw-file validation, empty files, damaged HDF5 attributes, time budgets (issue 14 items 5, 6)."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from afmforce.analysis.synthetic import static_curve
from afmforce.errors import FileFormatError
from afmforce.io import FORMATS, ReaderFormat, load
from afmforce.io._guard import FileTimeoutError, run_with_timeout
from afmforce.io.native.rawfile import format_text, write_raw

DATA = Path(__file__).resolve().parents[1] / "data"


@pytest.fixture(scope="module")
def text():
    return format_text(static_curve(noise=0.05e-9, seed=3))


def _edit(text: str, key: str, value: str) -> str:
    lines = text.splitlines()
    i = next(j for j, ln in enumerate(lines) if ln.startswith(f"# {key}:"))
    lines[i] = f"# {key}: {value}"
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("key,value", [("sensitivity", "-5e-08 m/V"), ("spring_constant", "0 N/m"),
                                       ("spring_constant", '{"a": 1}'), ("velocity", "-1e-7 m/s")])
def test_raw_metadata_must_be_positive_numbers(tmp_path, text, key, value):
    if f"# {key}:" not in text:
        text = text.replace("# format:", f"# {key}: 1\n# format:", 1)
    path = tmp_path / "bad.txt"
    path.write_text(_edit(text, key, value))
    with pytest.raises(FileFormatError, match=rf"bad\.txt.*{key}"):
        load(path)


def _data_rows(text: str) -> tuple[list[str], int]:
    lines = text.splitlines()
    first = next(i for i, ln in enumerate(lines) if ln and not ln.startswith("#")) + 1  # after the column names
    return lines, first


def test_raw_nan_and_time_order(tmp_path, text):
    lines, first = _data_rows(text)
    nan = list(lines)
    cells = nan[first + 5].split()
    cells[2] = "nan"
    nan[first + 5] = " ".join(cells) if "\t" not in lines[first] else "\t".join(cells)
    (tmp_path / "nan.txt").write_text("\n".join(nan) + "\n")
    with pytest.raises(FileFormatError, match="nan.txt.*non-finite"):
        load(tmp_path / "nan.txt")
    swapped = list(lines)
    swapped[first + 3], swapped[first + 4] = swapped[first + 4], swapped[first + 3]
    (tmp_path / "order.txt").write_text("\n".join(swapped) + "\n")
    with pytest.raises(FileFormatError, match="order.txt.*time does not increase"):
        load(tmp_path / "order.txt")


@pytest.mark.parametrize("name", ["empty.txt", "empty.csv", "empty.jpk-force", "empty.spm", "empty.h5"])
def test_empty_files_say_so(tmp_path, name):
    (tmp_path / name).write_bytes(b"")
    with pytest.raises(FileFormatError, match=rf"{name}: empty file"):
        load(tmp_path / name)


def test_text_not_claimed_by_ntmdt(tmp_path):
    (tmp_path / "notes.txt").write_text("hello\nworld\n")
    with pytest.raises(FileFormatError, match="notes.txt: content not recognised") as err:
        load(tmp_path / "notes.txt")
    assert "spring" not in str(err.value)


def test_oversized_hdf5_attribute_is_not_read(tmp_path):
    """A 'format' attribute of 8000 bytes is refused before it is read (detection reads at most
    256 bytes of it: it must not read untrusted attributes blindly)."""
    from afmforce.io.native._hdf5 import safe_attr

    path = tmp_path / "big.h5"
    write_raw(static_curve(noise=0.05e-9, seed=3), path)
    with h5py.File(path, "a") as f:
        del f.attrs["format"]
        f.attrs.create("format", np.zeros(1000, dtype="f8"))
    with pytest.raises(FileFormatError, match="big.h5: content not recognised"):
        load(path)
    with h5py.File(path, "r") as f:
        with pytest.raises(FileFormatError, match="declares 1000 x 8 bytes"):
            safe_attr(f, "format", limit=256)
        assert safe_attr(f, "absent", "x") == "x"
        assert safe_attr(f, "format").shape == (1000,)


def _forever(*args, **kwargs):
    """Hangs for 10 minutes (a test whose timeout failed ends, failing on the missing message,
    instead of hanging the suite), then returns what no reader returns."""
    end = time.monotonic() + 600
    while time.monotonic() < end:
        time.sleep(0.01)
    return "still hanging"


def _record_pid_and_hang(pidfile):
    pidfile.write_text(str(os.getpid()))
    _forever()


def _nested(pidfile):
    """A guarded call inside a guarded call (load(timeout=) detecting an HDF5 file does this)."""
    return run_with_timeout(_record_pid_and_hang, pidfile, timeout=600, path="inner")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux only")
def test_time_budget_kills_the_readers_own_children(tmp_path):
    """The outer budget kills the child and the grandchild it is waiting on (no orphan left spinning
    and holding the result pipe open: found by the fuzz test on an afmformats HDF5 export)."""
    pidfile = tmp_path / "pid"
    t0 = time.monotonic()
    with pytest.raises(FileTimeoutError, match="outer"):
        run_with_timeout(_nested, pidfile, timeout=2.0, path="outer")
    assert time.monotonic() - t0 < 10
    inner = int(pidfile.read_text())
    for _ in range(100):  # SIGKILL is delivered asynchronously
        try:
            os.kill(inner, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        os.kill(inner, 9)
        pytest.fail(f"grandchild {inner} survived its parent")


def test_time_budget_kills_a_hanging_reader(tmp_path, monkeypatch):
    t0 = time.monotonic()
    with pytest.raises(FileTimeoutError, match="x.slow: reading took longer than 0.5 s"):
        run_with_timeout(_forever, timeout=0.5, path=str(tmp_path / "x.slow"))
    assert time.monotonic() - t0 < 5
    assert run_with_timeout(sum, [1, 2, 3], timeout=5) == 6
    with pytest.raises(FileFormatError, match="no such file"):
        load(tmp_path / "missing.ibw", timeout=5)
    good = load(DATA / "asylum-mfp3d_SiN-tip_air.ibw", timeout=30)[0]
    np.testing.assert_array_equal(good.deflection_signal, load(DATA / "asylum-mfp3d_SiN-tip_air.ibw")[0].deflection_signal)


def test_batch_reports_a_hanging_file_and_goes_on(tmp_path, monkeypatch, capsys):
    """A reader that never returns: `analyze dir/ --file-timeout 1s` reports it and analyses the rest."""
    from afmforce.cli.main import main

    monkeypatch.setitem(FORMATS, "hang", ReaderFormat("hang", "hangs", (".hang",), lambda p: True, _forever,
                                                      via="afmforce"))
    (tmp_path / "a.hang").write_bytes(b"x")
    (tmp_path / "b.ibw").write_bytes((DATA / "asylum-mfp3d_SiN-tip_air.ibw").read_bytes())
    code = main(["analyze", str(tmp_path), "--file-timeout", "1s", "--serial"])
    out = capsys.readouterr()
    assert "a.hang" in out.out + out.err and "longer than 1 s" in out.out + out.err
    assert "b.ibw" in out.out
    assert code == 1
