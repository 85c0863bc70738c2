"""The hydration (exponential) repulsion (afmforce.surface_laws.hydration) against its closed
form, the Derjaguin integral of the pressure over a sphere, the scipy reference and the command
line (the fit of a law's parameter: test_steric.py)."""

import json
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad

from afmforce.surface_laws import law
from afmforce.surface_laws.hydration import hydration_force

from ._cycle import CYCLE, cycle_against_reference

P0, LAM = 3e7, 0.5e-9          # Pa, m: 15 mJ/m^2 = P0 lambda, Israelachvili's 3-30 mJ/m^2


def test_closed_form_and_the_pressure_integrated_over_a_sphere():
    R = 1e-6
    # at contact 2 pi R P0 lambda; 1/e per decay length; dF/dh = -F/lambda
    assert float(hydration_force(0.0, R, P0, LAM)) == pytest.approx(2 * math.pi * R * P0 * LAM, rel=1e-15)
    f, df = law("hydration").force(np.array([LAM, 3 * LAM]), R, {"hydration_pressure": P0,
                                                                  "hydration_length": LAM})
    assert f[0] / f[1] == pytest.approx(math.exp(2.0), rel=1e-14)
    assert df == pytest.approx(-f / LAM, rel=1e-15)
    # independent: P(gap) integrated over the sphere's exact profile (Derjaguin holds to lambda/R)
    for h in (0.2e-9, 1e-9, 2e-9):
        exact = quad(lambda r: P0 * math.exp(-(h + R - math.sqrt(R * R - r * r)) / LAM) * 2 * math.pi * r,
                     0.0, 0.2 * R, epsabs=0.0, epsrel=1e-12, limit=400)[0]
        assert float(hydration_force(h, R, P0, LAM)) == pytest.approx(exact, rel=3 * LAM / R)


def test_compiled_cycle_matches_the_scipy_reference_and_the_repulsion_shows():
    tr, _, _ = cycle_against_reference(hydration_pressure=P0, hydration_length=LAM)
    from afmforce.dynamics import SimulationConfig, simulate
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        bare = simulate(SimulationConfig(**CYCLE))
    # the repulsion weakens the attraction seen before contact
    assert tr.events.min_deflection > bare.events.min_deflection


def test_simulate_command_takes_the_laws_flags(capsys):
    from afmforce.cli.main import main

    argv = ["simulate", "--model", "spring", "--spring-constant", "1N/m", "--mass", "1e-11kg",
            "--radius", "20nm", "--geometry", "sphere-flat", "--hamaker", "1e-20J", "--velocity",
            "10um/s", "--start", "-30nm", "--turn", "3nm", "--end", "-60nm", "--sample-rate", "200kHz",
            "--json", "--no-progress"]
    assert main(argv + ["--hydration-pressure", "30MPa", "--hydration-length", "0.5nm"]) == 0
    on = json.loads(capsys.readouterr().out)
    assert main(argv) == 0
    off = json.loads(capsys.readouterr().out)
    assert on["min_deflection"] > off["min_deflection"]
    with pytest.raises(SystemExit) as exc:
        main(argv + ["--hydration-pressure", "-1Pa"])
    assert exc.value.code == 2 and "hydration_pressure" in capsys.readouterr().err
