"""A JPK archive whose member unpacks to more than a force curve holds (a zip bomb) is refused
from its declared size, before any member is unpacked: bounded memory for ``afmforce analyze``
and for ``afmforce serve``'s uploads (its analysis reads them with the same ``load``)."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from afmforce.errors import FileFormatError
from afmforce.limits import MAX_MEMBER_BYTES

CELL = Path(__file__).parents[1] / "data" / "jpk_cellhesion_spot3.jpk-force"


@pytest.fixture(scope="module")
def bomb(tmp_path_factory) -> Path:
    """The cell curve with its approach's deflection member replaced by zeros, 8 bytes more than
    the cap (~80 kB stored). Before: 1.5 MB stored, 800 MB unpacked, took 6 GB and minutes."""
    path = tmp_path_factory.mktemp("bomb") / "bomb.jpk-force"
    with zipfile.ZipFile(CELL) as src, zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        for info in src.infolist():
            if info.filename == "segments/0/channels/vDeflection.dat":
                with z.open(info.filename, "w", force_zip64=True) as fh:
                    block = bytes(1 << 20)
                    for _ in range(MAX_MEMBER_BYTES // len(block)):
                        fh.write(block)
                    fh.write(bytes(MAX_MEMBER_BYTES % len(block) + 8))
            else:
                z.writestr(info, src.read(info.filename))
    return path


@pytest.mark.parametrize("fmt", [None, "jpk-force", "jpk-zip"])
def test_every_jpk_reader_refuses_it_before_unpacking(bomb, fmt):
    from afmforce.io import load

    with pytest.raises(FileFormatError, match=r"vDeflection\.dat would unpack to 80,000,008 bytes .* zip bomb"):
        load(bomb, format=fmt)


def test_the_lean_directory_reader_never_unpacks_past_the_cap(bomb):
    from afmforce.io._lean_zip import LeanZip, index_group

    lean = LeanZip(bomb, index_group)
    try:
        with pytest.raises(zipfile.BadZipFile, match="zip bomb"):
            lean.read(lean.named["segments/0/channels/vDeflection.dat"], "vDeflection.dat")
    finally:
        lean.close()

