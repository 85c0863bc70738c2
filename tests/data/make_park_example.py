"""Write ``park-tiff_synthetic_2-spectra.tiff``: a **SYNTHETIC** Park Systems spectroscopy TIFF of two
spectra, the example of the ``park-tiff`` reader (every registered format has a file in tests/data).

The only public Park force-curve file found (nanoAFMr's ``ForceCurve_009.tiff``) is AGPL, so it is kept
out of this folder; this one is built with plain ``struct`` from Park's tag layout by
``tests/io/_park_build.py`` from arrays chosen there (0.35 N/m, 40 nm/V, 0.5 um/s, 500 Hz).

Run from the repository root (rewrites the file byte for byte)::

    python tests/data/make_park_example.py
"""

from __future__ import annotations

import sys
from pathlib import Path

DATA = Path(__file__).resolve().parent
sys.path.insert(0, str(DATA.parent / "io"))

from _park_build import write_park  # noqa: E402

NAME = "park-tiff_synthetic_2-spectra.tiff"

if __name__ == "__main__":
    path = write_park(DATA / NAME, points=2)
    print(f"wrote {NAME}: {path.stat().st_size} bytes")
