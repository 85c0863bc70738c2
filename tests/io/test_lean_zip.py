"""The zip directory read into arrays (afmforce.io._lean_zip), against the standard library's zipfile:
the same members with the same bytes for every JPK file of the corpus, a ZIP64 archive (more than
65,535 members, as a 128 x 128 QI file has), and a damaged member refused."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from afmforce.errors import FileFormatError
from afmforce.io._lean_zip import LeanZip, index_group
from afmforce.io.map_curves import open_map

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"


def _members(lean: LeanZip) -> dict[str, int]:
    out = dict(lean.named)
    for i, group in lean.groups.items():
        out.update({f"index/{i}/{rest}": entry for rest, entry in group.items()})
    return out


@pytest.mark.parametrize("path", sorted(CORPUS.glob("*.jpk-*")), ids=lambda p: p.name)
def test_every_member_as_zipfile_reads_it(path):
    lean = LeanZip(path, index_group)
    try:
        with zipfile.ZipFile(path) as arc:
            members = _members(lean)
            assert sorted(members) == sorted(arc.namelist())
            for name, entry in members.items():
                assert lean.read(entry, name) == arc.read(name), name
    finally:
        lean.close()


def test_zip64_directory(tmp_path):
    path = tmp_path / "many.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as arc:
        for i in range(70_000):  # > 0xFFFF members: zipfile writes the ZIP64 end records
            arc.writestr(f"index/{i}/x", str(i))
        arc.writestr("header.properties", b"a=1\n")
    lean = LeanZip(path, index_group)
    try:
        assert len(lean.groups) == 70_000 and list(lean.named) == ["header.properties"]
        assert lean.read(lean.groups[69_999]["x"]) == b"69999"
    finally:
        lean.close()


def test_a_damaged_member_is_named(tmp_path):
    from afmforce.instrument.soft_map import SoftMapConfig, write_soft_map

    path = write_soft_map(SoftMapConfig(nx=2, ny=1), tmp_path / "m.jpk-qi-data", format="jpk-qi")
    with zipfile.ZipFile(path) as arc:
        info = arc.getinfo("index/1/segments/0/channels/vDeflection.dat")
    data = bytearray(path.read_bytes())
    start = info.header_offset + 30 + len(info.filename) + len(info.extra)
    data[start + 5] ^= 0xFF  # one byte of the compressed samples
    path.write_bytes(bytes(data))
    reader = open_map(path, "jpk-force")
    try:
        assert reader.read(0).deflection_signal.size == 600
        with pytest.raises(FileFormatError, match=r"#1: damaged JPK archive"):
            reader.read(1)
    finally:
        reader.close()


def test_a_damaged_directory_is_refused_before_any_large_read(tmp_path):
    """End records pointing beyond the file, or announcing more members than fit, are not read."""
    import struct

    path = CORPUS / "jpk-qi-data_2020.02.07.jpk-qi-data"
    data = bytearray(path.read_bytes())
    at = data.rfind(b"PK\x05\x06")
    for field, value in ((12, 0x7FFFFFFF), (10, 0xFFFE)):  # directory size; member count
        bad = bytearray(data)
        struct.pack_into("<I" if field == 12 else "<H", bad, at + field, value)
        broken = tmp_path / f"bad{field}.jpk-qi-data"
        broken.write_bytes(bytes(bad))
        with pytest.raises(zipfile.BadZipFile):
            LeanZip(broken, index_group)
