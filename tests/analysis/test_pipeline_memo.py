"""``analyze(..., memo=)``: the sample steps' state reused after a calibration change (issue 33.7).

The result with the memo equals the result of a fresh analysis to the last bit, for a new spring
constant (in the probe record and in the metadata, as the web gives it) and for a new sensitivity;
and the sample steps really are skipped (counted), unless the curve's samples or their options change.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
from pathlib import Path

import pytest

from afmforce.analysis import pipeline
from afmforce.analysis.options import ContactOptions, ProbeCalibration, VdwOptions
from afmforce.io import load

DATA = Path(__file__).resolve().parents[1] / "data"


def _same(a, b) -> None:
    assert json.dumps(a.to_dict(arrays=True), sort_keys=True) == json.dumps(b.to_dict(arrays=True), sort_keys=True)


_VERSIONS = itertools.count()


@pytest.fixture
def counted(monkeypatch):
    from afmforce.analysis import registry

    calls = {"smooth": 0}
    step = registry.step("smooth")

    def smooth(st, o):
        calls["smooth"] += 1
        return step.func(st, o)

    # the record replaced in place (same place in the order); a version never used before rebuilds
    # every derived table (all undone after the test)
    monkeypatch.setitem(registry._STEPS, "smooth", dataclasses.replace(step, func=smooth))
    monkeypatch.setitem(registry._STATE, "version", 10**9 + next(_VERSIONS))
    assert pipeline.STEPS["smooth"].func is smooth
    return calls


@pytest.mark.parametrize("file", ["afmforce-raw_jpk-cellhesion-spot3.txt", "asylum-mfp3d_SiN-tip_air.ibw"])
def test_a_calibration_change_with_the_memo_equals_a_fresh_analysis(file, counted):
    curve = load(DATA / file)[0]
    memo: dict = {}
    first = pipeline.analyze(curve, memo=memo)
    assert counted["smooth"] == 1 and len(memo) == 1
    for probe, meta in ((ProbeCalibration(spring_constant=0.0421), {"spring_constant": 0.0421}),
                        (ProbeCalibration(sensitivity=61e-9), {"sensitivity": 61e-9})):
        changed = dataclasses.replace(curve, metadata={**curve.metadata, **meta})    # the same samples
        n = counted["smooth"]
        again = pipeline.analyze(changed, probe=probe, memo=memo, options=[VdwOptions(max_separation=12e-9)])
        assert counted["smooth"] == n                       # the sample steps were not run again
        fresh = pipeline.analyze(changed, probe=probe, options=[VdwOptions(max_separation=12e-9)])
        _same(again, fresh)
        assert again.spring_constant != first.spring_constant or again.sensitivity_used != first.sensitivity_used


def test_the_memo_is_not_used_for_other_samples_or_other_sample_options(counted):
    curve = load(DATA / "afmforce-raw_jpk-cellhesion-spot3.txt")[0]
    memo: dict = {}
    pipeline.analyze(curve, memo=memo)
    other = dataclasses.replace(curve, deflection_signal=curve.deflection_signal * 1.01)   # new samples
    _same(pipeline.analyze(other, memo=memo), pipeline.analyze(other))
    n = counted["smooth"]
    opts = [ContactOptions(**{f.name: f.default for f in dataclasses.fields(ContactOptions)
                              if f.default is not dataclasses.MISSING})]
    pipeline.analyze(curve, memo=memo, options=opts)        # the defaults spelled out: the same state
    assert counted["smooth"] == n
    changed = [ContactOptions(baseline_fraction=ContactOptions().baseline_fraction * 0.8)]
    pipeline.analyze(curve, memo=memo, options=changed)
    assert counted["smooth"] == n + 1                       # a contact option changed: the steps run again
    _same(pipeline.analyze(curve, memo=memo, options=changed), pipeline.analyze(curve, options=changed))
