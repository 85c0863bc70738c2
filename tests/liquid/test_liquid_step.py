"""The ``liquid`` step of ``afmforce analyze`` (issue 25 item 5): virtual colloid-probe curves in
water recorded by the ``liquid`` virtual AFM (curved photodiode, drift, 1/f noise, 16-bit ADC),
written as raw files and read back, analysed by the pipeline -- against the simulation's truth."""

import json
import math
import warnings

import numpy as np
import pytest

from afmforce.analysis.options import LiquidOptions, ProbeCalibration
from afmforce.analysis.pipeline import analyze
from afmforce.cli.main import main
from afmforce.dynamics import simulate
from afmforce.forces import effective_radius
from afmforce.instrument import get_preset
from afmforce.io.native.rawfile import read_raw, write_raw

K, R, ETA = 0.1, 5e-6, 0.89e-3
CFG = dict(model="spring", spring_constant=K, mass=1e-11, radius=R, geometry="sphere-flat",
           hamaker=1e-20, viscosity=ETA, permittivity=78.4, double_layer="constant_potential",
           surface_potential=-0.03, debye_length=10e-9, lever_drag=1e-5, z0=1e-9,
           start=-400e-9, turn=150e-9, end=-400e-9)
OPTS = LiquidOptions(medium="water", z0=1e-9, contact_separation=1e-9 / 2 ** (1 / 3))
PROBE = ProbeCalibration(radius=R)


def _record(tmp_path, velocity, rate, seed, **change):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(velocity=velocity, sample_rate=rate, **{**CFG, **change})
    return read_raw(write_raw(get_preset("liquid").record(tr, seed=seed), tmp_path / f"liquid_{seed}.txt"))


@pytest.mark.parametrize("seed,psi,lam", [(3, -0.03, 10e-9), (8, -0.045, 6e-9)])
def test_dlvo_and_quadratic_calibration_from_the_pipeline(tmp_path, seed, psi, lam):
    raw = _record(tmp_path, 1e-6, 2e3, seed, surface_potential=psi, debye_length=lam)
    res = analyze(raw, steps=["liquid"], options=[OPTS], probe=PROBE)
    q = res.details["liquid"]
    assert "liquid" not in res.not_applicable
    # photodiode (d + d^2/L)/s, s = 30 nm/V, L = 3 um: d = s u - s^2 u^2 / L + ...
    assert q.sensitivity == pytest.approx(30e-9, rel=0.01)
    assert q.nonlinearity_length == pytest.approx(3e-6, rel=0.25)
    assert q.surface_potential == pytest.approx(psi, rel=0.10)
    assert q.debye_length == pytest.approx(lam, rel=0.05)
    assert 0 < q.hamaker < 3e-20 and q.debye_length_se > 0 and q.surface_potential_se > 0
    assert res.surface_potential == q.surface_potential and res.debye_length == q.debye_length
    # the automatic zero: the approach's separation against the simulation's truth, away from contact
    truth, a = np.asarray(raw.truth["separation"]), raw.segment == 0
    far = truth[a] > 5e-9
    assert np.max(np.abs(res.separation[a][far] - truth[a][far])) < 1e-9


def test_lever_drag_from_the_offset_and_the_speed(tmp_path):
    v = 20e-6
    raw = _record(tmp_path, v, 20e3, seed=5)
    q = analyze(raw, steps=["liquid"], options=[OPTS], probe=PROBE).details["liquid"]
    # offset = 2 (c + 6 pi eta R^2 / h) v / k at the far region's middle; the drainage there subtracted
    beta = 6 * math.pi * ETA * float(effective_radius(R, "sphere-flat")) ** 2
    assert q.drag_offset == pytest.approx(2 * (1e-5 + beta / q.drag_separation) * v / K, rel=0.05)
    assert q.lever_drag == pytest.approx(1e-5, rel=0.10)
    # drainage separated from the static force at equal separation: v (c + beta / h) far out
    assert q.lever_drag_fit == pytest.approx(1e-5, rel=0.10)
    assert q.drainage_coefficient == pytest.approx(beta, rel=0.30)   # (+25 % here: the weakest number)
    assert q.drainage_coefficient_expected == pytest.approx(beta, rel=1e-12)
    # their standard errors (velocity_force_fit): statistical only, measured here c 9.48 +- 0.19e-6 and
    # beta 5.24 +- 0.29e-13 against 4.19e-13: beta's bias (3.6 se) is the model's (the retract still
    # relaxing from the pull-off, tip speed != piezo speed), not noise -- docs/liquid.md says so
    assert q.velocity_fit_undetermined == ""
    assert 0 < q.lever_drag_fit_se < 0.05 * 1e-5 and 0 < q.drainage_coefficient_se < 0.2 * beta


