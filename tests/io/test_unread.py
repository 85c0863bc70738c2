"""Families afmforce knows but does not read get one line naming the format and what to do
(``afmforce.io._unread``), not "unknown file type" and a list of endings. The UFF file is real
(PyFMReader's test file, MIT, ``tests/data/refused/``); the others are the formats' own signatures
written here (a TIFF with Park Systems' private tags, HDF5's signature under ``.nhf``)."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from afmforce.errors import FileFormatError
from afmforce.io import is_supported, load

UFF = Path(__file__).resolve().parents[1] / "data" / "refused" / "pyfmreader_20200904_Egel4-Z1.0_00025.uff"


def _refusal(path) -> str:
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert "\n" not in msg and "unknown file type" not in msg
    assert not is_supported(path)  # a folder given to `afmforce analyze` skips it
    return msg


def _tiff(path, park_kind=None):
    """A little-endian TIFF whose first IFD holds Park's magic tag (50432) and header tag (50435),
    the header's first int32 being the data type (0 image, 1 line profile, 2 spectroscopy)."""
    tags = [(256, 4, 1, 1)]
    header_at = 8 + 2 + 12 * 3 + 4
    if park_kind is not None:
        tags += [(50432, 4, 1, 0x0E031301), (50435, 1, 4, header_at)]
    ifd = struct.pack("<H", len(tags)) + b"".join(struct.pack("<HHII", *t) for t in tags) + b"\0" * 4
    body = b"II*\x00" + struct.pack("<I", 8) + ifd
    body = body.ljust(header_at, b"\0") + struct.pack("<i", park_kind or 0) + b"\0" * 60
    path.write_bytes(body)
    return path


def test_a_pyfmreader_uff_file_names_the_instrument_file_it_came_from():
    msg = _refusal(UFF)
    assert "PyFMReader UFF" in msg and "no time column" in msg
    assert msg.endswith("read the instrument file it was made from (20200904_Egel4-Z1.0_00025.spm)")


@pytest.mark.parametrize("name, content, words, reader", [
    ("map.nhf", b"\x89HDF\r\n\x1a\n" + b"\0" * 64, "Nanosurf NHF", "'nanosurf-nid'"),
    ("curve.mdt", b"\x01\xb0\x04\x06" + b"\0" * 64, "an NT-MDT MDT binary file", "'ntmdt-txt'"),
    ("volume.ff.ch1.gsi", b"WSxM file copyright UAM\n", "WSxM force volume", "'wsxm-curves'"),
    ("series.CUR", b"WSxM file copyright UAM\n", "WSxM text curve", "'wsxm-curves'"),
])
def test_known_unread_families_name_the_format_and_a_reader_to_export_to(tmp_path, name, content, words, reader):
    path = tmp_path / name
    path.write_bytes(content)
    msg = _refusal(path)
    assert msg.startswith(f"{path}: ") and words in msg and reader in msg and "afmforce formats" in msg


def test_park_tiff_spectroscopy_and_image_are_told_apart(tmp_path):
    """TIFF endings are claimed by the Park reader (tests/io/test_park_tiff.py): a Park image is refused
    by it as an image, any other TIFF still as an image; each in one line, and a folder scan skips both
(it takes a Park spectroscopy TIFF, whose damage is then said)."""
    from afmforce.io import in_folder

    def refusal(path, curves=False):
        with pytest.raises(FileFormatError) as err:
            load(path)
        assert "\n" not in str(err.value) and in_folder(path) is curves
        return str(err.value)

    msg = refusal(_tiff(tmp_path / "ForceCurve_009.tiff", park_kind=2), curves=True)   # no spectroscopy tags
    assert "Park Systems TIFF has no spectroscopy header (TIFF tag 50438); damaged" in msg and "park-tiff" in msg
    assert "holds an image" in refusal(_tiff(tmp_path / "topo.tif", park_kind=0))
    msg = refusal(_tiff(tmp_path / "photo.tiff"))
    assert "a TIFF image" in msg and "not a force curve" in msg
    broken = tmp_path / "broken.tiff"
    broken.write_bytes(b"II*\x00\xff\xff\xff\x7f")  # IFD beyond the end: still one line
    assert "a TIFF image" in refusal(broken)


def test_other_endings_keep_the_list_of_endings(tmp_path):
    odd = tmp_path / "curve.xyz"
    odd.write_text("1 2 3")
    with pytest.raises(FileFormatError, match="unknown file type; supported endings: .*\\.jpk-force"):
        load(odd)


def test_cli_prints_one_error_line_and_fails(tmp_path, capsys):
    from afmforce.cli.main import main

    path = tmp_path / "curve.mdt"
    path.write_bytes(b"\x01\xb0\x04\x06" + b"\0" * 64)
    try:
        rc = main(["analyze", str(path)])
    except SystemExit as exc:
        rc = exc.code
    err = capsys.readouterr().err
    assert rc not in (0, None) and "Traceback" not in err
    lines = [line for line in err.splitlines() if "NT-MDT" in line]
    assert len(lines) == 1 and "ntmdt-txt" in lines[0]


def test_a_nanoscope_ramp_script_is_refused_not_cut_into_curves():
    """Bruker's own v9.70 ramp-script example (Apache-2.0: 18 scripted segments, 16 of them tip-bias
    sweeps at a held height): its 11,264 samples were once cut into 11 'force curves' of 512 + 512
    points (one analysis then crashed with an IndexError). Refused by name, with the segments."""
    path = UFF.parent / "bruker-nanoscope_v9.70_Bruker-example_ScriptTipBiasSweep.spm"
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert "\n" not in msg and "a NanoScope ramp-script file (18 scripted segments (ramps: Z, Sweep," in msg
    assert "'bruker-ascii'" in msg
