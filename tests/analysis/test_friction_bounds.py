"""Coincident compliance lines bound friction, they never exclude it (spec sections 4.1, 4.2, 7).

The friction signature calls coincident lines "not detected" and carries the largest friction the
lines allow: an offset bound ``|offset| + nsigma se`` (at least the tolerance), a slope bound, and,
with the lever's geometry, the constant friction mu (eq 16), the viscous xi (eq 28 in steady
sliding) and the load-proportional lambda (eqs 18-19) those bounds allow. The conversions are
checked against the spec's numbers (Fig 3: 5 nN -> 0.76 nm; Fig 4: lambda = 2 -> beta 1.3654e5 /
1.2772e5; section 7: xi v = 1e-8 N -> 0.454 nm) and against eqs 16-19 written out here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce import statics
from afmforce.analysis.compliance import ComplianceLine, ComplianceResult, ShiftResult, friction_signature
from afmforce.analysis.dynamic import diagnose_curve
from afmforce.cantilever import InclinedCantilever

TH0 = math.radians(-15.0)
FIG3 = InclinedCantilever(L0=200e-6, L1=2e-6, L2=4e-6, theta0=TH0, k0=0.13)        # spec 4.1
BEAM = InclinedCantilever(L0=200e-6, L1=2e-6, L2=4e-6, theta0=TH0, B=3.5e-13)      # spec 5 (Figs 5-6)


def _eq18_19(c: InclinedCantilever, lam: float, sign: int) -> tuple[float, float]:
    """(k, beta) of eqs 18, 19 as the spec prints them (an independent transcription)."""
    L0, th, a, b, B = c.L0, c.theta0, c.a, c.b, c.B
    cs, sn = math.cos(th), math.sin(th)
    inv_k = ((2 / 3 * L0**3 * cs + a * L0**2) * (cs + sign * lam * sn)
             + (L0**2 * cs + 2 * a * L0) * (a + sign * b * lam)) / (2 * B)
    k = 1 / inv_k
    inv_beta = k / (2 * B) * (L0**2 * (cs + sign * lam * sn) + 2 * L0 * (a + sign * b * lam))
    return k, 1 / inv_beta


def _line(slope: float, z_at_zero: float, se: float = 1e-4) -> ComplianceLine:
    return ComplianceLine(intercept=-slope * z_at_zero, slope=slope, intercept_se=se, slope_se=slope * se,
                          sigma=1e-3, n_points=100, z_min=0.0, z_max=20e-9, s_min=0.0, s_max=slope * 20e-9)


# --- the closed forms ---------------------------------------------------------------------------
def test_constant_friction_from_the_offset_inverts_eq_16():
    # Fig 3: mu = 5 nN offsets the lines by 0.76 nm (the paper's number, 2 digits)
    assert statics.constant_friction_for_offset(FIG3, 0.76e-9) == pytest.approx(5e-9, rel=0.01)
    # spec 7: xi v = 1e-8 N (xi = 0.1 kg/s at 0.1 um/s) offsets the beam's lines by 0.454 nm; in steady
    # sliding mu = xi |dy2/dz2| v, so the offset gives xi back
    mu = statics.constant_friction_for_offset(BEAM, 0.454e-9)
    assert mu / (abs(BEAM.slide_ratio) * 0.1e-6) == pytest.approx(0.1, rel=0.01)
    # a tip on the beam's axis makes no offset: no friction force follows from one
    axis = InclinedCantilever(L0=200e-6, L1=1e-12, L2=0.0, theta0=TH0, k0=0.13)
    assert statics.constant_friction_offset(axis, 5e-9) == pytest.approx(0.0, abs=1e-15)


def test_load_friction_from_the_slope_ratio_inverts_eqs_18_19():
    # Fig 4 (lambda = 2): inward beta 1.3654e5 nm/rad, outward 1.2772e5 (spec 4.2); slopes go as 1/beta
    ratio = 1.2772e5 / 1.3654e5
    assert statics.load_friction_slope_ratio(FIG3, 2.0) == pytest.approx(ratio, rel=2e-4)
    assert statics.load_friction_for_slope_ratio(FIG3, ratio) == pytest.approx(2.0, rel=2e-3)
    for lam in (1e-3, 0.05, 0.7, 3.0):   # the quadratic's root against eqs 18-19 as printed
        k_in, b_in = _eq18_19(FIG3, lam, +1)
        k_out, b_out = _eq18_19(FIG3, lam, -1)
        assert statics.load_friction_for_slope_ratio(FIG3, b_out / b_in) == pytest.approx(lam, rel=1e-9)
    # no lambda below the stability limit makes the ratio 0: undetermined, not a number
    assert math.isinf(statics.load_friction_for_slope_ratio(FIG3, -0.1))


# --- the signature ------------------------------------------------------------------------------
def _signature(mu: float, se: float, **kw):
    """The lines of the Fig 3 lever with constant friction mu (eq 16) and position se [m] each."""
    offset = statics.constant_friction_offset(FIG3, mu)
    slope = 2e7                                    # V/m
    comp = ComplianceResult(_line(slope, offset), _line(slope, 0.0), "V")
    return offset, friction_signature(comp, ShiftResult(-offset, se, 0.2, True), **kw)


def test_friction_below_the_resolution_is_not_detected_and_bounded_above_it():
    """mu = 0.5 nN offsets the lines by 0.076 nm, below the 0.2 nm tolerance: 'not detected', and
    the bound is the tolerance's friction, above the true one: 0.2 nm x 5 nN / 0.76 nm (Fig 3)."""
    offset, sig = _signature(0.5e-9, 0.01e-9, lever=FIG3, velocity=1e-6)
    assert sig.kind == "not detected" and "no sign" not in sig.verdict and "not excluded" in sig.verdict
    assert sig.offset_bound == pytest.approx(max(offset + 3 * 0.01e-9, 0.2e-9))
    assert sig.friction_force_bound == pytest.approx(sig.offset_bound * 5e-9 / 0.76e-9, rel=0.01)
    assert sig.friction_force_bound > 0.5e-9
    assert sig.viscous_friction_bound == pytest.approx(
        sig.friction_force_bound / (abs(FIG3.slide_ratio) * 1e-6), rel=1e-12)
    # the slope bound is the 2 % tolerance: the lambda whose eqs 18-19 slopes differ by 2 %
    assert sig.slope_difference_bound == pytest.approx(max(3 * math.sqrt(2) * 1e-4, 0.02), rel=1e-12)
    k_in, b_in = _eq18_19(FIG3, sig.load_friction_bound, +1)
    k_out, b_out = _eq18_19(FIG3, sig.load_friction_bound, -1)
    assert b_out / b_in == pytest.approx(1 - sig.slope_difference_bound, rel=1e-9)
    assert f"{sig.friction_force_bound * 1e9:.3g} nN" in sig.verdict


