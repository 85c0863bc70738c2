"""Write nanite_modulus_reference.json: nanite's Young's modulus on the shared soft curves.

Run from the repository root with the bench extra installed (``pip install -e .[bench]``)::

    python tests/analysis/make_nanite_modulus_reference.py

Each curve is read and calibrated by afmforce (its reader, drift line and spring constant:
``analyze(curve, steps=["force"])``), then handed to nanite as force and height; nanite's
preprocessing (compute_tip_position, correct_force_offset, correct_tip_offset with
fit_line_polynomial) and its fit (whole approach, ``weight_cp=0``, the model's geometry and
nu = 0.5) give E and the contact point. So the comparison isolates the fit: same data, same
model, same geometry and range. ``test_indentation_nanite.py`` compares afmforce's indentation
step with these numbers (and with nanite itself where it is installed).
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "real"
_NOCAL = {"spring_constant": 0.1, "sensitivity": 50e-9}
#: (folder, file, meta_override): soft curves.
FILES = (
    ("tests/data", "jpk_cellhesion_spot3.jpk-force", {}),
    ("tests/data", "afmforce-map_jpk-map2x2.h5", {}),
    ("tests/data", "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw", {}),
    ("tests/data", "bruker-nanoscope_PyFMlab_Egel4_00025.spm", {}),
    ("tests/data", "afmformats_jpk-sr_cell1-0008.jpk-force", {}),
    ("tests/data", "ntmdt_gel-in-water.txt", _NOCAL),
    ("tests/data", "afmformats_afm-workshop-fd_single_2018-08-01.csv", _NOCAL),
    ("tests/data", "chiaro-txt_AEBP1_Indentation_002_thinned.txt", {}),
)
#: (afmforce model, nanite model, geometry in SI, nanite's geometry parameters)
MODELS = (
    ("hertz_paraboloid", "hertz_para", {"tip_radius": 5e-6}, {"R": 5e-6}),
    ("sneddon_sphere", "sneddon_spher_approx", {"tip_radius": 20e-6}, {"R": 20e-6}),  # delta < R on all
    ("hertz_cone", "hertz_cone", {"half_angle": math.radians(20)}, {"alpha": 20.0}),
    ("bilodeau_pyramid3", "hertz_pyr3s", {"half_angle": math.radians(15)}, {"alpha": 15.0}),
)


def nanite_fit(curve, nanite_model: str, geometry: dict) -> tuple[float, float] | None:
    """nanite's (E [Pa], contact point [m] of its tip position) on afmforce's calibrated curve."""
    import nanite

    from afmforce.analysis.pipeline import analyze

    r = analyze(curve, steps=["force"])
    seg = np.asarray(curve.segment)
    keep = seg <= 1
    z = np.asarray(curve.piezo_measured if curve.piezo_measured is not None else curve.piezo_nominal)
    data = {"force": (r.deflection * r.spring_constant)[keep], "height (measured)": -z[keep],
            "segment": seg[keep].astype(bool), "time": np.asarray(curve.time)[keep]}
    md = {"spring constant": r.spring_constant, "sensitivity": 1.0, "path": "afmforce", "enum": 0,
          "imaging mode": "force-distance", "duration": 1.0, "point count": int(keep.sum())}
    idnt = nanite.Indentation(data=data, metadata=md)
    idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset", "correct_tip_offset"],
                             options={"correct_tip_offset": {"method": "fit_line_polynomial"}})
    p = idnt.get_initial_fit_parameters(model_key=nanite_model)
    for k, v in geometry.items():
        p[k].set(value=v)
    p["nu"].set(value=0.5)
    idnt.fit_model(model_key=nanite_model, params_initial=p, weight_cp=0, range_x=(0, 0), range_type="absolute",
                   segment="approach")
    if not idnt.fit_properties.get("success"):
        return None
    fitted = idnt.fit_properties["params_fitted"]
    return float(fitted["E"].value), float(fitted["contact_point"].value)


def main() -> None:
    import nanite

    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load

    warnings.simplefilter("ignore")
    ref = {"_about": f"nanite {nanite.__version__} Young's modulus on afmforce's calibrated curves; written by "
                     "tests/analysis/make_nanite_modulus_reference.py", "curves": []}
    for folder, name, meta in FILES:
        for i, curve in enumerate(load(ROOT / folder / name, meta_override=meta)):
            if analyze(curve, steps=["kind"]).contact_kind != "soft":
                continue
            for ours, theirs, geom, ngeom in MODELS:
                got = nanite_fit(curve, theirs, ngeom)
                if got is None:
                    continue
                ref["curves"].append({"folder": folder, "file": name, "curve": i, "meta": meta, "model": ours,
                                      "nanite_model": theirs, "geometry": geom, "youngs_modulus": got[0],
                                      "contact_point": got[1]})
                print(name, i, ours, f"{got[0]:.4g} Pa")
    (Path(__file__).parent / "nanite_modulus_reference.json").write_text(json.dumps(ref, indent=1))


if __name__ == "__main__":
    main()
