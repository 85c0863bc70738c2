"""Image files a user may give by mistake are refused in one line naming what they hold (public files tried
after the corpus: tests/data/README.md, "Files tried").

* An Asylum image saved as .ibw (pycroscopy/SciFiDatasets' PFM images, 256 x 256 x 4 and x 5, MIT) was
  refused as "afmforce cannot read it (KeyError: 'NumPtsPerSec')": afmformats' words, not the cause.
* A Gwyddion .gwy (SciFiDatasets' `PTO_110_Virgin0001.gwy`) was "unknown file type".
"""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from afmforce.errors import FileFormatError
from afmforce.io import is_supported, load

from realdata import SHARED  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

DATA = Path(__file__).resolve().parents[1] / "data"


def _reshaped(tmp_path: Path, ndim: tuple[int, int, int]) -> Path:
    """``asylum-mfp3d_SiN-tip_air.ibw`` (2016 x 3 samples: Raw, Defl, ZSnsr) with its ``nDim`` set to
    ``ndim`` (the same 6048 values): what an image's header says (rows, columns, layers)."""
    raw = bytearray((DATA / "asylum-mfp3d_SiN-tip_air.ibw").read_bytes())
    order = "<" if struct.unpack("<h", raw[:2])[0] in (1, 2, 3, 5) else ">"
    assert struct.unpack(order + "4i", raw[64 + 68:64 + 84]) == (2016, 3, 0, 0)
    raw[64 + 68:64 + 84] = struct.pack(order + "4i", *ndim, 0)
    path = tmp_path / "image.ibw"
    path.write_bytes(bytes(raw))
    return path


@pytest.mark.parametrize("ndim", [(24, 28, 9), (48, 126, 0)])
def test_an_asylum_image_wave_is_refused_as_an_image(tmp_path, ndim):
    with pytest.raises(FileFormatError) as err:
        load(_reshaped(tmp_path, ndim))
    msg = str(err.value)
    layers = max(ndim[2], 1)
    assert f"holds an image ({ndim[0]} x {ndim[1]} pixels, {layers} channel" in msg
    assert "not a force curve" in msg and "\n" not in msg and "NumPtsPerSec" not in msg


def test_a_curve_wave_is_still_read(tmp_path):
    (curve,) = load(_reshaped(tmp_path, (2016, 3, 0)))    # unchanged shape: the curve as before
    assert curve.metadata["spring_constant"] == pytest.approx(1.1841, rel=1e-4)


@pytest.mark.parametrize("name, channels", [
    ("IgorIBWReader_ImageStack_BTFO_DSO.ibw", "HeightRetrace, AmplitudeRetrace"),
    ("IgorIBWReader_P0089OP0027.ibw", "HeightRetrace, AmplitudeRetrace"),
])
def test_scifidatasets_pfm_images(name, channels):
    path = SHARED / name
    if not path.is_file():
        pytest.skip(f"{name} not in {SHARED}: pycroscopy/SciFiDatasets data/microscopy/spm/afm/ (MIT, 1.1-1.4 MB)")
    with pytest.raises(FileFormatError, match=f"256 x 256 pixels, [45] channels: {channels}"):
        load(path)


def test_a_gwyddion_file_is_named(tmp_path):
    path = tmp_path / "PTO_110_Virgin0001.gwy"
    path.write_bytes(b"GWYP" + b"\0" * 64)       # Gwyddion's magic
    with pytest.raises(FileFormatError) as err:
        load(path)
    msg = str(err.value)
    assert "Gwyddion file (.gwy)" in msg and "afmforce formats" in msg and "unknown file type" not in msg
    assert not is_supported(path)
