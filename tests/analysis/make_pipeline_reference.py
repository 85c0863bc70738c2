"""Store the full ``analyze`` JSON (with the per-sample arrays) of soft real curves (issue 35, item 2).

Run ONCE with the code before the pipeline's speed work (main at 8787912) and commit the output,
``pipeline_reference.json.gz``; ``test_pipeline_reference.py`` then checks that the faster pipeline
gives every number within 1e-9 relative of it::

    PYTHONPATH=src python tests/analysis/make_pipeline_reference.py
"""

from __future__ import annotations

import dataclasses
import gzip
import json
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "data"
OUT = HERE / "pipeline_reference.json.gz"

# (file, curve indices, steps or None for the default pipeline, options as (name, kwargs))
CASES = [
    ("jpk_cellhesion_spot3.jpk-force", [0], None, None),
    ("bruker-nanoscope_PyFMlab_Egel4_00025.spm", [0], None, None),
    ("afmforce-map_jpk-map2x2.h5", [0, 1, 2, 3], None, None),
    ("afmformats_jpk-sr_cell1-0008.jpk-force", [0], None, None),
    ("ntmdt_gel-in-water.txt", [0], None, None),
    ("afmformats_afm-workshop-fd_single_2018-08-01.csv", [0], None, None),
    ("chiaro-txt_AEBP1_Indentation_002_thinned.txt", [0], None, None),
    ("corpus/jpk-force-map_HeLa_4x4.jpk-force-map", [0, 5, 10], None, None),
    ("corpus/bruker-nanoscope_force-volume_v9.2_Egel2_00023.spm", [0, 7], None, None),
    ("bruker-nanoscope_PyFMlab_Egel4_00025.spm", [0], ["indentation", "adhesion"], ("IndentationOptions", {"tip_radius": 5e-6, "poisson": 0.5})),
    ("afmforce-map_jpk-map2x2.h5", [2], ["indentation", "adhesion"], ("IndentationOptions", {"tip_radius": 5e-6, "poisson": 0.5})),
]


#: files whose reader now passes the header's tip radius (corpus3: the Chiaro reader), so the
#: indentation step fits a modulus where the stored reference (no radius then) has none
WITHOUT_RADIUS = {"chiaro-txt_AEBP1_Indentation_002_thinned.txt"}


def thinned(curve, n: int = 300):
    """A QI-like curve: ``n`` samples per run (as benchmarks/bench_contact.py)."""
    seg = np.asarray(curve.segment)
    idx = np.concatenate([np.flatnonzero(seg == s)[np.linspace(0, (seg == s).sum() - 1, n).astype(int)]
                          for s in (0, 1)])
    kw = {f.name: getattr(curve, f.name)[idx] for f in dataclasses.fields(curve)
          if isinstance(getattr(curve, f.name), np.ndarray) and getattr(curve, f.name).shape == seg.shape}
    return dataclasses.replace(curve, **kw)


def results():
    """(key, analyze JSON dict with arrays) of every case, computed by the code on PYTHONPATH."""
    from afmforce.analysis import options as O
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load

    overrides = json.loads((DATA / "meta_override.json").read_text())
    for name, indices, steps, opt in CASES:
        curves = load(DATA / name, meta_override=overrides.get(name))
        options = [getattr(O, opt[0])(**opt[1])] if opt else None
        if name in WITHOUT_RADIUS:  # as stored: the reader did not pass the file's tip radius then
            curves = [dataclasses.replace(c, metadata={k: v for k, v in c.metadata.items() if k != "radius"})
                      for c in curves]
        for i in indices:
            for label, c in (("", curves[i]), ("thinned300", thinned(curves[i]))):
                key = f"{name}#{i}{'/' + label if label else ''}{'/' + ','.join(steps) if steps else ''}"
                try:
                    d = analyze(c, steps=steps, options=options).to_dict(arrays=True)
                except Exception as exc:  # a refusal is an answer too
                    d = {"error": f"{type(exc).__name__}: {exc}"}
                yield key, json.loads(json.dumps(d, allow_nan=False, default=str))


def main() -> None:
    warnings.simplefilter("ignore")
    ref = dict(results())
    OUT.write_bytes(gzip.compress((json.dumps(ref, sort_keys=True) + "\n").encode(), mtime=0))
    print(f"wrote {OUT} ({len(ref)} results, {OUT.stat().st_size / 1e6:.2f} MB)")


if __name__ == "__main__":
    main()
