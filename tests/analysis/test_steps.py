"""The analysis steps one by one: closed forms, the paper's numbers, quasi-static round trips.

Synthetic curves come from :func:`afmforce.analysis.synthetic.static_curve` (static
equilibrium k z2 = Fs(z2 - z) on the stable branch, spec sections 1-2), whose truth
is computed independently of the analysis (root bracketing on a grid + bisection).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce import forces
from afmforce.analysis import (adhesion, diagnose_curve, effective_spring_constant, fit_fringes, fit_vdw,
                               oscillation_origin, position_map)
from afmforce.analysis._numeric import largest_step, robust_line, running_mean, two_line_split
from afmforce.analysis.compliance import ComplianceLine, ComplianceResult, ShiftResult, friction_signature
from afmforce.analysis.jumps import PullOff
from afmforce.analysis.oscillation import find_peak
from afmforce.analysis.synthetic import static_curve
from afmforce.constants import FIG3
from afmforce.analysis.options import FringesOptions
from afmforce.analysis.pipeline import analyze

K, R, A = 0.21, 220e-9, 5e-19  # Fig 9 theory (constants.FIG9)


# --- numerical kernels ------------------------------------------------------------------------
def test_running_mean_keeps_lines_and_levels_a_staircase():
    """Section 3.1: the running average interpolates linearly between digitization levels."""
    x = np.linspace(-3.0, 7.0, 101)
    np.testing.assert_allclose(running_mean(x, 11), x, rtol=0, atol=1e-12)  # exact on a line, ends too
    stairs = np.floor(x / 1.0)  # 1.0 steps, 10 samples per step
    smooth = running_mean(stairs, 21)
    assert np.max(np.abs(smooth - (x - 0.45))[15:-15]) < 0.3  # within a third of a step of the line


def test_two_line_split_finds_the_break():
    x = np.linspace(0, 1, 200)
    y = np.where(x < 0.6, 0.01 * x, 5 * (x - 0.6))
    assert two_line_split(x, y, 5) == int(np.argmax(x >= 0.6))


def test_robust_line_ignores_spikes():
    rng = np.random.default_rng(0)
    x = np.linspace(0, 1, 300)
    y = 2.0 + 3.0 * x + 0.01 * rng.standard_normal(300)
    y[::37] += 5.0  # spikes
    a, b, se_a, se_b, sigma, n = robust_line(x, y)
    assert a == pytest.approx(2.0, abs=5e-3) and b == pytest.approx(3.0, abs=1e-2)
    # a MAD-based scale from ~290 inliers: ~5 % standard error; measured 1.088 x the true 0.01
    assert sigma == pytest.approx(0.01, rel=0.12) and n < 300


def test_largest_step():
    d = np.array([0.0, 0.5, -3.0, -2.9, 4.0])
    assert largest_step(d, 0, 5, -1.0) == 1 and largest_step(d, 0, 4, 1.0) == 0


# --- force conversion: eqs 13 and 14 ---------------------------------------------------------
def test_tilt_correction_eq14_and_eq13():
    """eq 14: k = k0 / cos^2 theta0 = 1.07 k0 at -15 deg; eq 13 with the Fig 3 geometry:
    k = 0.1375 N/m for k0 = 0.13 N/m (spec section 4.1)."""
    c14 = effective_spring_constant(0.13, theta0=math.radians(-15))
    assert c14.method == "eq 14" and c14.tilt_factor == pytest.approx(1 / math.cos(math.radians(15)) ** 2)
    assert c14.tilt_factor == pytest.approx(1.07, abs=0.005)
    c13 = effective_spring_constant(FIG3["k0"], theta0=FIG3["theta0"], L0=FIG3["L0"], L1=FIG3["L1"],
                                    L2=FIG3["L2"])
    assert c13.method == "eq 13" and c13.spring_constant == pytest.approx(0.1375, abs=5e-4)
    assert effective_spring_constant(None).method == "none"


# --- adhesion: section 2.1 ----------------------------------------------------------------------
def test_radius_from_jump_out_distance():
    """Section 2.1 / spec 2: a 200 nm jump-out with k = 0.21 N/m gives R = 220 nm (JKR,
    gamma = A/(16 pi z0^2) = 0.081 J/m^2); and gamma back from that R."""
    po = PullOff(True, 10, -200e-9, -200e-9, -K * 200e-9, 200e-9, 100.0, False)
    res = adhesion(po, K, radius=220e-9)
    assert res.radius == pytest.approx(220e-9, rel=0.01)
    assert res.surface_energy == pytest.approx(forces.surface_energy(A), rel=0.01)
    assert adhesion(po, K, model="dmt").radius == pytest.approx(0.75 * res.radius)


# --- van der Waals fit: eq 2 -------------------------------------------------------------------
def test_vdw_fit_recovers_eq2_exactly_and_reports_errors():
    h = np.linspace(4.5e-9, 30e-9, 200)
    f = forces.vdw_force(h, R, A)
    fit = fit_vdw(h, f, spring_constant=K, radius=R)
    assert fit.hamaker_radius == pytest.approx(A * R, rel=1e-6)
    assert fit.hamaker == pytest.approx(A, rel=1e-6)
    # static jump-in of the fitted law: 4.4 nm (spec section 2)
    assert fit.static_jump_in_separation == pytest.approx(4.4e-9, abs=0.05e-9)
    rng = np.random.default_rng(1)
    errs = []
    for _ in range(20):  # the standard error describes the scatter (0.05 nm deflection noise)
        fn = fit_vdw(h, f + K * 0.05e-9 * rng.standard_normal(h.size), spring_constant=K)
        errs.append((fn.hamaker_radius - A * R) / fn.hamaker_radius_se)
    assert 0.5 < np.std(errs) < 1.6


# --- quasi-static round trips (the generator's truth) --------------------------------------------
@pytest.mark.parametrize("seed", [1, 2])
def test_quasi_static_round_trip(seed):
    """beta within 1 %, zero of separation within 0.3 nm, A R within 10 % at 0.05 nm noise,
    jump-in and pull-off within one sample; drift and offset removed."""
    c = static_curve(noise=0.05e-9, drift=0.01, offset=0.3, seed=seed)
    res = analyze(c)
    t = c.truth
    assert res.sensitivity_fit == pytest.approx(t["sensitivity"], rel=0.01)
    free = (c.segment == 0) & (t["separation"] > 1e-9)
    assert abs(np.median(res.separation[free] - t["separation"][free])) < 0.3e-9
    assert res.hamaker_radius == pytest.approx(A * R, rel=0.10)
    assert abs(res.details["jumps"].jump_in.index - t["jump_in_index"]) <= 1
    assert abs(res.details["jumps"].pull_off.index - t["pull_off_index"]) <= 1
    # pull-off of a rigid contact: the largest attraction -A R / (16 z0^2) (eq 2)
    assert res.pull_off_force == pytest.approx(forces.max_attraction_force(R, A), rel=0.03)


def test_inserted_shift_is_recovered():
    """Move the inward run's recorded positions by +7 nm (the size of Fig 9C's shift): the
    shift step finds -7 nm (it overlays inward onto outward) within 2 nm, and the offset
    (inward line to the right of the outward one) reads as friction's direction (spec 7)."""
    c = static_curve(noise=0.05e-9, seed=5)
    z = c.piezo_measured.copy()
    z[c.segment == 0] += 7e-9
    import dataclasses
    res = analyze(dataclasses.replace(c, piezo_measured=z))
    assert res.shift == pytest.approx(-7e-9, abs=2e-9)
    assert res.friction == "constant"
    assert res.details["friction"].offset == pytest.approx(7e-9, abs=2e-9)


