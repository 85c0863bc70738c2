"""The fit and the plan as a user types them: unit mistakes and edge values refused with one
readable line naming what was typed, before any work; guesses that stay inside the declared
ranges."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from afmforce.errors import ParameterError


def test_static_guess_at_a_search_bound_stays_inside_the_declared_range():
    """A jump-in smaller than the smallest A gives (a stiff lever: ``--meta spring_constant=200``
    on 0.14 N/m curves) drives the guess to the lower search bound: exp(log(1e-22 J)) is
    9.99...e-23 J, which the record refused, and the fit failed with "hamaker = 1e-22 J is out
    of range", a value nobody typed."""
    from afmforce.dynamics import SimulationConfig
    from afmforce.fit.core import _guess_globals
    from afmforce.fit.params import PARAMETERS

    base = SimulationConfig()
    curves = [SimpleNamespace(velocity=1e-6, guess={"min_deflection": -1e-30})]   # no A gives so small a jump
    for name in ("hamaker", "radius"):
        g = _guess_globals(curves, base, (name,))
        assert g[name] == pytest.approx(PARAMETERS[name].lower, rel=1e-9)
        assert PARAMETERS[name].lower <= g[name] <= PARAMETERS[name].upper


@pytest.mark.parametrize("argv, said", [
    (["fit", "a.txt", "b.txt", "--fringe-period", "335"],        # 335 m, meant 335 nm
     "--fringe-period 335 is out of range: fringe_period"),
    (["plan", "--noise", "0.05"], "--noise 0.05 is out of range: deflection_noise"),    # 5 cm of noise
    (["plan", "--force-error", "200"], "--force-error 200 is out of range: force_error"),
    (["plan", "--slip-target", "2"], "--slip-target 2 is out of range: slip_target"),
])
def test_unit_mistakes_are_refused_while_parsing(capsys, argv, said):
    """Before: ``--fringe-period 1e308`` ran an 85 s fit and warned of fringes of "period inf nm";
    ``plan --noise 200`` (200 m) and ``--force-error 200`` (200 N) made a plan."""
    from afmforce.cli.main import main

    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.startswith(f"error: {said}") and len(err.splitlines()) == 1, err


def test_the_library_refuses_them_too():
    from afmforce.fit import fit_dynamic
    from afmforce.fit.plan import plan_experiment
    from afmforce.fit.plan_slip import plan_slip

    with pytest.raises(ParameterError, match="fringe_period = 1e"):
        fit_dynamic([], "beam", fringe_period=1.0)
    with pytest.raises(ParameterError, match="deflection_noise = "):
        plan_experiment("beam", noise=200.0)
    with pytest.raises(ParameterError, match="slip_target = "):
        plan_slip("spring", target=math.inf)


def test_a_plan_at_one_speed_is_refused():
    """``plan --speeds 1um/s,1um/s`` weighed designs of two curves at one speed and reported a
    standard error of xi, which one speed cannot determine (the fit refuses such curves)."""
    from afmforce.fit.plan import plan_experiment

    with pytest.raises(ParameterError, match="2 different candidate speeds"):
        plan_experiment("beam", speeds=(1e-6, 1e-6))
