"""The drift step's compiled kernels (analysis._drift_kernel, issue 35 item 2).

The kernels must give the numbers of the numpy code of analysis.drift bit for bit where they
reach every sample (the baseline lines), and its choices; their robust fits are checked against
a plain numpy bisquare IRLS written here, their medians against ``np.median``.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis import _drift_kernel as K
from afmforce.analysis import drift as D
from afmforce.analysis._numeric import irls_bisquare, median_near
from afmforce.analysis.regions import RunRegions

DATA = Path(__file__).resolve().parents[1] / "data"


def _plain_bisquare(X, y, n_iter=6, tuning=4.685):
    """Tukey bisquare IRLS in plain numpy (lstsq on sqrt-weighted rows; MAD scale), written from
    the definition, independently of the library's loops."""
    w = np.ones(y.size)
    coef = np.linalg.lstsq(X, y, rcond=None)[0]
    sigma = 0.0
    for _ in range(n_iter):
        r = y - X @ coef
        sigma = 1.4826 * np.median(np.abs(r - np.median(r)))
        if not sigma > 0:
            break
        u = r / (tuning * sigma)
        w = np.where(np.abs(u) < 1, (1 - u**2) ** 2, 0.0)
        sw = np.sqrt(w)
        new = np.linalg.lstsq(X * sw[:, None], y * sw, rcond=None)[0]
        moved = np.sum(np.abs(new - coef))
        coef = new
        if moved < 1e-4 * sigma:
            break
    return coef, sigma