def test_fringe_calibration_maps_nominal_to_true_position():
    """Spec section 6: fringes I0 cos(2 pi D / P) in the baseline expose a nonlinear nominal
    piezo (3 % and -2 % quadratic bends, different per run: a loop). The fitted map leaves a
    residual under 1 % of the range; with the fringe period known, the absolute scale within 1 %."""
    c = static_curve(start=-1000e-9, turn=40e-9, end=-1200e-9, fringe_amplitude=0.02, fringe_period=320e-9,
                     piezo_quadratic=(0.03, -0.02), noise=0.05e-9, velocity=2e-6, sample_rate=4000, seed=4)
    for period in (None, 320e-9):
        res = analyze(c, steps=["fringes"], options=[FringesOptions(period=period)])
        fr = res.details["fringes"]
        assert fr.applied and fr.approach.found and fr.retract.found
        for seg, run in ((0, fr.approach), (1, fr.retract)):
            m = c.segment == seg
            u = position_map(c.piezo_nominal[m], run)
            zt = c.truth["position"][m]
            p = np.polyfit(u, zt, 1)
            assert np.ptp(zt - np.polyval(p, u)) < 0.01 * np.ptp(zt)
            if period:
                assert p[0] == pytest.approx(1.0, abs=0.01)
        assert res.details["fringes"].approach.period == pytest.approx(320e-9, rel=0.05)


def test_no_fringes_on_a_clean_baseline():
    c = static_curve(start=-600e-9, noise=0.05e-9, seed=2)
    fr = analyze(c, steps=["fringes"]).details["fringes"]
    assert not fr.applied and not (fr.approach.found and fr.retract.found)


def test_fit_fringes_alone():
    z = np.linspace(0, 2e-6, 3000)
    r = 0.01 * np.cos(2 * np.pi * z / 300e-9 + 0.4) + 1e-4 * np.random.default_rng(0).standard_normal(z.size)
    f = fit_fringes(z, r)
    assert f.found and f.period == pytest.approx(300e-9, rel=1e-3) and f.amplitude == pytest.approx(0.01, rel=0.02)


# --- friction signature: sections 2.2.2-2.2.4 ----------------------------------------------------
def _line(slope, z_at_zero):
    return ComplianceLine(intercept=-slope * z_at_zero, slope=slope, intercept_se=1e-4, slope_se=slope * 1e-4,
                          sigma=1e-3, n_points=100, z_min=0.0, z_max=20e-9, s_min=0.0, s_max=slope * 20e-9)


