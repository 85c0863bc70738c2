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
#: Soft curves afmformats cannot read (or splits differently): nanite's contact-point function is applied
#: to afmforce's reading (approach segment, time order, deflection signal), without nanite's preprocessing.
#: ``ambiguous``: an onset no method pins down (nanite's own point moves by ~5 um when its input is
#: block-averaged); the test asserts the warning there instead of the agreement.
CURVES_ARRAYS = (
    ("tests/data", "bruker-nanoscope_PyFMlab_Egel4_00025.spm", {}, False),
    ("shared", "afmformats_jpk-sr_cell1-0008.jpk-force", {}, False),
    ("shared", "jpkfile_force-save-2016.06.15-13.17.08.jpk-force", {}, True),
    # no calibration in these files: any k and sensitivity do (the contact point is in position)
    ("shared", "ntmdt_gel-in-water.txt", {"spring_constant": 0.1, "sensitivity": 50e-9}, False),
    ("shared", "afmformats_afm-workshop-fd_single_2018-08-01.csv", {"spring_constant": 0.1, "sensitivity": 50e-9},
     False),
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


def nanite_contact_on_arrays(curve, method: str = "fit_line_polynomial") -> tuple[int, float]:
    """nanite's contact point (``method``) on the approach of an afmforce curve: (sample index, z there [m])."""
    from nanite import poc

    idx = np.flatnonzero(np.asarray(curve.segment) == 0)
    d = np.asarray(curve.deflection_signal)[idx]
    z = np.asarray(curve.piezo_measured if curve.piezo_measured is not None else curve.piezo_nominal)[idx]
    j = int(poc.compute_poc(d, method))
    return int(idx[j]), float(z[j])


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
                                  "z": float(z[idx]), "via": "afmformats+nanite preprocessing"})
    for folder, name, meta, ambiguous in CURVES_ARRAYS:
        path = (ROOT / folder if folder != "shared" else SHARED) / name
        curve = load(path, meta_override=meta)[0]
        idx, z = nanite_contact_on_arrays(curve)
        entry = {"folder": folder, "file": name, "curve": 0, "meta": meta, "index": idx, "z": z,
                 "via": "afmforce reading, nanite.poc", "ambiguous": ambiguous}
        if ambiguous:  # a slow rise before a steep contact: where nanite's gradient-based methods put the onset
            i2, z2 = nanite_contact_on_arrays(curve, "deviation_from_baseline")
            entry["steep"] = {"method": "deviation_from_baseline", "index": i2, "z": z2,
                              "also": {"gradient_zero_crossing": nanite_contact_on_arrays(curve, "gradient_zero_crossing")[1]}}
        ref["curves"].append(entry)
    (Path(__file__).parent / "nanite_reference.json").write_text(json.dumps(ref, indent=1))


if __name__ == "__main__":
    main()
