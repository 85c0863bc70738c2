"""The Alexander-de Gennes brush force (afmforce.surface_laws.steric) against its published
exponential form, the Derjaguin integral of the AdG pressure, the scipy reference, the command
line and the dynamic fit."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad

from afmforce.forces import KB
from afmforce.surface_laws import law
from afmforce.surface_laws.steric import brush_force

from ._cycle import cycle_against_reference

L0, S, T = 10e-9, 3e-9, 298.15


def test_published_exponential_form():
    R = 1e-6
    kT = KB * T
    # Butt et al. 1999: F = 50 kT R L0 Gamma^(3/2) exp(-2 pi h / L0), Gamma = 1/s^2
    for h in (2e-9, 5e-9, 9e-9):
        want = 50 * kT * R * L0 * (1 / S**2) ** 1.5 * math.exp(-2 * math.pi * h / L0)
        assert float(brush_force(h, R, L0, S, T)) == pytest.approx(want, rel=1e-14)
    f, df = law("steric").force(np.array([3e-9, 3e-9 + L0]), R,
                                {"brush_length": L0, "brush_spacing": S, "temperature": T})
    assert f[0] / f[1] == pytest.approx(math.exp(2 * math.pi), rel=1e-13)
    assert df == pytest.approx(-2 * math.pi / L0 * f, rel=1e-15)


def test_it_tracks_the_derjaguin_integral_of_the_adg_pressure():
    """Independent: de Gennes' pressure for one brush, P = kT/s^3 [(L0/D)^(9/4) - (D/L0)^(3/4)],
    integrated to W(D) by quad; the exponential form is pi R W within 10 % over 0.2 < h/L0 < 0.7
    (it departs near L0, where the AdG force ends and the exponential does not)."""
    R, kT = 1e-6, KB * T

    def pressure(d):
        return kT / S**3 * ((L0 / d) ** 2.25 - (d / L0) ** 0.75)

    for u in (0.2, 0.3, 0.5, 0.7):
        w = quad(pressure, u * L0, L0, epsabs=0.0, epsrel=1e-12)[0]
        assert float(brush_force(u * L0, R, L0, S, T)) == pytest.approx(math.pi * R * w, rel=0.10), u
    w9 = quad(pressure, 0.9 * L0, L0)[0]
    assert float(brush_force(0.9 * L0, R, L0, S, T)) > 2 * math.pi * R * w9     # past the fit


def test_compiled_cycle_matches_the_scipy_reference():
    tr, _, _ = cycle_against_reference(brush_length=L0, brush_spacing=S)
    # the brush pushes the probe back long before eq 2's wall: no jump-in
    assert math.isnan(tr.events.jump_in_position) or tr.events.min_deflection > -0.05e-9


def test_simulate_command_takes_the_laws_flags(capsys):
    import json

    from afmforce.cli.main import main

    argv = ["simulate", "--model", "spring", "--spring-constant", "1N/m", "--mass", "1e-11kg",
            "--radius", "20nm", "--geometry", "sphere-flat", "--hamaker", "1e-20J", "--velocity", "10um/s",
            "--start", "-40nm", "--quality-factor", "2",
            "--turn", "3nm", "--end", "-60nm", "--sample-rate", "200kHz", "--json", "--no-progress"]
    assert main(argv + ["--brush-length", "10nm", "--brush-spacing", "3nm", "--temperature", "310K"]) == 0
    on = json.loads(capsys.readouterr().out)
    assert main(argv) == 0
    off = json.loads(capsys.readouterr().out)
    assert off["min_deflection"] < -0.02e-9 and on["min_deflection"] > -0.001e-9   # no attraction seen


@pytest.mark.slow
def test_fit_recovers_the_brush_length():
    """``fit_dynamic(free=("brush_length",))``: the free parameter comes from the law's record."""
    from afmforce.fit import fit_dynamic, virtual_curves

    speeds = [10e-6, 40e-6]
    run = dict(model="spring", spring_constant=0.1, mass=1e-11, radius=5e-6, geometry="sphere-flat",
               hamaker=5e-21, viscosity=0.89e-3, lever_drag=1e-5, start=-100e-9, turn=40e-9,
               end=-100e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cur = virtual_curves(speeds, seed=4, noise=0.05e-9, drift_rms=0.5e-9,
                             sample_rates=[v / 2e-9 for v in speeds], brush_length=L0,
                             brush_spacing=S, **run)
        fixed = {k: v for k, v in run.items() if k not in ("start", "turn", "end", "model")}
        res = fit_dynamic(cur, model="spring", free=("brush_length",),
                          fixed={**fixed, "brush_spacing": S, "brush_length": 7e-9},
                          jump_window=0.3e-3)
    b = res.parameters["brush_length"]
    assert b.value == pytest.approx(L0, rel=0.1) and b.interval[0] <= L0 <= b.interval[1]
    assert b.unit == "m"