@pytest.mark.parametrize("app,ret,shift,kind", [
    ((2e7, 0.0), (2e7, 0.0), 0.0, "not detected"),  # coincident: bounded, not excluded
    ((2e7, 0.76e-9), (2e7, 0.0), -0.76e-9, "constant"),  # Fig 3: inward 0.76 nm to the right
    ((2e7, -57e-9), (2e7, 0.0), 57e-9, "opposite"),  # Fig 7B: backlash
    ((2.4e7, 0.0), (2e7, 0.0), 0.0, "load-proportional"),  # Fig 4: non-parallel
    ((-2e7, 0.0), (-2e7, 0.0), 0.0, "pinned"),  # eqs 20-21: negative calibration
])
def test_friction_signature(app, ret, shift, kind):
    comp = ComplianceResult(_line(*app), _line(*ret), "V")
    sig = friction_signature(comp, ShiftResult(shift, 0.01e-9, 0.2, True))
    assert sig.kind == kind


# --- oscillations: section 3.2 --------------------------------------------------------------------
def test_oscillation_peak_and_origin():
    """640 Hz in a 2.7 kHz record is found; white noise alone is not (false alarm 1e-3)."""
    rng = np.random.default_rng(3)
    t = np.arange(1500) / 2700.0
    noise = 0.05e-9 * rng.standard_normal(t.size)
    peak = find_peak(t, 0.3e-9 * np.sin(2 * np.pi * 640 * t) + noise, 1.36e-6, "approach")
    assert peak.found and peak.frequency == pytest.approx(640, rel=0.01)
    assert peak.wavelength == pytest.approx(1.36e-6 / 640, rel=0.01)
    assert not find_peak(t, noise, 1.36e-6, "approach").found


def test_oscillation_origin_paper_numbers():
    """Fig 9B/C: 640 Hz at 1.36 um/s and 670 Hz at 2.0 um/s -> the same temporal frequency."""
    assert oscillation_origin([640, 670], [1.36e-6, 2.0e-6])[0] == "temporal"
    assert oscillation_origin([640, 640 * 2.0 / 1.36], [1.36e-6, 2.0e-6])[0] == "spatial"
    assert oscillation_origin([640], [1.36e-6])[0] == "undetermined"
    assert oscillation_origin([], [])[0] == "none"


# --- dynamic diagnosis: eqs 3, 4 -------------------------------------------------------------------
def test_diagnosis_inertia_parameter_and_lag():
    """Spec section 3, Fig 1 (f = 0.73 kHz, dx = 0.5 nm): lag v/(4f) = 3.4 nm at 10 um/s and
    0.34 nm at 1 um/s; at the jump Fs' = k so R = v / (4 f dx): 6.8 (dynamic) and 0.68."""
    f = math.sqrt(0.21 / 1e-8) / (2 * math.pi)
    fast = diagnose_curve(velocity=10e-6, spring_constant=0.21, resonance_frequency=f, resolution=0.5e-9,
                          force_gradient=0.21)
    slow = diagnose_curve(velocity=1e-6, spring_constant=0.21, resonance_frequency=f, resolution=0.5e-9,
                          force_gradient=0.21)
    assert fast.inertial_lag == pytest.approx(3.4e-9, rel=0.02) and slow.inertial_lag == pytest.approx(0.34e-9, rel=0.02)
    assert fast.inertia_parameter == pytest.approx(10e-6 / (4 * f * 0.5e-9)) and fast.dynamic
    assert slow.inertia_parameter < 1 and not slow.dynamic
    unknown = diagnose_curve(velocity=1e-6, spring_constant=0.21, resonance_frequency=None, resolution=0.5e-9)
    assert not unknown.dynamic and "unknown" in unknown.verdict
    # issue 13: never a default stand-in for the gradient: without a measured one, not assessed
    blind = diagnose_curve(velocity=10e-6, spring_constant=0.21, resonance_frequency=f, resolution=0.5e-9)
    assert math.isnan(blind.inertia_parameter) and "force gradient not measured" in blind.verdict


def test_diagnosis_flags_a_weak_attraction():
    """eq 2: a rigid contact pulls off at -A R/(16 z0^2); an approach attraction far weaker
    than that (friction, Fig 6) is flagged."""
    f_pull = float(forces.max_attraction_force(R, A))
    ok = diagnose_curve(velocity=1e-6, spring_constant=K, resonance_frequency=None, resolution=0.05e-9,
                        hamaker_radius=A * R, pull_off_force=f_pull, contact_separation=0.35e-9)
    weak = diagnose_curve(velocity=1e-6, spring_constant=K, resonance_frequency=None, resolution=0.05e-9,
                          hamaker_radius=0.4 * A * R, pull_off_force=f_pull, contact_separation=0.35e-9)
    assert ok.attraction_ratio == pytest.approx(1.0) and not ok.dynamic
    assert weak.dynamic and "pull-off" in weak.verdict
