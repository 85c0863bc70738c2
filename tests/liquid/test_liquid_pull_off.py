"""The liquid step on README's water run (docs walk, 2026-11-29): a pull-off inside the far region, a
lever that never pulls off, a Hamaker constant at its bound, the medium's own Hamaker constant --
against the simulation's truth and closed forms, never a silent wrong number."""

import argparse
import math
import warnings

import numpy as np
import pytest

from afmforce.analysis.liquid import fit_dlvo
from afmforce.analysis.options import LiquidOptions, ProbeCalibration
from afmforce.analysis.pipeline import analyze
from afmforce.constants import HAMAKER, MEDIA
from afmforce.dynamics import simulate
from afmforce.forces import double_layer_force, effective_radius
from afmforce.instrument import get_preset
from afmforce.io.native.rawfile import read_raw, write_raw

R, V, K = 5e-6, 10e-6, 0.21          # README's water run: the default lever (0.21 N/m), 10 um/s
W = MEDIA["water"]
# README: --double-layer weak_overlap --surface-potential=-30mV --salt-concentration 1mM (9.62 nm)
README = dict(model="spring", mass=1e-11, radius=R, geometry="sphere-flat", viscosity=W["viscosity"],
              permittivity=W["permittivity"], double_layer="weak_overlap", surface_potential=-0.03,
              debye_length=9.62e-9, slip_length=3e-9, velocity=V, start=-300e-9, turn=60e-9, end=-1e-6)
PROBE = ProbeCalibration(radius=R)
OPTS = LiquidOptions(medium="water", double_layer="weak_overlap")


def _analyze(tmp_path, seed, **change):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(**{**README, **change})
    raw = read_raw(write_raw(get_preset("liquid").record(tr, seed=seed), tmp_path / f"w{seed}.txt"))
    return analyze(raw, steps=["liquid"], options=[OPTS], probe=PROBE)


def test_pull_off_inside_the_far_region_is_left_out_of_the_baseline(tmp_path):
    # z0 0.35 nm: the lever pulls off at z = -225 nm, inside the far region (below -192 nm); the
    # retract's in-contact part had made the drag offset 30 nm and the DLVO fit psi -84 mV, 1/kappa 66 nm
    res = _analyze(tmp_path, 1, hamaker=1e-20)
    q = res.details["liquid"]
    assert "liquid" not in res.not_applicable
    beta = 6 * math.pi * W["viscosity"] * float(effective_radius(R, "sphere-flat")) ** 2
    # no lever drag in the run: the offset is the drainage at that distance, 2 beta v / (k h)
    assert q.drag_offset == pytest.approx(2 * beta * V / (K * q.drag_separation), abs=0.3e-9)
    assert abs(q.drainage_coefficient - beta) < 3 * q.drainage_coefficient_se
    assert q.debye_length == pytest.approx(9.62e-9, rel=0.05)
    assert q.surface_potential == pytest.approx(-0.03, rel=0.15)   # -26.7 mV: see docs/liquid.md
    assert 0 < q.hamaker < 3e-20


def test_a_lever_that_never_pulls_off_is_refused_with_the_reason(tmp_path):
    # air's Hamaker constant in water (the old --medium water default): the lever stays in contact and
    # the photodiode clips down to the end; the step had reported a drag offset of 281 nm
    res = _analyze(tmp_path, 2, hamaker=HAMAKER)
    why = res.not_applicable["liquid"]
    assert "never pulls off" in why and "clipped" in why and "liquid" not in res.details


def test_a_pull_off_leaving_too_few_free_samples_says_so(tmp_path):
    res = _analyze(tmp_path, 3, hamaker=1e-20, end=-235e-9)
    why = res.not_applicable["liquid"]
    assert "pulls off at z = " in why and "inside the far region" in why and "no pull-off" not in why


def test_a_hamaker_constant_at_its_bound_is_undetermined_not_a_number():
    # a double layer with an extra short-range repulsion ~ 1/h^2 (a negative Hamaker constant): the fit
    # runs A to its lower bound; that is no estimate of A
    h = np.linspace(2e-9, 60e-9, 300)
    f = np.asarray(double_layer_force(h, R, -0.03, 10e-9, None, 78.4, "weak_overlap", "sphere-flat"))
    f = f + 2e-20 * R / (6 * h ** 2) + np.random.default_rng(4).normal(0, 2e-12, h.size)
    fit = fit_dlvo(h, f, R, sigma=2e-12, law="weak_overlap", guess=(-0.03, 10e-9, 1e-20))
    assert math.isnan(fit.hamaker) and math.isnan(fit.stderr["hamaker"])
    assert "hamaker undetermined" in fit.note and "bound" in fit.note


def test_the_medium_carries_its_hamaker_constant_and_the_flag_wins():
    from afmforce.cli import simulate as S
    from afmforce.cli.simulate import config_from_args

    p = argparse.ArgumentParser()
    for add in S.ARGUMENT_GROUPS:
        add(p)
    base = ["--model", "spring", "--geometry", "sphere-flat", "--radius", "5um"]
    assert config_from_args(p.parse_args(base + ["--medium", "water"])).hamaker == 1e-20
    assert config_from_args(p.parse_args(base + ["--medium", "air"])).hamaker == HAMAKER
    assert config_from_args(p.parse_args(base + ["--medium", "water", "--hamaker", "3e-20J"])).hamaker == 3e-20


def test_a_lever_creeping_into_contact_keeps_its_double_layer(tmp_path):
    # no slip at 10 um/s: the drainage damps the jump-in, the lever creeps in; the steepest step of the
    # approach was then a noise step at 96 nm and the step said "no double-layer repulsion"
    res = _analyze(tmp_path, 1, hamaker=1e-20, slip_length=0.0)
    q = res.details["liquid"]
    assert "liquid" not in res.not_applicable, res.not_applicable
    assert q.debye_length == pytest.approx(9.62e-9, rel=0.06)
    assert q.hamaker == pytest.approx(1e-20, rel=0.15)