def test_noisy_lines_widen_the_bound():
    """The same friction on lines known to 0.2 nm: the bound follows the standard error (3 se + offset)."""
    offset, sig = _signature(0.5e-9, 0.2e-9, lever=FIG3)
    assert sig.kind == "not detected"
    assert sig.offset_bound == pytest.approx(offset + 3 * 0.2e-9)
    assert sig.friction_force_bound == pytest.approx(sig.offset_bound * 5e-9 / 0.76e-9, rel=0.01)
    assert math.isnan(sig.viscous_friction_bound)          # no speed given


def test_friction_above_the_resolution_is_detected():
    offset, sig = _signature(5e-9, 0.01e-9, lever=FIG3)   # Fig 3: 0.76 nm
    assert sig.kind == "constant" and sig.offset == pytest.approx(0.76e-9, rel=0.01)
    assert sig.friction_force_bound >= 5e-9               # an upper bound still, never below the truth


def test_without_the_geometry_the_bound_stays_in_the_lines_units():
    _, sig = _signature(0.5e-9, 0.01e-9)
    assert sig.kind == "not detected" and sig.offset_bound == pytest.approx(0.2e-9)
    assert math.isnan(sig.friction_force_bound) and math.isnan(sig.load_friction_bound)
    assert "geometry" in sig.verdict


