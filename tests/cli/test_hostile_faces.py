"""Hostile input typed as a user types it, each refused in one readable line (branch fuzzfaces).

Each case is one a systematic pass over every command and web endpoint found answered wrongly:
a truncated thermal spectrum read as if whole, a symbolic-link loop called "no such file", a
1-byte ``.tiff`` called "a TIFF image", numpy's advice rendered as a flag afmforce has not
(``--usecols``), a finite 1e308 m/s shown as "inf um/s", an empty value shown as ``got  (not a number)``.
"""

from __future__ import annotations

import hashlib
import os
import zipfile
from pathlib import Path

import numpy as np
import pytest

from afmforce.cli.main import main
from afmforce.errors import FileFormatError, ParameterError, UnitError

DATA = Path(__file__).parents[1] / "data"
TND = DATA / "jpk-tnd_PFQNM-water_thermal-noise_0-80kHz.tnd"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _one_line_error(capsys, argv, status=(1, 2)) -> str:
    code = main(argv)
    err = [line for line in capsys.readouterr().err.splitlines()
           if line.strip() and not line.startswith("afmforce: first run")]
    assert code in status, err
    assert len(err) == 1 and "Traceback" not in err[0], err
    return err[0]


def _cut_mid_row(src: Path, dst: Path) -> None:
    """The first half of ``src``, cut inside a data row (as a copy stopped mid-transfer)."""
    data = src.read_bytes()
    cut = len(data) // 2
    while data[cut - 1:cut] in (b"\n", b" "):   # inside a number, never at a row's end
        cut += 1
    dst.write_bytes(data[:cut])


def test_a_truncated_tnd_spectrum_is_refused_not_read_in_part(tmp_path, capsys):
    from afmforce.calibration.spectrum import read_spectrum

    half = tmp_path / "half.tnd"
    _cut_mid_row(TND, half)
    before = _digest(half)
    with pytest.raises(FileFormatError, match="truncated"):
        read_spectrum(half)
    line = _one_line_error(capsys, ["calibrate", "thermal", str(half)])
    assert "truncated" in line and "half.tnd" in line
    assert _digest(half) == before            # never modified
    assert len(read_spectrum(TND).frequency) > 1000   # the whole file still reads


def test_own_spectrum_format_declares_its_rows_and_refuses_a_cut_copy(tmp_path):
    from afmforce.calibration.spectrum import ThermalSpectrum, read_spectrum, write_spectrum

    f = np.linspace(100.0, 1e5, 400)
    whole = write_spectrum(tmp_path / "s.psd", ThermalSpectrum(f, 1e-26 + 0 * f, unit="m^2/Hz"))
    assert "# rows: 400" in whole.read_text()
    assert len(read_spectrum(whole).frequency) == 400          # round trip
    lines = whole.read_text().splitlines()
    cut = tmp_path / "cut.psd"
    cut.write_text("\n".join(lines[:-150]) + "\n")              # ends on a whole row: only the count tells
    with pytest.raises(FileFormatError, match="declares 400 rows, the file holds 250"):
        read_spectrum(cut)
    old = tmp_path / "old.psd"                                   # files written before: no count, read
    old.write_text("\n".join(x for x in lines if not x.startswith("# rows")) + "\n")
    assert len(read_spectrum(old).frequency) == 400


@pytest.mark.parametrize("command", [["analyze"], ["fit"]])
def test_a_symbolic_link_loop_is_named_as_such(tmp_path, capsys, command):
    a, b = tmp_path / "a.ibw", tmp_path / "b.ibw"
    os.symlink(b, a)
    os.symlink(a, b)
    line = _one_line_error(capsys, [*command, str(a), str(tmp_path / "nope.ibw")], status=(2,))
    assert "symbolic link" in line and "a.ibw" in line
    assert "no such file or folder" in line and "nope.ibw" in line and "a.ibw" not in line.split(";")[0]


