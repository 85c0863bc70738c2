"""Write ``asylum-ardf_mfp3d-curve_2x2.ARDF``: an Asylum ARDF force map of 2 x 2 curves, the example of
the ``asylum-ardf`` reader (every registered format has a file in tests/data).

No public ARDF file under an MIT-compatible licence was found, so the map is built byte by byte
(``tests/io/_ardf_build.py``: plain ``struct``, from the public description of the layout) from real
data: the MFP-3D curve and wave note of ``corpus/asylum-ibw_no-date_ForceMap.ibw`` (itself exported
from an ARDF force map; pycroscopy/SciFiDatasets, MIT), z shifted by 20 nm per grid step.

Run from the repository root (rewrites the file byte for byte)::

    python tests/data/make_ardf_example.py
"""

from __future__ import annotations

import sys
from pathlib import Path

DATA = Path(__file__).resolve().parent
sys.path.insert(0, str(DATA.parent / "io"))

from _ardf_build import build_ardf  # noqa: E402

NAME = "asylum-ardf_mfp3d-curve_2x2.ARDF"

if __name__ == "__main__":
    info = build_ardf(DATA / NAME, nx=2, ny=2)
    print(f"wrote {NAME}: {info['size']} bytes, {len(info['curves'])} curves")
