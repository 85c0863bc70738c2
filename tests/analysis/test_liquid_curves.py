"""Curves in a liquid, analysed as typed (``afmforce analyze FILE``, no liquid options): a long-range
double-layer repulsion lifts the approach over several Debye lengths before a rigid contact.

The virtual AFM's liquid instrument records a colloid probe (R = 5 um, k = 0.21 N/m) approaching a flat in
water, 0.1 mM salt (Debye length 30.4 nm, closed form), -80 mV on both surfaces, a weak van der Waals
attraction: no jump into contact (the tip creeps in), no adhesion. Before the fix the contact region's
curvature (the double layer's exponential before the straight contact line) made the contact "soft", its
contact point 122 nm before the surface (the double layer's onset) and an "indentation" of 79 nm on a rigid
flat (:func:`afmforce.analysis.steps.kind._surface_force_before_line`).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce import forces
from afmforce.analysis.pipeline import analyze
from afmforce.cli.main import main
from afmforce.io import load

SIM = ["simulate", "--model", "spring", "--mass", "10ng", "--geometry", "sphere-flat", "--medium", "water",
       "--radius", "5um", "--double-layer", "weak_overlap", "--surface-potential=-80mV",
       "--salt-concentration", "0.1mM", "--hamaker", "1e-21", "--slip-length", "3nm", "--velocity", "10um/s",
       "--start=-400nm", "--turn", "200nm", "--turn-force", "20nN", "--end=-400nm", "--instrument", "liquid",
       "--seed", "1", "--no-progress"]


@pytest.fixture(scope="module")
def double_layer(tmp_path_factory):
    path = tmp_path_factory.mktemp("liquid") / "dl.txt"
    assert main(SIM + ["--raw", str(path)]) == 0
    curve = load(str(path))
    curve = curve[0] if isinstance(curve, list) else curve
    names = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")][0].split("\t")
    table = np.loadtxt(path, comments="#", skiprows=1 + sum(ln.startswith("#") for ln in
                                                            path.read_text().splitlines()))
    truth = {n.split(" [")[0]: table[:, i] for i, n in enumerate(names)}
    return curve, truth, analyze(curve)


def test_double_layer_rise_is_not_an_indentation(double_layer):
    _, truth, r = double_layer
    assert r.contact_kind == "hard", r.contact_kind_reason
    assert "surface force" in r.contact_kind_reason
    assert r.indentation is None or not math.isfinite(r.indentation)
    assert r.youngs_modulus is None or not math.isfinite(r.youngs_modulus)
    # the decay length the reason quotes: the Debye length of 0.1 mM 1:1 salt in water within 15 %
    lam = float(r.contact_kind_reason.split("decay length ")[1].split(" nm")[0]) * 1e-9
    debye = forces.debye_length(1e-4)  # I = 0.1 mM = 1e-4 mol/L: 30.4 nm
    assert abs(lam / debye - 1) < 0.15, (lam, debye)


def test_double_layer_contact_is_the_surface(double_layer):
    _, truth, r = double_layer
    # the truth's surface: h = z_s - z + d for every sample, so z_s = h + z - d (one constant)
    zs = truth["truth.separation"] + truth["truth.piezo_position"] - truth["truth.deflection"]
    assert np.ptp(zs) < 1e-12
    zero = r.details["zero"].contact_position
    # within 3 nm (the liquid instrument's sensitivity is 5 % off its fitted slope over a 43 nm deflection),
    # where before it lay 122 nm out, at the double layer's onset
    assert abs(zero - zs[0]) < 3e-9, (zero, zs[0])


def test_no_jump_in_and_no_adhesion_through_a_repulsion(double_layer):
    _, truth, r = double_layer
    assert r.jump_in_separation is None or not math.isfinite(r.jump_in_separation)
    assert r.adhesion_force is None or not math.isfinite(r.adhesion_force)
    # the truth: the force stays repulsive down to contact on the approach (no attractive dip)
    app = truth["segment"] == 0
    assert truth["truth.normal_force"][app].min() > -1e-11
