"""Issue 6: the paper reproduced — every report entry passes, every figure is a valid PNG."""

import json

import pytest

from afmforce.cli.main import main
from afmforce.paper import all_checks, evaluate_checks
from afmforce.paper.numbers_dynamic import lag_behind_static
from afmforce.paper.reproduce import FIGURES
from afmforce.paper.runs import FIG1_RUN, run

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def reproduced(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    code = main(["reproduce", "--out", str(out), "--fast"])
    return code, out


def test_reproduce_fast_writes_every_figure(reproduced):
    code, out = reproduced
    for key, (stem, _) in FIGURES.items():
        png = out / f"{stem}.png"
        assert png.exists(), key
        data = png.read_bytes()
        assert data[:8] == PNG_MAGIC and len(data) > 10_000, key
    assert code == 0


def test_report_every_entry_passes(reproduced):
    _, out = reproduced
    rep = json.loads((out / "report.json").read_text())
    assert rep["passed"] is True
    assert len(rep["checks"]) == len(all_checks())
    for c in rep["checks"]:
        assert c["passed"] or not c["gated"], c["key"]
    assert sum(c["gated"] for c in rep["checks"]) >= len(rep["checks"]) - 2
    md = (out / "report.md").read_text()
    assert "Decisions" in md and "3.5e-13" in md


def test_report_numbers_come_from_the_library():
    # perturbing a check's inputs changes the computed value: nothing is a stored literal
    (r,) = evaluate_checks([c for c in all_checks() if c.key == "fig1_dynamic_lag_10"])
    tr = run(velocity=10e-6, **FIG1_RUN)
    assert r.ours == pytest.approx(1e9 * lag_behind_static(tr, 0.21, 100e-9), rel=1e-12)
    tr_slow = run(velocity=1e-6, **FIG1_RUN)
    assert lag_behind_static(tr_slow, 0.21, 100e-9) < lag_behind_static(tr, 0.21, 100e-9)


def test_unknown_figure_is_a_usage_error(capsys, tmp_path):
    assert main(["reproduce", "--out", str(tmp_path), "--only", "fig99"]) == 2
    assert "unknown figure" in capsys.readouterr().err


def test_fig6_shows_every_spike_unclipped():
    """Issue 12: every dashed Fig 6 curve shows its spike (peak from the dense output, located
    by the integrator), and the y range is not clipped below the highest spike."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from afmforce.paper.figures_dynamic import fig6
    from afmforce.paper.runs import FIG5_RUN

    axes = fig6()
    for ax, xi in zip(axes, (0.01, 0.1)):
        peaks = sorted(ln.get_ydata()[0] for ln in ax.lines if ln.get_marker() == "^")
        want = sorted(run(xi=xi, velocity=v, **FIG5_RUN).events.spike_height * 1e9
                      for v in (0.1e-6, 1e-6))
        assert peaks == pytest.approx(want)
        assert ax.get_ylim()[1] > max(want)
    plt.close("all")


# --- issue 12: the report passes only on real checks -----------------------------------------
def test_every_gate_is_real_and_states_its_reason():
    """Each entry says what gates it: a paper value within <= 25 % with its reason, a bound with
    its reason, or an independent reference; estimates and differences are not gated by the
    paper."""
    from afmforce.paper.numbers import KINDS, MAX_TOLERANCE

    assert MAX_TOLERANCE == 0.25
    for c in all_checks():
        assert c.gate in KINDS, c.key
        if c.gate == "check":
            assert c.paper is not None and 0 < c.tolerance <= MAX_TOLERANCE, c.key
            assert c.reason, c.key
        elif c.gate == "bound":
            assert c.paper is not None and c.reason, c.key
        elif c.gate == "reference":
            assert c.reference is not None and c.reference_tolerance <= 0.1, c.key
        elif c.gate == "estimate":
            assert c.paper is None and c.estimate is not None and c.reference is not None, c.key
        else:
            assert c.note, c.key


def test_estimates_and_differences_have_no_paper_verdict(reproduced):
    _, out = reproduced
    rep = json.loads((out / "report.json").read_text())
    by_key = {c["key"]: c for c in rep["checks"]}
    lag = by_key["fig1_dynamic_lag_10"]
    assert lag["kind"] == "estimate" and lag["estimate"] == pytest.approx(3.428, abs=0.001)
    assert lag["ours"] == pytest.approx(0.96, abs=0.03)        # gated by the scipy reference only
    spike = by_key["fig5_spike_positive_duration"]
    assert spike["passed"] is None and spike["gated"] is False
    assert 0.15 < spike["ours"] < 0.25                          # the model: about 0.2 ms
    assert "0.2 ms" in spike["note"] and "0.1 ms" in spike["note"]
    md = (out / "report.md").read_text()
    assert "estimate 3.428" in md and "simulation / estimate = 0.28" in md
    assert "differs (see note)" in md and "gated numbers pass" in md


def test_added_numbers_against_independent_forms():
    """Issue 12's missing numbers, each recomputed here without the library's helpers."""
    import math

    import numpy as np

    res = {r.key: r for r in evaluate_checks([c for c in all_checks() if c.group != "dynamics"])}
    # Fig 3 inward force at z2 = 10 nm (eqs 7-12 solved directly, Fy = +mu inward)
    L0, L1, L2, th, k0, mu = 200e-6, 2e-6, 4e-6, math.radians(-15), 0.13, 5e-9
    B = k0 * L0**3 / 3
    a, b = L1 * math.cos(th) + L2 * math.sin(th), L1 * math.sin(th) - L2 * math.cos(th)

    def tip(fz, fy):
        f0, tau = fz * math.cos(th) + fy * math.sin(th), a * fz + b * fy
        x = (2 / 3 * f0 * L0**3 + tau * L0**2) / (2 * B)
        t = (f0 * L0**2 + 2 * L0 * tau) / (2 * B)
        return x * math.cos(th) + a * t, x * math.sin(th) + b * t

    z_fz, _ = tip(1.0, 0.0)
    z_fy, y_fy = tip(0.0, 1.0)
    _, y_fz = tip(1.0, 0.0)
    assert res["fig3_force_in"].ours == pytest.approx(1e9 * (10e-9 - z_fy * mu) / z_fz, rel=1e-9)
    assert res["fig3_force_in"].passed and abs(res["fig3_force_in"].ours - 3.0) < 0.5
    # pinned tip: y2 = 0 fixes Fy = -Fz y_fz / y_fy
    k_pin = 1.0 / (z_fz - z_fy * y_fz / y_fy)
    assert res["pinned_k"].ours == pytest.approx(k_pin, rel=1e-9)
    # k0 = 3B/L0^3 with B = 3.5e-13, and the beam modes from the spec's K, T, masses
    assert res["k0_fig5"].ours == pytest.approx(3 * 3.5e-13 / L0**3) == pytest.approx(0.13125)
    Bd = 3.5e-13
    K = Bd * np.array([[12 / L0**3, -6 / L0**2], [-6 / L0**2, 4 / L0]])
    T = np.array([[1, 0], [-1.5 / L1, 1 / L1]])
    M = np.diag([1e-10 + 1e-10 / 4, 1e-10 / 3])
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(M, T.T @ K @ T)).real)
    f = np.sqrt(w2) / (2 * math.pi) / 1e3
    assert res["beam_mode_low"].ours == pytest.approx(f[0], rel=1e-9) == pytest.approx(4.06, abs=0.01)
    assert res["beam_mode_high"].ours == pytest.approx(f[1], rel=1e-9) == pytest.approx(1464, abs=1)
    # JKR: -3 pi gamma R / 4 = -3 A R / (64 z0^2)
    assert res["jkr_pull_off"].ours == pytest.approx(-1e9 * 3 * 5e-19 * 100e-9 / (64 * 0.35e-9**2))
    # bare lever: R = v |Fs'| / (4 f k dx) with |Fs'(5 nm)| = A R / (3 h^3) (z0 << h, exact form)
    h, z0 = 5e-9, 0.35e-9
    grad = (5e-19 * 100e-9 / 6) * (h**-3 - z0**6 * h**-9)
    assert res["bare_lever_R"].ours == pytest.approx(10e-6 * grad / (4 * 20e3 * 0.21 * 0.5e-9))
    assert res["bare_lever_R"].ours < 0.1 and res["pinned_beta"].ours < 0
