"""``RawCurve``'s position channel and deflection unit conversion (issue 31, item 5): one method
each instead of a copy in every module.

On every file of the real-file corpus the factors equal the ones computed here from the header
values read WITHOUT afmforce (``corpus.json``: the files' own header text, igor2, zipfile); and
the numbers are those of the code the methods replace: the analysis pipeline's choice of
channel (``analysis.state.prepare``) and the calibration's file factor
(``analysis.compliance._metadata_factor``), compared exactly.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import AnalysisError, FileFormatError
from afmforce.io import load
from afmforce.io.curve import RawCurve

DATA = Path(__file__).resolve().parents[1] / "data"
CORPUS = DATA / "corpus"
TABLE = json.loads((CORPUS / "corpus.json").read_text())
READ = sorted(n for n, e in TABLE.items() if not e.get("expect", {}).get("read", "").startswith("issue 32"))
OVERRIDES = json.loads((DATA / "meta_override.json").read_text())


def _expected(unit: str, k: float | None, s: float | None) -> tuple[float, float]:
    """(deflection per signal unit, force per signal unit) from the header's k [N/m] and InvOLS [m/V]."""
    k, s = (float(k) if k else math.nan), (float(s) if s else math.nan)
    return {"V": (s, s * k), "m": (1.0, k), "N": (1.0 / k, 1.0)}[unit]


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=1e-12)


@pytest.mark.parametrize("name", READ)
def test_factors_are_the_header_s_calibration(name):
    head, given = TABLE[name]["header"], TABLE[name].get("given", {})
    k = head["spring_constant"] if head["spring_constant"] is not None else given.get("spring_constant")
    s = head["sensitivity"] if head["sensitivity"] is not None else given.get("sensitivity")
    curves = load(CORPUS / name, meta_override=given or None)
    assert curves
    for curve in curves:
        defl, force = _expected(curve.deflection_unit, k, s)
        assert _same(curve.deflection_factor(), defl), (curve.deflection_unit, curve.deflection_factor(), defl)
        assert _same(curve.force_factor(), force), (curve.deflection_unit, curve.force_factor(), force)


def _files():
    out = [pytest.param(CORPUS / n, TABLE[n].get("given"), id=n) for n in READ]
    for p in sorted(DATA.iterdir()):
        if p.is_file() and not p.name.startswith(".") and p.suffix not in (".md", ".json", ".py", ".tnd", ".psd"):
            out.append(pytest.param(p, OVERRIDES.get(p.name), id=p.name))
    return out


@pytest.mark.parametrize("path, given", _files())
def test_numbers_are_those_of_the_code_they_replace(path, given):
    from afmforce.analysis.compliance import _metadata_factor
    from afmforce.analysis.state import prepare

    try:
        curves = load(path, meta_override=given or None)
    except FileFormatError as exc:     # a file tests/data holds for a refusal
        pytest.skip(f"not read: {exc}")
    for curve in curves:
        assert curve.position_channel() == ("measured" if curve.piezo_measured is not None else "nominal")
        assert curve.position() is curve.piezo_measured or curve.position() is curve.piezo_nominal or \
            np.shares_memory(curve.position(), curve.piezo_measured if curve.piezo_measured is not None
                             else curve.piezo_nominal)
        f_old = _metadata_factor(curve.deflection_unit, curve.metadata or {})
        assert _same(curve.deflection_factor(), f_old)
        md = curve.metadata
        kk, ss = md.get("spring_constant") or math.nan, md.get("sensitivity") or math.nan
        old_force = {"N": 1.0, "m": kk, "V": kk * ss}[curve.deflection_unit]   # the pipeline's to_force
        assert _same(curve.force_factor(), old_force)
        for channel in ("auto", "nominal") + (("measured",) if curve.piezo_measured is not None else ()):
            try:
                st = prepare(curve, channel)
            except AnalysisError:      # a one-run export: the analysis refuses it, the choice is the same
                continue
            assert st.channel == curve.position_channel(channel)
            np.testing.assert_array_equal(st.z, curve.position(channel))


def _curve(measured: bool, unit: str, **md) -> RawCurve:
    n = 6
    z = np.linspace(0.0, 1e-7, n)
    return RawCurve(time=np.arange(n, dtype=float), piezo_nominal=z, deflection_signal=np.zeros(n),
                    segment=np.array([0, 0, 0, 1, 1, 1], np.int8), piezo_measured=z * 1.01 if measured else None,
                    metadata=md, deflection_unit=unit)


def test_channel_requests_and_refusals():
    both, nominal = _curve(True, "V"), _curve(False, "V")
    assert both.position_channel() == "measured" and both.position("nominal") is both.piezo_nominal
    np.testing.assert_array_equal(both.position(), both.piezo_measured)
    assert nominal.position_channel("auto") == "nominal"
    with pytest.raises(AnalysisError, match="no measured position channel"):
        nominal.position("measured")
    with pytest.raises(AnalysisError, match="must be auto, measured or nominal"):
        both.position_channel("height")


def test_factors_take_given_values_before_the_file_s():
    v = _curve(False, "V", sensitivity=50e-9, spring_constant=0.1)
    assert v.deflection_factor() == 50e-9 and v.force_factor() == 50e-9 * 0.1
    assert v.deflection_factor(sensitivity=20e-9) == 20e-9
    assert v.force_factor(sensitivity=20e-9, spring_constant=2.0) == 20e-9 * 2.0
    assert math.isnan(_curve(False, "V").deflection_factor())          # no InvOLS: unknown, not 0
    assert math.isnan(_curve(False, "V", sensitivity=0.0).force_factor())
    n = _curve(False, "N", spring_constant=0.5)
    assert n.deflection_factor() == 2.0 and n.force_factor() == 1.0
    m = _curve(False, "m")
    assert m.deflection_factor() == 1.0 and math.isnan(m.force_factor())
