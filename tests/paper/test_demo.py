"""Issue 6: ``afmforce demo`` = reproduce --fast + a virtual experiment analysed end to end."""

import json

import pytest

from afmforce.cli.main import main
from afmforce.paper.demo import virtual_experiment
from afmforce.io.native.rawfile import read_raw


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = tmp_path_factory.mktemp("virtual")
    return out, virtual_experiment(out, seed=1)


def test_frictionless_run_recovers_hamaker(runs):
    _, (static, _) = runs
    # quasi-static, no friction, 'typical' instrument noise: the fit finds the true A (eq 2)
    assert static.relative_error == pytest.approx(0.0, abs=0.15)
    assert static.friction == "not detected"


def test_friction_underestimates_attraction(runs):
    _, (static, friction) = runs
    # paper section 2.3 / spec 7: friction (xi v = 1e-9 N) weakens the apparent precontact attraction
    assert friction.relative_error < static.relative_error - 0.1
    assert friction.friction in ("constant", "load")  # parallel offset of the compliance lines
    assert any("dynamic" in w.lower() or "friction" in w.lower() for w in friction.warnings) or friction.verdict


def test_raw_files_written_and_readable(runs):
    out, results = runs
    for r in results:
        curve = read_raw(r.raw_file)
        assert curve.truth is not None and len(curve) > 100
        assert r.figure.read_bytes()[:4] == b"\x89PNG"


def test_demo_command(tmp_path, capsys, monkeypatch):
    """The demo's numbers, and each part printed as soon as it is done (issue 35 item 4): what
    stdout holds when each later part starts is recorded by wrapping the real functions."""
    import afmforce.paper.demo as vdemo
    import afmforce.paper.demo_liquid as ldemo
    import afmforce.paper.numbers as numbers
    from afmforce.cli.demo import FIRST_GROUPS
    from afmforce.dynamics import radau

    printed: list[str] = []
    seen: list[tuple[str, str, int]] = []        # (what starts, stdout so far, integrator calls so far)
    calls = {"integrate": 0}

    def so_far() -> str:
        printed.append(capsys.readouterr().out)
        return "".join(printed)

    def recorder(name, real):
        def wrapped(*a, **kw):
            seen.append((name, so_far(), calls["integrate"]))
            return real(*a, **kw)
        return wrapped

    integrate = radau.integrate_segment

    def counting(*a):
        calls["integrate"] += 1
        return integrate(*a)

    monkeypatch.setattr(radau, "integrate_segment", counting)
    evaluated: list[list] = []
    real_checks = numbers.evaluate_checks

    def checks(*a, **kw):
        seen.append(("checks", so_far(), calls["integrate"]))
        evaluated.append(real_checks(*a, **kw))
        return evaluated[-1]

    monkeypatch.setattr(numbers, "evaluate_checks", checks)
    monkeypatch.setattr(vdemo, "virtual_runs", recorder("virtual", vdemo.virtual_runs))
    monkeypatch.setattr(ldemo, "liquid_experiment", recorder("liquid", ldemo.liquid_experiment))
    assert main(["demo", "--out", str(tmp_path / "paper")]) == 0
    out = so_far()
    import re

    assert [name for name, _, _ in seen] == ["checks", "checks", "virtual", "liquid"]
    first, simulated = evaluated
    assert {c.group for c in first} == set(FIRST_GROUPS) and len(first) >= 25
    assert {c.group for c in simulated} == {"dynamics"}
    # the closed-form and static rows come first, computed without the integrator
    assert "quantity" in seen[0][1] and "gated numbers pass" not in seen[1][1]
    assert seen[1][2] == 0 and calls["integrate"] > 0
    for c in first:
        assert f"{c.quantity[:64]:<64} " in seen[1][1] and f"{c.ours:>12.5g}" in seen[1][1]
    # the whole table (its tally) before the virtual experiment, that one before the liquid one
    assert "gated numbers pass" in seen[2][1] and "virtual experiment" not in seen[2][1]
    assert "vs true 5e-19 J" in seen[3][1] and "liquid experiment" not in seen[3][1]
    for c in simulated:
        assert f"{c.quantity[:64]:<64} " in seen[2][1]

    m = re.search(r"(\d+) of (\d+) gated numbers pass", out)
    assert m and m.group(1) == m.group(2), out[-500:]
    assert int(m.group(2)) == sum(c.passed is not None for c in first + simulated)
    assert "virtual experiment" in out and "vs true" in out
    # issue 25: the liquid experiment, slip length vs truth (3 nm) and detected
    m = re.search(r"slip length ([\d.]+) nm \(95 % \[([\d.]+), ([\d.]+)\]\) vs true 3 nm; slip detected", out)
    assert m and abs(float(m.group(1)) - 3.0) < 0.5 and float(m.group(2)) <= 3.0 <= float(m.group(3)), out[-800:]
    # every figure written (the paper's and the virtual runs' analyses, drawn in a forked child)
    for name in ("fig1_inertia_simple_spring", "fig5_trajectory", "fig7_virtual_instrument"):
        assert (tmp_path / "paper" / f"{name}.png").read_bytes()[:4] == b"\x89PNG"
    for i in (1, 2):
        assert (tmp_path / "paper" / "virtual" / f"virtual_run_{i}_analysis.png").read_bytes()[:4] == b"\x89PNG"
    assert "wrote 7 figure files" in out
    rep = json.loads((tmp_path / "paper" / "report.json").read_text())
    assert rep["passed"]
    # the report keeps the paper's order of the checks
    assert [c["key"] for c in rep["checks"]] == [c.key for c in numbers.all_checks()]
