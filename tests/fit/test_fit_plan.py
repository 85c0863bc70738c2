"""Experiment design: Fisher-information predictions against an actual fit, static-error scan."""

from __future__ import annotations

import math

import pytest

from afmforce.cli.main import main
from afmforce.dynamics import static_jump_in
from afmforce.fit.plan import plan_experiment


@pytest.fixture(scope="module")
def plan():
    return plan_experiment("beam", xi=0.005, noise=0.01e-9, speeds=(0.2e-6, 1e-6, 5e-6),
                           n_curves=3, start=-30e-9, turn=10e-9)


def test_plan_information(plan):
    alone = {c["speed"]: c["sigma_xi_alone"] for c in plan.candidates}
    paired = {c["speed"]: c["sigma_xi_paired"] for c in plan.candidates}
    # pairing a fast curve with the slowest one (which pins A*R) beats either alone
    assert paired[5e-6] < alone[5e-6] and paired[5e-6] < alone[0.2e-6]
    b = plan.best_design
    assert len(set(b["speeds"])) >= 2
    assert 0 < b["sigma_xi"] <= paired[5e-6] * 1.0001
    assert b["detect_z"] == pytest.approx(0.005 / b["sigma_xi"])


def test_static_scan(plan):
    from afmforce.dynamics import SimulationConfig

    k = SimulationConfig().force_constant
    f_static = k * static_jump_in(k, 100e-9)[2]
    errs = [s["error"] for s in plan.static_scan]
    assert all(s["force_static"] == pytest.approx(f_static) for s in plan.static_scan)
    assert errs[-1] > errs[0]          # friction x speed lowers the apparent attraction
    # friction holds the tilt back: its minimum lies before contact, so no note on the fall (test_plan_fall.py)
    assert not any(s["minimum_at_contact"] for s in plan.static_scan)
    assert not any("fall from the instability" in n for n in plan.notes)
    ok = [s["speed"] for s in plan.static_scan if s["error"] <= plan.force_error]
    assert (max(ok) if ok else math.nan) == plan.fastest_static_speed or not ok


def test_plan_cli_json(capsys):
    rc = main(["plan", "--xi", "0.005kg/s", "--speeds", "0.5um/s,5um/s", "--curves", "2",
               "--noise", "0.01nm", "--json"])
    assert rc == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert d["best_design"]["speeds"] == pytest.approx([0.5e-6, 5e-6])
    assert d["best_design"]["sigma_xi"] > 0


def test_docs_fit_md_states_what_its_plan_command_gives(capsys):
    """docs/fit.md's numbers for its own `afmforce plan --xi 5e-3kg/s --speeds 0.2um/s,...,10um/s --noise
    0.01nm` are what that command gives (they had drifted: 1.2e-4 kg/s stated, 1.8e-4 given)."""
    import json
    import re
    import shlex
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "fit.md").read_text(encoding="utf-8")
    line = next(ln for ln in text.splitlines() if ln.startswith("afmforce plan --xi 5e-3kg/s --speeds"))
    assert main([*shlex.split(line, comments=True)[1:], "--json"]) == 0
    plan = json.loads(capsys.readouterr().out)

    def e(x: float) -> str:   # 1.8e−4, as the page writes it
        mantissa, exponent = f"{x:.1e}".split("e")
        return f"{mantissa}e\u2212{int(exponent[1:])}"

    alone = sorted(c["sigma_xi_alone"] for c in plan["candidates"])
    paired = {round(c["speed"] * 1e6, 3): c["sigma_xi_paired"] for c in plan["candidates"]}
    best = plan["best_design"]
    said = re.sub(r"\s+", " ", text)
    assert f"σ(ξ) {alone[0] * 1e3:.1f}–{e(alone[-1])} kg/s" in said
    lo, hi = sorted((paired[2.0], paired[5.0]))
    assert f"paired with a slow one {lo * 1e4:.1f}–{e(hi)};" in said
    assert sorted(round(v * 1e6, 3) for v in best["speeds"]) == [0.2, 0.2, 5.0, 5.0]
    assert "two slow (0.2 µm/s) and two fast (5 µm/s) curves" in said
    assert f"σ(ξ) = {e(best['sigma_xi'])} kg/s" in said
