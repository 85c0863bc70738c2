"""Write ``bruker-nanoscope_v8.15_force-volume_64x64-scan_2x2-curves_trimmed.000``: four curves of the
real NanoScope 8.15 force volume ``Test.003`` (JSotres/FSAS-ForceSpectroscopyAnalysisSoftware-MatLab,
commit a319f85, ``SampleFiles/Test.003``, BSD-2-Clause, 574 kB: MultiMode, mica in air, 16 x 16
curves of 512 + 512 int16 samples under a 64 x 64 height image) as a 2 x 2 force volume (67 kB).

Its quirk, kept: the ``\\*Ciao scan list`` says ``Samps/line: 64`` and ``Lines: 64`` (the height
image's pixels, unchanged here with its 8192 bytes), while the curves lie on the grid of the force
volume's own image after them (``\\*Ciao image list``, Deflection Error, ``Samps/line: 16``,
``Number of lines: 16``). Kept byte for byte: the 40960-byte header but what follows, the height
image, and the 1024 int16 samples of curves 0, 15, 240 and 255 (the corners). Changed, to describe
the trimmed file: the force channel's ``\\Data length`` (4 x 2048 bytes), the force-volume image's
``\\Data offset``, ``\\Data length`` (its 4 matching pixels, after the curves), ``Samps/line`` and
``Number of lines`` (16 -> 2). Run: ``python tests/data/make_nanoscope_fv_image_grid_trimmed.py [SOURCE]``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REAL = Path(os.environ.get("AFMFORCE_REAL_DATA") or HERE.parents[2] / "shared" / "data" / "real")
SOURCE = REAL / "bruker-nanoscope_v8.15_FSAS_force-volume_Test.003"
TARGET = HERE / "bruker-nanoscope_v8.15_force-volume_64x64-scan_2x2-curves_trimmed.000"
KEEP = (0, 15, 240, 255)  # curves of the 16 x 16 grid, written as the 2 x 2 grid (row by row)
HEADER, CURVES, PER = 40960, 49152, 1024  # header bytes, the curves' offset, samples per curve (512 + 512)
IMAGE = CURVES + 256 * PER * 2            # the force volume's Deflection Error image (16 x 16 int16)


def main(source: Path = SOURCE) -> Path:
    data = source.read_bytes()
    head = data[:HEADER].decode("latin-1")
    assert "\\Samps/line: 64\r" in head and len(data) == IMAGE + 512, "not FSAS' Test.003"
    height = data[HEADER:CURVES]
    curves = np.frombuffer(data, "<i2", count=256 * PER, offset=CURVES).reshape(256, PER)
    image = np.frombuffer(data, "<i2", count=256, offset=IMAGE)
    body = curves[list(KEEP)].tobytes()
    pixels = image[list(KEEP)].tobytes()
    head = head.replace(f"\\Data length: {256 * PER * 2}\r", f"\\Data length: {len(body)}\r", 1)
    img = head.index(f"\\Data offset: {IMAGE}\r")
    tail = (head[img:].replace(f"\\Data offset: {IMAGE}\r", f"\\Data offset: {CURVES + len(body)}\r", 1)
            .replace("\\Data length: 512\r", f"\\Data length: {len(pixels)}\r", 1)
            .replace("\\Samps/line: 16\r", "\\Samps/line: 2\r", 1)
            .replace("\\Number of lines: 16\r", "\\Number of lines: 2\r", 1))
    head = head[:img] + tail
    raw = head.rstrip("\0").encode("latin-1")
    assert len(raw) <= HEADER
    TARGET.write_bytes(raw + b"\0" * (HEADER - len(raw)) + height + body + pixels)
    return TARGET


if __name__ == "__main__":
    print(main(Path(sys.argv[1]) if len(sys.argv) > 1 else SOURCE))
