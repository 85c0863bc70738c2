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
    for target, bound in ((-1e-30, "lower"), (-1.0, "upper")):      # no A gives so small / so deep a jump
        curves = [SimpleNamespace(velocity=1e-6, guess={"min_deflection": target})]
        for name in ("hamaker", "radius"):
            g = _guess_globals(curves, base, (name,))
            assert g[name] == pytest.approx(getattr(PARAMETERS[name], bound), rel=1e-9)
            assert PARAMETERS[name].lower <= g[name] <= PARAMETERS[name].upper
