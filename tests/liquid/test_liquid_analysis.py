"""Liquid-curve analysis (issue 25): a colloid probe in water simulated, recorded by the
``liquid`` virtual AFM (curved photodiode response, drift, noise), written as a raw file and
read back, then calibrated with a quadratic compliance, zeroed without a human, the drag
baselines measured and the DLVO forces fitted -- against the simulation's truth."""

import warnings

import numpy as np
import pytest

from afmforce.analysis.liquid import (drag_baselines, fit_dlvo, quadratic_compliance,
                                      split_drainage, velocity_force_fit)
from afmforce.dynamics import simulate
from afmforce.instrument import get_preset
from afmforce.io.native.rawfile import read_raw, write_raw

K = 0.1
CFG = dict(model="spring", spring_constant=K, mass=1e-11, radius=5e-6, geometry="sphere-flat",
           hamaker=1e-20, viscosity=0.89e-3, permittivity=78.4, double_layer="constant_potential",
           surface_potential=-0.03, debye_length=10e-9, lever_drag=1e-5, z0=1e-9,
           start=-400e-9, turn=150e-9, end=-400e-9)


def _record(tmp_path, velocity, rate, seed):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tr = simulate(velocity=velocity, sample_rate=rate, **CFG)
    path = write_raw(get_preset("liquid").record(tr, seed=seed), tmp_path / f"liquid_{seed}.txt")
    return tr, read_raw(path)


def _calibrate(raw, far):
    z, v, seg = raw.piezo_measured, raw.deflection_signal, raw.segment
    a, r = seg == 0, seg == 1
    mid = 0.5 * (z.min() + far)
    pa = np.polyfit(z[a][z[a] < far], v[a][z[a] < far], 1)
    pr = np.polyfit(z[r][z[r] < far], v[r][z[r] < far], 1)
    v0 = 0.5 * (np.polyval(pa, mid) + np.polyval(pr, mid))    # the drag cancels
    return z, v, a, r, quadratic_compliance(z[a], v[a], v0)


def test_quadratic_compliance_zero_and_dlvo_fit(tmp_path):
    tr, raw = _record(tmp_path, 1e-6, 2e3, seed=3)
    assert raw.deflection_unit == "V"
    z, v, a, r, cal = _calibrate(raw, -250e-9)
    # photodiode: V = (d + d^2/L)/s + offset, s = 30 nm/V, L = 3 um -> d = s u - s^2 u^2 / L + ...
    assert cal.a == pytest.approx(30e-9, rel=0.01)
    assert cal.c == pytest.approx(-30e-9**2 / 3e-6, rel=0.2)
    d = cal.deflection(v)
    assert np.max(np.abs(d - np.interp(raw.time, tr.time, tr.deflection))) < 0.5e-9
    h = cal.separation(z, v, h_contact=1e-9 / 2 ** (1 / 3))
    assert np.max(np.abs(h - np.interp(raw.time, tr.time, tr.separation))[a]) < 0.5e-9
    # DLVO on the approach before the jump, the (known) drainage in the model
    db = drag_baselines(z[a], d[a], z[r], d[r], -250e-9)
    ha, ta = h[a], raw.time[a]
    fa = K * (d[a] - db.approach[0] - db.approach[1] * z[a])
    jump = int(np.argmin(np.diff(ha)))
    sel = (np.arange(ha.size) < jump) & (ha > 2e-9) & (ha < 120e-9)
    fit = fit_dlvo(ha[sel], fa[sel], 5e-6, sigma=K * 0.05e-9, z0=1e-9, h_dot=np.gradient(ha, ta)[sel],
                   viscosity=0.89e-3)
    assert fit.surface_potential == pytest.approx(-0.03, rel=0.10)
    assert fit.debye_length == pytest.approx(10e-9, rel=0.05)
    assert fit.stderr["debye_length"] < 0.05 * fit.debye_length


