"""The speed regression gate's comparison (benchmarks/gate.py, issue 35.5): given stored and
measured ratios it fails on a metric more than 10 % worse, and the stored baseline is one it
can use. No timing here (speed is measured by benchmarks/regression.py)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _load_gate():
    spec = importlib.util.spec_from_file_location("afmforce_bench_gate", ROOT / "benchmarks" / "gate.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod            # its dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


gate = _load_gate()

STORED = {"fig5_x_radau": {"value": 500.0, "better": "higher"},
          "short_ms": {"value": 0.1, "better": "lower"}}


def _verdicts(measured, tolerance=0.10):
    rows = gate.compare(STORED, measured, tolerance)
    return {r.name: r.regressed for r in rows}, gate.failed(rows), rows


@pytest.mark.parametrize("value, regressed", [(500.0, False), (600.0, False), (451.0, False),
                                              (450.5, False), (449.0, True), (300.0, True)])
def test_higher_is_better_fails_beyond_ten_percent(value, regressed):
    v, failed, _ = _verdicts({"fig5_x_radau": value, "short_ms": 0.1})
    assert v["fig5_x_radau"] is regressed
    assert failed is regressed


@pytest.mark.parametrize("value, regressed", [(0.1, False), (0.05, False), (0.111, False),
                                              (0.1112, True), (0.2, True)])
def test_lower_is_better_fails_beyond_ten_percent(value, regressed):
    # lower is better: the change is stored / measured (0.1 / 0.111 = 0.901 passes,
    # 0.1 / 0.1112 = 0.899 fails)
    v, failed, _ = _verdicts({"fig5_x_radau": 500.0, "short_ms": value})
    assert v["short_ms"] is regressed
    assert failed is regressed


def test_change_is_the_measured_over_the_stored_ratio():
    _, _, rows = _verdicts({"fig5_x_radau": 550.0, "short_ms": 0.08})
    change = {r.name: r.change for r in rows}
    assert change["fig5_x_radau"] == pytest.approx(1.1)
    assert change["short_ms"] == pytest.approx(1.25)


def test_a_metric_not_measured_is_a_regression_and_a_new_one_is_not():
    v, failed, rows = _verdicts({"fig5_x_radau": 500.0, "new_metric": 3.0})
    assert v["short_ms"] is True and failed
    assert v["new_metric"] is False
    assert "REGRESSION (not measured)" in gate.render(rows)
    assert "new" in gate.render(rows).splitlines()[-2]


def test_a_nonpositive_measurement_is_a_regression():
    v, failed, _ = _verdicts({"fig5_x_radau": 0.0, "short_ms": 0.1})
    assert v["fig5_x_radau"] is True and failed


def test_tolerance_is_a_parameter():
    assert _verdicts({"fig5_x_radau": 460.0, "short_ms": 0.1}, tolerance=0.05)[1]
    assert not _verdicts({"fig5_x_radau": 460.0, "short_ms": 0.1}, tolerance=0.10)[1]


def test_render_says_failed_or_passed():
    assert gate.render(gate.compare(STORED, {"fig5_x_radau": 100.0, "short_ms": 0.1}))\
        .endswith("FAILED")
    assert gate.render(gate.compare(STORED, {"fig5_x_radau": 500.0, "short_ms": 0.1}))\
        .endswith("passed")


@pytest.mark.parametrize("metric, message", [
    ({"value": -1.0, "better": "higher"}, "positive finite"),
    ({"value": float("inf"), "better": "higher"}, "positive finite"),
    ({"value": 2.0, "better": "faster"}, "'higher' or 'lower'"),
    (3.0, "expected an object"),
])
def test_bad_baselines_are_refused_with_the_reason(tmp_path, metric, message):
    f = tmp_path / "b.json"
    f.write_text(json.dumps({"metrics": {"m": metric}}))
    with pytest.raises(gate.BaselineError, match=message):
        gate.load_baseline(f)


def test_the_stored_baseline_is_usable_and_holds_the_forward_model_ratios():
    base = gate.load_baseline(ROOT / "benchmarks" / "baseline.json")
    assert {"fig5_x_yardstick", "fig5_damped_x_yardstick", "short_call_x_yardstick"} <= set(base["metrics"])
    assert base["tolerance"] == pytest.approx(0.10)
    # ratios measured in one run, not seconds: the yardstick takes ~15 ms, a Fig-5 cycle ~2 ms
    assert all(m["better"] == "higher" and m["value"] > 2 for m in base["metrics"].values())