def test_skipped_in_air_and_without_a_double_layer(tmp_path):
    raw = _record(tmp_path, 1e-6, 2e3, seed=9, double_layer="none", lever_drag=0.0)
    res = analyze(raw, steps=["liquid"], probe=PROBE)
    assert "no liquid medium" in res.not_applicable["liquid"] and "liquid" not in res.details
    res = analyze(raw, steps=["liquid"], options=[LiquidOptions(medium="air")], probe=PROBE)
    assert "air" in res.not_applicable["liquid"]
    res = analyze(raw, steps=["liquid"], options=[OPTS], probe=PROBE)
    assert "no double-layer repulsion" in res.not_applicable["liquid"]
    q = res.details["liquid"]    # the calibration and the drag are still reported
    assert q.sensitivity == pytest.approx(30e-9, rel=0.01) and math.isnan(q.surface_potential)
    assert math.isnan(res.surface_potential)
    # strong adhesion (A R / 6 z0^2 = 83 nN: 830 nm of deflection): the retract never pulls off
    raw = _record(tmp_path, 1e-6, 2e3, seed=10, double_layer="none", hamaker=1e-19)
    res = analyze(raw, steps=["liquid"], options=[OPTS], probe=PROBE)
    assert "the retract never pulls off" in res.not_applicable["liquid"]   # (the photodiode clips, too)


def test_cli_analyze_liquid_json(tmp_path, capsys):
    raw = _record(tmp_path, 1e-6, 2e3, seed=3)
    path = tmp_path / "liquid_3.txt"
    rc = main(["analyze", str(path), "--steps", "liquid", "--medium", "water", "--radius", "5um",
               "--option", "liquid.z0=1nm", "--json"])
    out = capsys.readouterr()
    assert rc == 0, out.err
    r = json.loads(out.out)["results"]["liquid_3.txt"]
    assert r["surface_potential"] == pytest.approx(-0.03, rel=0.10)
    assert r["debye_length"] == pytest.approx(10e-9, rel=0.05)
    assert r["units"]["lever_drag"] == "N s/m" and r["details_units"]["liquid"]["surface_potential"] == "V"
    assert raw.deflection_unit == "V"
    assert main(["analyze", str(path), "--steps", "liquid", "--medium", "water", "--radius", "5um",
                 "--option", "liquid.z0=1nm"]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("liquid_3.txt: liquid:")][0]
    psi = float(line.split("DLVO psi ")[1].split()[0])
    assert psi == pytest.approx(r["surface_potential"] * 1e3, rel=1e-3) and "Debye length" in line
    # 1 um/s: the drag offset (0.15 nm) is within the drift between the runs: undetermined, said so
    assert "lever drag undetermined" in line and r["lever_drag"] is None


def test_figure_panel_of_a_liquid_curve(tmp_path):
    from afmforce.plotting.curves import plot_summary

    raw = _record(tmp_path, 1e-6, 2e3, seed=3)
    res = analyze(raw, steps=["liquid"], options=[OPTS], probe=PROBE)
    fig = plot_summary(res, raw)
    ax = fig.axes[2]                       # the lower-left panel: the double layer on a log scale
    assert ax.get_yscale() == "log" and "DLVO" in ax.get_legend().get_texts()[-2].get_text()
    fit = [ln for ln in ax.get_lines() if ln.get_label().startswith("DLVO")][0]
    q = res.details["liquid"]
    assert np.nanmax(fit.get_ydata()) == pytest.approx(np.max(q.fit_force) * 1e9)
    fig.savefig(tmp_path / "liquid.png")
