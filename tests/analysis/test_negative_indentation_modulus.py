"""No modulus from a soft contact whose deflection outruns its position (corpus5). The kind step already
withholds the indentation there ("physically impossible: after the contact point the deflection rises
... more than the position travels"), but the indentation fit still gave a Young's modulus from those
impossible indentations: E = 223.6 kPa on the corpus' Asylum force-map wave (uncalibrated InvOLS
100 nm/V; 20 nm paraboloid), and 55.35 kPa on an Asylum SMFS curve of 2025 (YY-Zhang1999/Gen_SMFS
``data/raw/Imagef1_0000.ibw``, no licence stated, not redistributed: InvOLS 179.86 nm/V where the
contact line gives 1.63 x less). The modulus is now not applicable, with the reason."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from afmforce.analysis.options import IndentationOptions
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.plausibility import IMPOSSIBLE
from afmforce.io import load

CORPUS = Path(__file__).resolve().parents[1] / "data" / "corpus"


def test_no_modulus_where_the_indentation_is_negative():
    from igor2 import binarywave

    path = CORPUS / "asylum-ibw_no-date_ForceMap.ibw"
    wave = binarywave.load(str(path))["wave"]
    defl, zsnsr = wave["wData"][:, 1].astype(float), wave["wData"][:, 2].astype(float)
    end = 224  # Indexes 0,224,...: the approach ends at sample 224 (wave note)
    assert defl[end] - defl[end - 60] > zsnsr[end] - zsnsr[end - 60] > 0  # read without afmforce
    r = analyze(load(path)[0], options=[IndentationOptions(model="hertz_paraboloid", tip_radius=20e-9)])
    assert r.contact_kind == "soft" and math.isnan(r.indentation)
    assert math.isnan(r.youngs_modulus) and math.isnan(r.youngs_modulus_low)
    why = r.not_applicable["indentation"]
    assert why.startswith(IMPOSSIBLE) and "negative indentation" in why and "suspect input: sensitivity" in why
    assert why in r.verdict


def test_a_soft_contact_with_a_positive_indentation_keeps_its_modulus():
    """The same options on a soft JPK cell curve whose indentation is positive: a modulus, no such reason."""
    path = CORPUS / "jpk-force_cellhesion_spot3.jpk-force"
    r = analyze(load(path)[0], options=[IndentationOptions(model="hertz_paraboloid", tip_radius=20e-9)])
    assert r.contact_kind == "soft" and r.indentation > 0
    assert np.isfinite(r.youngs_modulus) and r.youngs_modulus > 0
    assert "indentation" not in r.not_applicable
