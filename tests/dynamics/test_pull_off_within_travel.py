"""A retract that ends before the pull-off is not shown with a pull-off force: before, ``afmforce
simulate`` printed "pull-off position z nan" beside "pull-off force -29.97 nN" -- the lever's force
at the end of the travel, k x |end| = 0.1 N/m x 300 nm, read as the adhesion. ``events.pull_off_force``
keeps its documented meaning (the most negative Fz in contact on the retract, which the solve's
guard compares between tolerances); the text says there was no pull-off and names that force as
what it is."""

from __future__ import annotations

import math

import pytest

from afmforce.cli.main import main
from afmforce.dynamics import simulate

nm = 1e-9
SPHERE = dict(model="spring", spring_constant=0.1, mass=10e-12, radius=5e-6, geometry="sphere-flat",
              viscosity=0.89e-3, hamaker=1e-20, velocity=10e-6, start=-300 * nm, turn=60 * nm)
ARGV = ["simulate", "--model", "spring", "--spring-constant", "0.1N/m", "--mass", "10ng", "--radius", "5um",
        "--geometry", "sphere-flat", "--medium", "water", "--hamaker", "1e-20J", "--velocity", "10um/s",
        "--start=-300nm", "--turn", "60nm"]


@pytest.mark.filterwarnings("ignore:the retract ended in contact")
def test_no_pull_off_within_the_travel_is_said(capsys):
    short = simulate(**SPHERE, end=-300 * nm)
    e = short.events
    assert math.isfinite(e.contact_time) and math.isnan(e.pull_off_position)
    # what the old line called the pull-off force: the lever's force at the end of the retract
    assert e.pull_off_force == pytest.approx(short.spring_constant * short.deflection[-1], rel=0.01)
    assert e.pull_off_force == pytest.approx(-30 * nm, rel=0.01)
    assert main(ARGV + ["--end=-300nm"]) == 0
    out = capsys.readouterr().out
    assert "pull-off force" not in out and "pull-off position" not in out
    assert "none: still in contact at the end of the retract (z = -300 nm); retract further (end)" in out
    line = next(x for x in out.splitlines() if "most negative force in contact" in x)
    assert line.split()[-2:] == [f"{e.pull_off_force / nm:.5g}", "nN"]


def test_a_retract_far_enough_shows_its_pull_off(capsys):
    long = simulate(**SPHERE, end=-600 * nm)
    e = long.events
    assert math.isfinite(e.pull_off_position) and e.pull_off_position > -600 * nm
    assert e.pull_off_force < -30 * nm           # beyond the bound the short retract reached
    assert e.pull_off_force == pytest.approx(long.normal_force[long.segment == 1].min(), rel=0.01)
    assert main(ARGV + ["--end=-600nm"]) == 0
    out = capsys.readouterr().out
    assert "pull-off force" in out and f"{e.pull_off_force / nm:.5g} nN" in out and "none: still" not in out


@pytest.mark.filterwarnings("ignore:the retract ended in contact")
def test_the_summary_a_sweep_tabulates_has_no_pull_off_force_without_a_pull_off():
    """``Trajectory.summary()`` (the sweep's columns, the web's and `simulate --json`'s summary):
    NaN for both pull-off entries when the retract ends in contact, the event's force otherwise."""
    short = simulate(**SPHERE, end=-300 * nm).summary()["pull_off"]
    assert math.isnan(short["piezo_position"]) and math.isnan(short["force"])
    long = simulate(**SPHERE, end=-600 * nm)
    assert long.summary()["pull_off"]["force"] == long.events.pull_off_force < -30 * nm
