"""The comparison of the speed regression gate (``benchmarks/regression.py``, issue 35.5).

A baseline (``benchmarks/baseline.json``) stores, per metric, a *ratio measured in one run*
(for instance the scipy Radau solve of the Fig-5 cycle over afmforce's, both timed in the same
process): a slower or busier machine moves both sides, so the ratio travels between machines
where seconds do not. :func:`compare` sets a measurement against the stored ratios and marks a
metric regressed when it is worse by more than the tolerance (10 %). No timing here: the tests
(``tests/benchmarks/test_gate.py``) give it numbers.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Mapping

__all__ = ["TOLERANCE", "Comparison", "BaselineError", "load_baseline", "compare", "render",
           "failed"]

#: A metric worse than its stored value by more than this fraction is a regression.
TOLERANCE = 0.10


class BaselineError(ValueError):
    """The baseline file is not one :func:`load_baseline` can use (says what is wrong)."""


@dataclass(frozen=True)
class Comparison:
    """One metric against its stored value.

    ``change`` is the measured value over the stored one where higher is better (the stored
    over the measured where lower is better): below 1 is worse; ``regressed`` when
    ``change < 1 - tolerance`` or the metric was not measured (``measured`` None)."""

    name: str
    stored: float
    measured: float | None
    better: str
    change: float | None
    regressed: bool
    what: str = ""


def _check_metric(name: str, m) -> None:
    if not isinstance(m, Mapping):
        raise BaselineError(f"metric {name!r}: expected an object with 'value' and 'better'")
    v = m.get("value")
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not v > 0 or v == float("inf"):
        raise BaselineError(f"metric {name!r}: 'value' must be a positive finite number, got {v!r}")
    if m.get("better") not in ("higher", "lower"):
        raise BaselineError(f"metric {name!r}: 'better' must be 'higher' or 'lower', "
                            f"got {m.get('better')!r}")


def load_baseline(path) -> dict:
    """The baseline file as a dict (``metrics``: name -> {value, better, what}; ``tolerance``
    optional), checked."""
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise BaselineError(f"cannot read the baseline {path}: {exc}") from None
    metrics = data.get("metrics") if isinstance(data, dict) else None
    if not isinstance(metrics, dict) or not metrics:
        raise BaselineError(f"{path}: no 'metrics' object")
    for name, m in metrics.items():
        _check_metric(name, m)
    tol = data.get("tolerance", TOLERANCE)
    if not isinstance(tol, (int, float)) or not 0 <= tol < 1:
        raise BaselineError(f"{path}: 'tolerance' must be in [0, 1), got {tol!r}")
    return data


def compare(stored: Mapping[str, Mapping], measured: Mapping[str, float],
            tolerance: float = TOLERANCE) -> list[Comparison]:
    """Every stored metric against its measurement (``measured``: name -> value; a stored
    metric missing there counts as regressed), then the measured ones the baseline lacks
    (reported, never regressed)."""
    out = []
    for name, m in stored.items():
        _check_metric(name, m)
        ref, better = float(m["value"]), m["better"]
        got = measured.get(name)
        if got is None or not got > 0:
            out.append(Comparison(name, ref, got, better, None, True, m.get("what", "")))
            continue
        got = float(got)
        change = got / ref if better == "higher" else ref / got
        out.append(Comparison(name, ref, got, better, change, change < 1.0 - tolerance,
                              m.get("what", "")))
    for name, got in measured.items():
        if name not in stored:
            out.append(Comparison(name, float("nan"), float(got), "higher", None, False,
                                  "(not in the baseline)"))
    return out


def failed(rows: list[Comparison]) -> bool:
    """Whether any metric regressed."""
    return any(r.regressed for r in rows)


def render(rows: list[Comparison], tolerance: float = TOLERANCE) -> str:
    """The comparison as a text table."""
    lines = [f"{'metric':28s} {'stored':>10s} {'measured':>10s} {'change':>8s}  verdict"]
    for r in rows:
        meas = "missing" if r.measured is None else f"{r.measured:10.4g}"
        change = "" if r.change is None else f"{(r.change - 1.0) * 100:+7.1f}%"
        if r.regressed:
            verdict = "REGRESSION" + ("" if r.measured is not None else " (not measured)")
        elif r.change is None:
            verdict = "new"
        else:
            verdict = "ok"
        lines.append(f"{r.name:28s} {r.stored:10.4g} {meas:>10s} {change:>8s}  {verdict}"
                     + (f"  ({r.better} is better)" if r.regressed else ""))
    lines.append(f"tolerance: {tolerance:.0%} worse than stored; "
                 + ("FAILED" if failed(rows) else "passed"))
    return "\n".join(lines)
