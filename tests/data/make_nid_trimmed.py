"""Write ``nanosurf-nid_spectroscopy-map_2x2_trimmed.nid``: four curves of the real Nanosurf FlexAFM
spectroscopy map ``shared/data/real/nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid`` (10 x 10 curves,
5.5 MB; NSFopen 2.2.4's ``NSFopen/example/Force_Spectroscopy/spectroscopy.nid``, Nanosurf, MIT) as a
2 x 2 map (about 210 kB).

Kept byte for byte: every header line but those below (the lever, scan head and spectroscopy
parameters, the 100 kB video configuration, the image sections' text), and the int32 samples of
the curves 0, 9, 90 and 99 (the map's corners) of the four spectroscopy blocks (``Spec forward`` and
``Spec backward``, ``Deflection`` and ``Z-Axis Sensor``). Changed, to describe the trimmed file: the
``[DataSet]`` group list (the 16 other groups, the indentation results and the two images, dropped
with their sections and data), ``Lines`` and ``CurLine`` of the kept blocks, their ``LineDim<i>``
entries (those of the kept rows, renumbered 0-3) and the map table's grid (``;10;10;`` -> ``;2;2;``).
The map runs back and forth, so the corners in file order 0, 9, 90, 99 are the 2 x 2 grid's
(0, 0), (1, 0), (1, 1), (0, 1) in its own back-and-forth order.
Run: ``python tests/data/make_nid_trimmed.py [SOURCE]``.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REAL = Path(os.environ.get("AFMFORCE_REAL_DATA") or HERE.parents[2] / "shared" / "data" / "real")
SOURCE = REAL / "nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid"
TARGET = HERE / "nanosurf-nid_spectroscopy-map_2x2_trimmed.nid"
KEEP = (0, 9, 90, 99)
BLOCKS = ("DataSet-0:0", "DataSet-0:7", "DataSet-1:0", "DataSet-1:7")
POINTS, LINES = 1024, 100


def main(source: Path = SOURCE) -> Path:
    data = source.read_bytes()
    end = data.index(b"\r\n#!")
    head = data[:end].decode("latin-1")      # latin-1: every byte back as it was
    body = np.frombuffer(data, "<i4", count=len(BLOCKS) * LINES * POINTS, offset=end + 4).reshape(
        len(BLOCKS), LINES, POINTS)  # the data start with the four blocks kept, in this order
    parts = re.split(r"(?m)^(?=\[)", head)
    out = []
    for part in parts:
        name = part[1:part.index("]")] if part.startswith("[") else ""
        if name.startswith("DataSet-") and ":" in name and name not in BLOCKS:
            continue
        if name == "DataSet":
            lines = part.split("\r\n")
            keep = [ln for ln in lines if not re.match(r"Gr([2-9]|1\d)-", ln)]
            part = "\r\n".join("GroupCount=2" if ln.startswith("GroupCount=") else ln for ln in keep)
        elif name in BLOCKS:
            lines = []
            for ln in part.split("\r\n"):
                m = re.match(r"LineDim(\d+)(\w+)=", ln)
                if m:
                    row = int(m.group(1))
                    if row not in KEEP:
                        continue
                    ln = f"LineDim{KEEP.index(row)}{m.group(2)}={ln.split('=', 1)[1]}"
                elif ln.startswith("Lines="):
                    ln = f"Lines={len(KEEP)}"
                elif ln.startswith("CurLine="):
                    ln = f"CurLine={len(KEEP) - 1}"
                lines.append(ln)
            part = "\r\n".join(lines)
        elif name == "DataSet\\SpecInfos\\SpecMapTable":
            part = part.replace(";10;10;", ";2;2;")
        out.append(part)
    text = "".join(out)
    samples = body[:len(BLOCKS)][:, list(KEEP), :]
    TARGET.write_bytes(text.encode("latin-1") + b"\r\n#!" + samples.astype("<i4").tobytes())
    return TARGET


if __name__ == "__main__":
    print(main(Path(sys.argv[1]) if len(sys.argv) > 1 else SOURCE))