def test_artefacts_carry_no_friction_bound():
    comp = ComplianceResult(_line(2e7, -57e-9), _line(2e7, 0.0), "V")    # Fig 7B: backlash
    sig = friction_signature(comp, ShiftResult(57e-9, 0.01e-9, 0.2, True), lever=FIG3)
    assert sig.kind == "opposite" and math.isnan(sig.offset_bound) and math.isnan(sig.friction_force_bound)


def test_not_detected_counts_as_assessed_but_never_clears_friction():
    f = math.sqrt(0.21 / 1e-11) / (2 * math.pi)
    d = diagnose_curve(velocity=1e-6, spring_constant=0.21, resonance_frequency=f, resolution=0.05e-9,
                       force_gradient=0.21, friction="not detected", friction_verdict="friction not detected")
    assert d.assessed and not d.dynamic
    # the old word is no kind any more: a caller passing it gets "not assessed", not a clearance
    old = diagnose_curve(velocity=1e-6, spring_constant=0.21, resonance_frequency=f, resolution=0.05e-9,
                         force_gradient=0.21, friction="none")
    assert not old.assessed


def test_bound_against_numpy_on_a_real_curve(monkeypatch):
    """Asylum MFP-3D, SiN tip in air (hard contact, coincident lines): the offset and the slope ratio
    against least-squares lines numpy fits to the same compliance samples (the library's lines are
    robust, Tukey bisquare: on these clean lines the two agree to a small part of the bound), and the
    bounds hold numpy's offset and slope ratio with their 3-standard-error margins."""
    from realdata import real_file

    import afmforce.analysis.steps.friction as F
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load

    seen = {}
    spy = F._drift_uncertainty

    def keep(st, comp):
        seen["state"] = st
        return spy(st, comp)

    monkeypatch.setattr(F, "_drift_uncertainty", keep)
    curve = load(real_file("asylum-mfp3d_SiN-tip_air.ibw"))
    curve = curve[0] if isinstance(curve, list) else curve
    res = analyze(curve)
    sig, st = res.details["friction"], seen["state"]
    assert res.friction == sig.kind == "not detected"
    lines = {}
    for run in (st.approach, st.retract):
        idx = run.index[run.compliance & ~run.saturated]
        (b, a), cov = np.polyfit(st.z[idx], st.signal[idx], 1, cov=True)
        lines[run.kind] = (a, b, cov, st.z[idx].mean(), idx.size)
    s_ref = res.details["shift"].reference_signal
    z_at = {k: (s_ref - a) / b for k, (a, b, *_) in lines.items()}
    offset = z_at["approach"] - z_at["retract"]
    ratio = lines["approach"][1] / lines["retract"][1]
    # position standard error at s_ref: var(a + b z*) propagated to z* = (s - a) / b
    se = math.hypot(*[math.sqrt(np.array([1.0, z_at[k]]) @ cov[::-1, ::-1] @ np.array([1.0, z_at[k]])) / abs(b)
                      for k, (a, b, cov, *_ ) in lines.items()])
    ratio_se = abs(ratio) * math.hypot(*[math.sqrt(cov[0, 0]) / abs(b) for (a, b, cov, *_ ) in lines.values()])
    assert offset == pytest.approx(sig.offset, abs=0.1 * sig.offset_bound)
    assert ratio == pytest.approx(sig.slope_ratio, abs=0.1 * sig.slope_difference_bound)
    assert sig.offset_bound >= abs(offset) + 3 * se
    assert sig.slope_difference_bound >= abs(ratio - 1) + 3 * ratio_se
