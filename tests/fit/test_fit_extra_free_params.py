"""``--free hamaker,xi,z0`` (docs/fit.md's own example) gave z0 a Wald interval from the Jacobian's
curvature; z0 enters the force as 1/(d + z0)^2 near contact, far from linear over its standard
error, and the interval missed the truth (the walk of 2026-11-29): virtual AFM, 0.5/2/8 um/s, xi
0.005 kg/s, 0.01 nm noise, seed 2: z0 = 0.775 nm [0.472, 1.079] for 0.35 nm (simulated); the
`typical` preset as files (seed 2): 0.595 nm [0.523, 0.666] nm. z0 is profiled like A and xi now:
seed 2 [0.259, 1.160] nm; the `typical` set (open, 0.974] nm, the profile flat down to the bound."""

from __future__ import annotations

import pytest

from afmforce.dynamics import SimulationConfig
from afmforce.fit import fit_dynamic, virtual_curves


def test_z0_interval_is_the_profile_and_covers_the_simulated_value():
    truth = SimulationConfig().surface.z0           # the virtual AFM's (the model's default) 0.35 nm
    assert truth == pytest.approx(0.35e-9)
    curves = virtual_curves([0.5e-6, 2e-6, 8e-6], xi=0.005, noise=0.01e-9, seed=2)
    res = fit_dynamic(curves, "beam", free=("hamaker", "xi", "z0"), compare=False)
    p = res.parameters["z0"]
    assert p.interval_method == "profile"
    lo, hi = p.interval
    assert (lo is None or lo <= truth) and (hi is None or truth <= hi), p
    assert res.parameters["xi"].interval[0] <= 0.005 <= res.parameters["xi"].interval[1]


def test_lever_mass_free_fit_ends_below_the_held_fit_and_its_interval_covers():
    """``--free hamaker,xi,m_joint`` (the walk of 2026-11-29; same virtual set, seed 2, white noise):
    along the A*R-xi ridge m_joint wandered off and the full fit ended above the fit with m_joint
    held at the simulated 1e-10 kg (chi2 320.17 against 312.88; seed 3: 444.6 against 260.5), with
    m_joint = 3.42e-8 kg [3.38e-8, 3.45e-8] (Wald) for 1e-10. Now the held ridge's best point starts
    the full fit too (chi2 311.92 <= 312.88), and m_joint is profiled (its Wald interval
    [4.2e-9, 5.8e-9] kg around the 5e-9 optimum, 1 chi2 below the truth's, missed it)."""
    truth = SimulationConfig().m_joint            # the virtual AFM's (the model's default) 100 ng
    assert truth == pytest.approx(1e-10)
    curves = virtual_curves([0.5e-6, 2e-6, 8e-6], xi=0.005, noise=0.01e-9, seed=2)
    kw = dict(compare=False, noise="white")
    held = fit_dynamic(curves, "beam", free=("hamaker", "xi"), profile=(), **kw)
    res = fit_dynamic(curves, "beam", free=("hamaker", "xi", "m_joint"), **kw)
    assert res.chi2 <= held.chi2 + 1e-6 * held.chi2      # the nested fit is inside the richer one
    p = res.parameters["m_joint"]
    assert p.interval_method in ("profile", "undetermined")
    lo, hi = p.interval
    assert (lo is None or lo <= truth) and (hi is None or truth <= hi), p