def _design(rng, n, p):
    t = np.linspace(0, 1, n)
    X = np.column_stack([np.ones(n), t, 1 / (1.1 - t) ** 2][:p])
    X = np.ascontiguousarray(X / np.max(np.abs(X), axis=0))
    y = X @ rng.normal(size=p) + rng.normal(0, 0.01, n)
    y[rng.integers(0, n, n // 20)] += 0.5  # outliers the bisquare weights reject
    return X, y


@pytest.mark.parametrize("n,p", [(40, 1), (301, 2), (1344, 2), (1344, 3), (4001, 3), (2000, 1)])
def test_robust_fit_is_a_bisquare_irls(n, p):
    """_numeric.irls_bisquare (the drift kernels' robust fit, bracketed medians) equals a plain
    numpy bisquare IRLS (other solvers: to rounding)."""
    rng = np.random.default_rng(n + p)
    X, y = _design(rng, n, p)
    coef, sigma, ssr, ok = irls_bisquare(X, y, 6, 4.685)
    assert ok
    c_ref, s_ref = _plain_bisquare(X, y)
    np.testing.assert_allclose(coef, c_ref, rtol=1e-9, atol=1e-12)
    assert sigma == pytest.approx(s_ref, rel=1e-9)
    assert ssr > 0


@pytest.mark.parametrize("n,p", [(40, 1), (301, 2), (1344, 3), (4001, 2)])
def test_uncompiled_robust_fit_is_the_compiled_one(n, p):
    """What runs uncompiled (the first run after an install: drift._irls_seq, numpy calls with
    ordered sums) gives irls_bisquare's numbers bit for bit."""
    rng = np.random.default_rng(7 * n + p)
    X, y = _design(rng, n, p)
    c1, s1, q1, ok1 = D._irls_seq(X, y, 6, 4.685)
    c2, s2, q2, ok2 = irls_bisquare(X, y, 6, 4.685)
    assert ok1 and ok2 and np.array_equal(c1, c2) and s1 == s2 and q1 == q2


def test_median_is_numpys():
    """The bracketed median (_numeric.median_near) is np.median exactly: even and odd sizes, ties, brackets that hold the
    middle and brackets that miss it (then a full selection)."""
    rng = np.random.default_rng(5)
    for n in (1, 2, 3, 64, 65, 66, 300, 1343, 1344):
        for x in (rng.normal(size=n), np.round(rng.normal(size=n), 1), np.full(n, 0.25)):
            buf = np.empty(n)
            m = float(np.median(x))
            for guess, width in ((0.0, 0.0), (m, 0.05), (m + 0.3, 0.1), (m, 1e-300), (-5.0, 1.0), (m, 10.0)):
                assert median_near(x, guess, width, buf) == m, (n, guess, width)


def _settling_run(seed, slope=0.02, jump=0.0, amplitude=-6e-3, n=165):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 2000.0 + 0.408
    s = 0.05 + slope * t + jump + amplitude * np.exp(-(t - t[0]) / 6.5e-3) + rng.normal(0, 1e-3, n)
    return t, s


def test_tau_is_geomspaces():
    """drift._tau gives np.geomspace's element bit for bit (the settling times of the winner)."""
    rng = np.random.default_rng(11)
    for _ in range(300):
        a = 10 ** rng.uniform(-9, 2)
        b = a * 10 ** rng.uniform(0.01, 5)
        g = np.geomspace(a, b, 16)
        assert [D._tau(a, b, 16, k) for k in range(16)] == list(g)


@pytest.mark.parametrize("p", [1, 2])
def test_family_coef_is_the_familys(p):
    """family_coef (the winning settling column's system alone) gives _family's coefficients bit
    for bit, with and without a winning column."""
    seen = set()
    for seed in range(12):
        for amplitude in (-6e-3, 6e-3):
            t, s = _settling_run(seed, amplitude=amplitude, n=165 + 97 * seed)
            u = (t - t[0] + 0.2) / (t[-1] - t[0] + 0.2)
            X = u[:, None] if p == 1 else np.column_stack([np.ones_like(u), u])
            y = s - (0.05 + 0.02 * (t[0] - 0.2))  # from the approach line's value at the turn
            E = D._transient(t)
            _, coef, k = D._family(X, y, E, (4.685e-3) ** 2)
            assert np.array_equal(D.family_coef(X, y, t, k), coef)
            seen.add(k >= 0)
    assert seen == {True, False}


def _regions(kind, index, zero_force):
    n = index.size
    none = np.zeros(n, bool)
    return RunRegions(kind=kind, index=index, split=int(np.argmax(~zero_force)) if kind == "approach" else 0,
                      contact=~zero_force, zero_force=zero_force, compliance=none, saturated=none)


def _curve(kind, seed=0, n=400, dwell=0):
    """A synthetic record: an approach and a retract of ``n`` samples (contact in the last/first
    quarter), optionally a dwell between them; the retract's free part with a drift of its own,
    a settling lever, ringing (noisy) or the approach's line."""
    rng = np.random.default_rng(seed)
    m = 2 * n + dwell
    t = np.arange(m) / 1000.0
    z = np.concatenate([np.linspace(0, 1e-6, n), np.full(dwell, 1e-6), np.linspace(1e-6, 0, n)])
    s = 0.1 + 0.05 * t + rng.normal(0, 1e-3, m)
    ret = np.arange(n + dwell, m)
    tr = t[ret] - t[ret[0]]
    if kind == "separate":
        s[ret] += 0.02 + 0.3 * tr
    elif kind == "continuous":
        s[ret] += 0.3 * tr
    elif kind == "settling":
        s[ret] += -0.05 * np.exp(-tr / 0.08)
    elif kind == "ringing":
        s[ret] += 0.02 * np.sin(2 * np.pi * 60 * tr) * rng.normal(1, 0.1, n)
    elif kind == "noisy":  # too noisy for a line of its own, 10 mV off the approach line: its own offset
        s[ret] += 0.01 + rng.normal(0, 0.01, n)
    elif kind == "tilt":  # a baseline that follows the position on the way back (numpy's polyfit: the numpy code)
        v = 1e-6 / (t[n - 1] - t[0])
        s[ret] = 0.1 + 0.05 * t[ret[0]] + 0.05 / v * (z[ret] - z[ret[0]]) + rng.normal(0, 8e-3, n)
    contact = np.zeros(n, bool)
    contact[-n // 4:] = True
    app = _regions("approach", np.arange(n), ~contact)
    retr = _regions("retract", ret, ~contact[::-1])
    seg = np.concatenate([np.zeros(n, int), np.full(dwell, 2), np.ones(n, int)])
    return t, s, seg, app, retr, z


@pytest.mark.parametrize("kind", ["separate", "continuous", "approach", "settling", "ringing", "noisy", "tilt"])
@pytest.mark.parametrize("order", [1, 0])
@pytest.mark.parametrize("dwell", [0, 37])
@pytest.mark.parametrize("with_z", [True, False])
def test_compiled_drift_is_the_numpy_code(kind, order, dwell, with_z):
    """remove_drift (the kernels) gives _remove_drift_numpy's corrected signal and result bit for
    bit, on every path: the retract's own line, continued or separate, the approach line, a
    settling lever, a ringing retract (its offset borrowed), orders 0 and 1, a dwell between the
    runs (interpolated), with and without the position (the approach's tail regressor)."""
    t, s, seg, app, ret, z = _curve(kind, seed=len(kind) + order, dwell=dwell)
    args = (t, s, seg, app, ret, "V", order)
    kw = {"z": z if with_z else None}
    out, res = D.remove_drift(*args, **kw)
    out0, res0 = D._remove_drift_numpy(*args, **kw)
    assert np.array_equal(out, out0)
    assert dataclasses.astuple(res) == dataclasses.astuple(res0)


def test_settling_test_is_the_numpy_codes():
    """The kernel's settling test (a relaxation, not a drift line) answers as drift.is_settling:
    relaxations of several depths and times, a line, a bow the other way."""
    t = np.arange(300) / 1000.0
    rng = np.random.default_rng(9)
    answers = []
    for a, tau in ((-0.05, 0.08), (-0.2, 0.1), (-0.05, 0.2), (-0.01, 0.02), (0.0, 1.0), (0.05, 0.08)):
        s = 0.1 + 0.05 * t + a * np.exp(-t / tau) + rng.normal(0, 1e-3, t.size)
        answers.append(D.is_settling(t, s))
        assert K.is_settling(t, s) == (answers[-1], True)
    s = 0.1 + 0.5 * (t - 0.15) ** 2 + rng.normal(0, 1e-3, t.size)  # a bow: both ways
    assert K.is_settling(t, s) == (D.is_settling(t, s), True) == (False, True)
    assert set(answers) == {True, False}


def test_real_curves_are_the_numpy_code(monkeypatch):
    """On real files (a 4,000-sample JPK curve, a JPK record with pauses, a Bruker curve with a
    ringing retract), the pipeline's drift step gives the numpy code's numbers bit for bit."""
    from afmforce.analysis.pipeline import analyze
    from afmforce.analysis.steps import drift as step
    from afmforce.io import load

    compared = []

    def both(*a, **k):
        out, res = D.remove_drift(*a, **k)
        out0, res0 = D._remove_drift_numpy(*a, **k)
        assert np.array_equal(out, out0) and dataclasses.astuple(res) == dataclasses.astuple(res0)
        compared.append(res.retract_line)
        return out, res

    monkeypatch.setattr(step, "remove_drift", both)
    overrides = json.loads((DATA / "meta_override.json").read_text())
    for name in ("jpk_cellhesion_spot3.jpk-force", "afmformats_jpk-sr_cell1-0008.jpk-force",
                 "bruker-nanoscope_PyFMlab_Egel4_00025.spm"):
        analyze(load(DATA / name, meta_override=overrides.get(name))[0])
    assert len(compared) == 3