@pytest.mark.parametrize("content", [b"\x00", b"GIF89a" + bytes(64)])
def test_a_tiff_ending_without_a_tiff_signature_is_not_called_a_tiff_image(tmp_path, content):
    from afmforce.io import load

    path = tmp_path / "x.tiff"
    path.write_bytes(content)
    with pytest.raises(FileFormatError) as info:
        load(path)
    assert "TIFF image" not in str(info.value) and "content not recognised" in str(info.value)
    real = tmp_path / "image.tif"               # a real (non-Park) TIFF image is still named as one
    real.write_bytes(b"II*\x00\x08\x00\x00\x00\x00\x00")
    with pytest.raises(FileFormatError, match="TIFF image"):
        load(real)


def test_numpy_advice_is_not_rendered_as_a_flag(tmp_path, capsys):
    src = DATA / "afm-workshop_single.csv"
    half = tmp_path / "half.csv"
    half.write_bytes(src.read_bytes()[: src.stat().st_size // 2])
    code = main(["analyze", str(half)])
    err = capsys.readouterr().err
    assert code == 1 and "Traceback" not in err
    assert "usecols" not in err and "half.csv" in err


def test_a_finite_value_past_the_display_unit_is_shown_finite():
    from afmforce._fields import show

    assert show(1e308, "m/s", "um/s") == "1e+308 m/s"
    assert show(2e-6, "m/s", "um/s") == "2 um/s"
    assert show(float("inf"), "m/s", "um/s") == "inf um/s"     # what was typed: inf


@pytest.mark.parametrize("text", ["", "  ", "\t"])
def test_an_empty_value_is_said_empty(text):
    from afmforce.units import parse_quantity

    with pytest.raises(UnitError, match="got an empty value; give one"):
        parse_quantity(text, "velocity", "velocity")


def test_a_zip_member_claiming_a_huge_size_is_refused_unread(tmp_path, capsys):
    bomb = tmp_path / "bomb.jpk-force"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("header.properties", "force-scan-series.header.force-settings.type=x\n")
        z.writestr("segments/0/channels/height.dat", b"\0" * 90_000_000)     # 90 MB of zeros, 90 kB stored
    line = _one_line_error(capsys, ["analyze", str(bomb)], status=(1,))
    assert "zip bomb" in line


def test_a_batch_goes_past_bad_files_and_names_each(tmp_path, capsys):
    good = tmp_path / "good.ibw"
    good.write_bytes((DATA / "asylum-mfp3d_SiN-tip_air.ibw").read_bytes())
    (tmp_path / "empty.csv").write_bytes(b"")
    (tmp_path / "junk.spm").write_bytes(os.urandom(512))
    before = {p.name: _digest(p) for p in tmp_path.iterdir()}
    code = main(["analyze", str(good), str(tmp_path / "empty.csv"), str(tmp_path / "junk.spm")])
    out, err = capsys.readouterr()
    assert code == 1 and "Traceback" not in err
    assert "empty.csv: empty file" in err and "junk.spm" in err and "2 of 3 file(s) failed" in err
    assert "good.ibw" in out                                       # the good file was analysed
    assert {p.name: _digest(p) for p in tmp_path.iterdir()} == before


@pytest.mark.parametrize("starts", [7, 100_000_000])
def test_fit_starts_have_one_cap_on_every_face(capsys, starts):
    from afmforce.fit.core import check_starts
    from afmforce.limits import MAX_STARTS

    assert MAX_STARTS == 6
    line = _one_line_error(capsys, ["fit", "--example", "speeds", "--starts", str(starts)], status=(2,))
    assert line == f"error: --starts: {starts:,} local fits is more than the {MAX_STARTS} one request may ask for"
    with pytest.raises(ParameterError, match="`starts`"):
        check_starts(starts)
    check_starts(MAX_STARTS)
    for bad in (0, -1, 1.5, True):
        with pytest.raises(ParameterError, match="at least 1"):
            check_starts(bad)


def test_a_drive_in_the_wrong_order_is_said_in_the_units_typed(capsys):
    line = _one_line_error(capsys, ["simulate", "--start", "5um"], status=(2,))
    assert line == ("error: --turn (20 nm) must lie above --start (5 um): the approach moves the substrate up "
                    "(z increasing)")
    line = _one_line_error(capsys, ["simulate", "--end", "50nm"], status=(2,))
    assert line.startswith("error: --end (50 nm) must lie below --turn (20 nm)")
