"""`afmforce plan --xi 0`: the dynamic pull-in force 2.5 x the static one at 0.2 um/s.

Not a dynamic effect of speed, nor an undamped lever's ringing: the scan's measure (k x the smallest
apparent deflection before contact, on the dense output) is reached at contact, after the tip's fall from
the static instability (h_s) to contact (h_c), where the tip's deflection is z_contact + h_c; in the
quasi-static limit k (z_s + h_c), (z_s + h_c) / d_s = 2.49 x the static pull-in k d_s for the Fig 5 lever
(closed form of the vdW instability, dynamics.static). The integrator's number is checked against an
independent scipy Radau solve of the same equations at rtol 1e-10 (dynamics.reference). `plan` now says so.
"""

from __future__ import annotations

import warnings

import pytest

from afmforce.dynamics import DynamicsWarning, SimulationConfig, simulate
from afmforce.dynamics.reference import reference_solve
from afmforce.dynamics.static import surface_jump_in
from afmforce.fit.plan import plan_experiment

FALL = "fall from the instability"


@pytest.fixture(scope="module")
def plan():
    return plan_experiment("beam", xi=0.0, noise=0.05e-9, speeds=(0.2e-6, 20e-6), n_curves=2)


def test_without_friction_the_dynamic_pull_in_is_the_deflection_at_contact(plan):
    base = SimulationConfig(model="beam", xi=0.0)
    k, hc = base.force_constant, base.contact_separation
    h_s, z_s, d_s = surface_jump_in(k, base.surface)[:3]
    assert h_s == pytest.approx(d_s - z_s, rel=1e-9)        # h = z2 - z at the instability
    assert (z_s + hc) / d_s == pytest.approx(2.49, abs=0.01)
    slow, fast = plan.static_scan
    for row in (slow, fast):
        assert row["minimum_at_contact"]
        assert row["force_static"] == pytest.approx(k * d_s, rel=1e-9)
        # the apparent deflection (beta x angle) at contact, within 1 % of the tip's z_contact + h_c
        assert row["force_dynamic"] == pytest.approx(row["force_at_contact"], rel=0.01)
    assert slow["force_dynamic"] == pytest.approx(k * (z_s + hc), rel=0.01)     # the quasi-static limit
    assert slow["force_dynamic"] / slow["force_static"] == pytest.approx(2.47, abs=0.03)
    note = next(n for n in plan.notes if FALL in n)
    assert "not a dynamic effect of speed" in note and "2.49 x the static" in note


def test_the_number_is_the_equations_not_the_integrator():
    """afmforce's compiled Radau against scipy's Radau (rtol 1e-10) on the same run: 20 um/s from -6.5 nm
    (the window up to contact; the full plan run at 20 um/s, from -40 nm, agreed as well: -469.09 pN both)."""
    cfg = SimulationConfig(model="beam", xi=0.0, velocity=20e-6, sample_rate=40e3, start=-6.5e-9, turn=20e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DynamicsWarning)
        ev = simulate(cfg).events
    ref = reference_solve(cfg, rtol=1e-10, atol=1e-16, t_stop=-cfg.start / cfg.velocity, fine_points=20001)
    assert ref.min_apparent_deflection == pytest.approx(ev.min_apparent_deflection, rel=1e-4)
    assert ref.contact_position == pytest.approx(ev.contact_position, rel=1e-5)
    k = cfg.force_constant
    assert k * ref.min_apparent_deflection == pytest.approx(k * (ref.contact_position + cfg.contact_separation),
                                                            rel=0.01)
