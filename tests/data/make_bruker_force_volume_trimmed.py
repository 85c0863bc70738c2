"""Write ``bruker-nanoscope_force-volume_2x2_trimmed.spm``: four curves of the real NanoScope v9.2
force volume ``shared/data/real/bruker-nanoscope_force-volume_v9.2_Egel.spm`` (16 x 16 curves,
2.2 MB; DyNaMo-INSERM/PyFMlab_DyNaMo PyFMReader tests, MIT) as a 2 x 2 force volume (114 kB).

Kept byte for byte: the 80960-byte header (with its quirks: ``Bytes/pixel: 2`` over 4-byte data,
the malformed scaling line ``(\\Data length V/LSB)``), and the 2048 int32 samples of curves
0, 1, 23 and 255 (curve 23 made the fringe fit divide by zero). Changed, to describe the trimmed
file: the grid (``\\Samps/line: 16`` and ``\\Lines: 16`` of the ``\\*Ciao scan list`` -> 2), the
force channel's ``\\Data length`` (4 x 2048 x 4 bytes) and the height image (the 4 matching
pixels, after the curves). Run: ``python tests/data/make_bruker_force_volume_trimmed.py [SOURCE]``.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REAL = Path(os.environ.get("AFMFORCE_REAL_DATA") or HERE.parents[2] / "shared" / "data" / "real")
SOURCE = REAL / "bruker-nanoscope_force-volume_v9.2_Egel.spm"
TARGET = HERE / "bruker-nanoscope_force-volume_2x2_trimmed.spm"
KEEP = (0, 1, 23, 255)  # curves of the 16 x 16 grid, written as the 2 x 2 grid (row by row)
HEADER, PER, NX = 80960, 2048, 16


def main(source: Path = SOURCE) -> Path:
    data = source.read_bytes()
    head = data[:HEADER].decode("latin-1")
    curves = np.frombuffer(data, "<i4", count=256 * PER, offset=HEADER).reshape(256, PER)
    image_offset = HEADER + 256 * PER * 4
    image = np.frombuffer(data, "<i4", count=256, offset=image_offset)
    body = curves[list(KEEP)].tobytes()
    pixels = image[list(KEEP)].tobytes()
    scan = head.index("\\*Ciao scan list")
    end_scan = head.index("\\*", scan + 2)
    section = head[scan:end_scan].replace("\\Samps/line: 16\r", "\\Samps/line: 2\r").replace(
        "\\Lines: 16\r", "\\Lines: 2\r")
    head = head[:scan] + section + head[end_scan:]
    head = head.replace(f"\\Data length: {256 * PER * 4}\r", f"\\Data length: {len(body)}\r", 1)
    head = head.replace(f"\\Data offset: {image_offset}\r", f"\\Data offset: {HEADER + len(body)}\r", 1)
    img = head.index("\\*Ciao image list")
    tail = head[img:].replace("\\Data length: 1024\r", f"\\Data length: {len(pixels)}\r", 1)
    head = head[:img] + tail.replace("\\Samps/line: 16\r", "\\Samps/line: 2\r", 1).replace(
        "\\Number of lines: 16\r", "\\Number of lines: 2\r", 1)
    raw = head.rstrip("\0").encode("latin-1")
    assert len(raw) <= HEADER
    TARGET.write_bytes(raw + b"\0" * (HEADER - len(raw)) + body + pixels)
    return TARGET


if __name__ == "__main__":
    print(main(Path(sys.argv[1]) if len(sys.argv) > 1 else SOURCE))
