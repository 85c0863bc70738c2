"""The indentation step's Young's modulus against nanite's on every shared soft curve (issue 26, item 5).

nanite's numbers are stored (``nanite_modulus_reference.json``, written by
``make_nanite_modulus_reference.py`` from the same calibrated curves, same model, geometry, nu and
range: the whole approach, unweighted), so the test runs without nanite; where nanite is
installed one curve is also fitted by nanite here.
"""

from __future__ import annotations

import json
import math
import warnings
from functools import lru_cache
from pathlib import Path

import pytest

from afmforce.analysis.options import IndentationOptions
from afmforce.analysis.pipeline import analyze
from afmforce.io import load

HERE = Path(__file__).parent
ROOT = HERE.parents[1]
REF = json.loads((HERE / "nanite_modulus_reference.json").read_text())["curves"]


@lru_cache(maxsize=None)
def _curves(folder: str, file: str, meta: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load(ROOT / folder / file, meta_override=json.loads(meta))


def _ours(entry):
    curve = _curves(entry["folder"], entry["file"], json.dumps(entry["meta"]))[entry["curve"]]
    opts = IndentationOptions(model=entry["model"], poisson=0.5, **entry["geometry"])
    return analyze(curve, steps=["indentation"], options=[opts])


def test_reference_covers_the_soft_files_and_models():
    files = {e["file"] for e in REF}
    assert len(files) >= 8 and len(REF) >= 40
    assert {e["model"] for e in REF} == {"hertz_paraboloid", "sneddon_sphere", "hertz_cone", "bilodeau_pyramid3"}


@pytest.mark.parametrize("entry", REF, ids=lambda e: f"{e['file']}#{e['curve']}-{e['model']}")
def test_modulus_within_ten_percent_of_nanite(entry):
    res = _ours(entry)
    assert "indentation" not in res.not_applicable, res.not_applicable
    ratio = res.youngs_modulus / entry["youngs_modulus"]
    assert abs(ratio - 1) < 0.10, f"E {res.youngs_modulus:.4g} Pa vs nanite {entry['youngs_modulus']:.4g} Pa"
    lo, hi = res.youngs_modulus_low, res.youngs_modulus_high
    assert lo < res.youngs_modulus < hi and res.youngs_modulus_se > 0


def test_nanite_computed_here_agrees():
    pytest.importorskip("nanite", reason="nanite (bench extra) not installed: the stored numbers are checked instead")
    from make_nanite_modulus_reference import nanite_fit  # noqa: E402  (tests/analysis on sys.path)

    entry = next(e for e in REF if e["file"].startswith("bruker") and e["model"] == "hertz_paraboloid")
    curve = _curves(entry["folder"], entry["file"], json.dumps(entry["meta"]))[0]
    E, _ = nanite_fit(curve, "hertz_para", {"R": 5e-6})
    assert math.isclose(E, entry["youngs_modulus"], rel_tol=1e-3)
    assert abs(_ours(entry).youngs_modulus / E - 1) < 0.10


def test_hard_contact_is_skipped_with_the_reason():
    curve = load(ROOT / "tests/data/asylum-mfp3d_SiN-tip_air.ibw")[0]
    res = analyze(curve, steps=["indentation"], options=[IndentationOptions(tip_radius=20e-9)])
    assert "hard contact" in res.not_applicable["indentation"] and math.isnan(res.youngs_modulus)


def test_missing_geometry_is_skipped_naming_the_flag():
    entry = REF[0]
    curve = _curves(entry["folder"], entry["file"], json.dumps(entry["meta"]))[0]
    res = analyze(curve, steps=["indentation"], options=[IndentationOptions(model="hertz_cone")])
    assert "`half_angle`" in res.not_applicable["indentation"]   # the key; the CLI renders --half-angle
