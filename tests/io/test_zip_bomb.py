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



def test_an_hdf5_dataset_declaring_more_values_than_a_curve_holds_is_refused(tmp_path):
    """afmforce's HDF5 format: a chunked, compressed (or never written) dataset declared with 10 M + 1
    values is a file of a few kB; before, the reader allocated and filled it (80 MB here, 8 GB for
    1e9 values) before anything looked at its size."""
    import shutil

    h5py = pytest.importorskip("h5py")
    from afmforce.io import load
    from afmforce.limits import MAX_SAMPLES

    path = tmp_path / "bomb.h5"
    shutil.copy(Path(__file__).parents[1] / "data" / "afmforce-hdf5_virtual-afm.h5", path)
    with h5py.File(path, "r+") as f:
        group = f if "time" in f else next(g for g in f.values() if "time" in g)
        del group["time"]
        group.create_dataset("time", shape=(MAX_SAMPLES + 1,), chunks=(1 << 16,), compression="gzip")
    assert path.stat().st_size < 2_000_000
    with pytest.raises(FileFormatError, match=r"dataset /time declares 10,000,001 values, more than a force curve"):
        load(path)