def test_drag_baselines_give_the_lever_drag_and_split_drainage(tmp_path):
    v = 20e-6
    tr, raw = _record(tmp_path, v, 20e3, seed=5)
    z, vs, a, r, cal = _calibrate(raw, -250e-9)
    d = cal.deflection(vs)
    db = drag_baselines(z[a], d[a], z[r], d[r], -250e-9, spring_constant=K, v_app=v, v_ret=v)
    # gap = 2 (c + 6 pi eta R^2 / h) v / k: the lever drag plus the long-ranged drainage at the
    # far region's middle (z = -325 nm, h ~ 325 nm); drift and noise are < 0.1 nm over the run
    beta = 6 * np.pi * 0.89e-3 * (5e-6) ** 2
    assert db.lever_drag == pytest.approx(1e-5 + beta / 325e-9, rel=0.03)
    # at equal separation the velocity part is v (c + beta / h) far out: c and eta R^2 in situ
    h = cal.separation(z, vs)
    hs, fs, fv = split_drainage(h[a], K * d[a], h[r], K * d[r])
    vf = velocity_force_fit(hs, fv, v, 60e-9, 350e-9)
    c, b = vf.lever_drag, vf.drainage_coefficient
    assert c == pytest.approx(1e-5, rel=0.05) and b == pytest.approx(beta, rel=0.1)
    assert vf.undetermined == "" and abs(c - 1e-5) < 4 * vf.lever_drag_se and abs(b - beta) < 4 * vf.drainage_coefficient_se
    far = (hs > 150e-9) & (hs < 350e-9)     # (closer in, the retract still relaxes from pull-off)
    noise = K * 0.05e-9       # force noise of one sample (0.03 nm white + 0.03 nm 1/f)
    assert np.max(np.abs(fs[far])) < 5 * noise and abs(np.mean(fs[far])) < 0.015 * 1e-5 * v


def test_dlvo_intervals_cover_the_truth_under_correlated_noise():
    """fit_dlvo on the weak-overlap closed form (2 pi R 2 eps eps0 kappa psi^2 e^-kappa h) minus vdW
    A R / 6 h^2 with AR(1) force noise of correlation time 39 samples (drift and 1/f noise of a real
    curve), 20 draws: the white-noise covariance covered psi 7, 1/kappa 9 and A 15 times in 20 (its
    standard errors ~3x too small); widened by the residuals' correlation time, at least 15 each."""
    import math

    eps0, eps, R = 8.8541878128e-12, 78.4, 5e-6
    psi, lam, A, sig, a = -0.03, 10e-9, 1e-20, 5e-12, 0.95
    h = np.linspace(60e-9, 2e-9, 300)
    truth = 2 * math.pi * R * 2 * eps * eps0 / lam * psi ** 2 * np.exp(-h / lam) - A * R / (6 * h ** 2)
    covered = np.zeros(3)
    for seed in range(20):
        rng = np.random.default_rng(seed)
        e = rng.normal(0, sig * math.sqrt(1 - a * a), h.size)
        noise = np.empty(h.size)
        noise[0] = rng.normal(0, sig)
        for i in range(1, h.size):
            noise[i] = a * noise[i - 1] + e[i]
        fit = fit_dlvo(h, truth + noise, R, sigma=sig, law="weak_overlap", z0=0.0, guess=(-0.02, 12e-9, 1e-20))
        got = np.array([fit.surface_potential, fit.debye_length, fit.hamaker])
        se = np.array([fit.stderr[k] for k in ("surface_potential", "debye_length", "hamaker")])
        covered += np.abs(got - [psi, lam, A]) < 1.96 * se
        assert fit.correlation_time > 5
    assert (covered >= 15).all(), covered


def test_drag_baselines_standard_error_covers_the_offset():
    """Far lines d = a + b z of both runs offset by a known gap (0 and 2 nm) with AR(1) noise
    (correlation time 19 samples, rms 0.3 nm), 20 draws each: gap +- 1.96 se holds the truth at
    least 17 times; with no drag the interval reaches 0 (the step then says undetermined)."""
    import math

    k, v = 0.1, 1e-6
    z = np.linspace(-400e-9, -200e-9, 400)
    for true_gap in (0.0, 2e-9):
        covered = 0
        for seed in range(20):
            rng = np.random.default_rng(seed)
            runs = []
            for sign in (0.5, -0.5):
                e = rng.normal(0, 0.3e-9 * math.sqrt(1 - 0.81), z.size)
                n = np.empty(z.size)
                n[0] = rng.normal(0, 0.3e-9)
                for i in range(1, z.size):
                    n[i] = 0.9 * n[i - 1] + e[i]
                runs.append(1e-9 + 0.01 * z + sign * true_gap + n)
            db = drag_baselines(z, runs[0], z, runs[1], -200e-9, spring_constant=k, v_app=v, v_ret=v)
            covered += abs(db.gap - true_gap) < 1.96 * db.gap_se
            assert db.lever_drag_se == pytest.approx(k * db.gap_se / (2 * v))
        assert covered >= 17
