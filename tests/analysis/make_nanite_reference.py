"""Write nanite_reference.json: nanite's fit_line_polynomial contact point on the shared soft curves.

Run from the repository root with the bench extra installed (``pip install -e .[bench]``)::

    python tests/analysis/make_nanite_reference.py

For each curve: the index nanite's preprocessing (compute_tip_position,
correct_force_offset, correct_tip_offset with method fit_line_polynomial) puts
the contact at, and the position z of that sample in afmforce's reading of the
same file (our readers keep afmformats' sample order for these files). The test
``test_contact_kinds.py`` compares afmforce's soft contact point with these
numbers in CI (which has no nanite) and with nanite itself where it is installed.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "real"
#: (folder, file, meta_override): soft curves nanite and afmforce both read.
CURVES = (
    ("tests/data", "jpk_cellhesion_spot3.jpk-force", {}),
    ("shared", "afmformats_jpk-fd_map2x2_extracted.jpk-force-map", {}),
    ("shared", "ForceMetric_X60_3_x4_0100.ibw", {}),
)


def nanite_contact(path: Path, meta: dict) -> list[int]:
    import afmformats
    import nanite

    out = []
    for dd in afmformats.load_data(path, meta_override=meta):
        idnt = nanite.Indentation(data=dd._raw_data, metadata=dd.metadata)
        idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset", "correct_tip_offset"],
                                 options={"correct_tip_offset": {"method": "fit_line_polynomial"}})
        out.append(int(np.argmin(np.abs(idnt["tip position"]))))
    return out


def main() -> None:
    import nanite

    from afmforce.io import load

    warnings.simplefilter("ignore")
    ref = {"_about": f"nanite {nanite.__version__} fit_line_polynomial contact point; written by "
                     "tests/analysis/make_nanite_reference.py", "curves": []}
    for folder, name, meta in CURVES:
        path = (ROOT / folder if folder != "shared" else SHARED) / name
        curves = load(path, meta_override=meta)
        for i, idx in enumerate(nanite_contact(path, meta)):
            c = curves[i]
            z = np.asarray(c.piezo_measured if c.piezo_measured is not None else c.piezo_nominal)
            ref["curves"].append({"folder": folder, "file": name, "curve": i, "meta": meta, "index": idx,
                                  "z": float(z[idx])})
    (Path(__file__).parent / "nanite_reference.json").write_text(json.dumps(ref, indent=1))


if __name__ == "__main__":
    main()
