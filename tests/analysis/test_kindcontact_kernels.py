"""The compiled kernels of the kind, contact, compliance and smooth steps (issue 35) against plain numpy
computations of the same quantities: bit for bit where they promise it (sums, means, grids, masks,
indices, regions), to rounding where a solver differs (the contact point's 3 x 3 normal equations)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.analysis import _contact_kernel as K
from afmforce.analysis import _regions_kernel as RK
from afmforce.analysis import _smooth_kernel as SK
from afmforce.analysis import regions
from afmforce.analysis._numeric import robust_line
from afmforce.analysis.contact_point import curvature_ratio, soft_contact_point
from afmforce.analysis.steps.smooth import _smooth_run, _staircase_window

SIZES = [0, 1, 5, 7, 8, 9, 127, 128, 129, 300, 1000, 4001, 8193, 12000]


@pytest.mark.parametrize("n", SIZES)
def test_pairwise_sum_is_numpy_sum_bit_for_bit(n):
    rng = np.random.default_rng(n)
    a = 1e-6 * rng.normal(size=n) + 3.7
    assert K.pairwise_sum(a, 0, n) == np.sum(a)
    if n > 10:
        assert K.pairwise_sum(a, 3, n - 5) == np.sum(a[3:n - 2])


@pytest.mark.parametrize("n", [400, 999, 1000, 1501, 4000, 12000])
def test_block_mean_and_linspace_are_numpy_bit_for_bit(n):
    x = np.cumsum(np.random.default_rng(n).normal(size=n))
    m = n // 500
    expect = x if m <= 1 else x[:(n // m) * m].reshape(n // m, m).mean(1)
    assert np.array_equal(K.block_mean(x, 500), expect)
    for lo, hi, num in ((0.0, 1.0, n), (0.137, 0.437, 121), (0.2, 0.2, 41), (0.31, 0.3125, 41)):
        assert np.array_equal(K.linspace(lo, hi, num), np.linspace(lo, hi, num))


def _fit_grid_numpy(x, y, cands, p):
    """The normal equations of ``y = a + b x + c (x - x_c)_+^p`` per candidate, solved by LAPACK."""
    coef, rss = [], []
    for c in cands:
        g = np.where(x > c, np.clip(x - c, 0, None) ** p, 0.0)
        A = np.column_stack([np.ones_like(x), x, g])
        M = A.T @ A + 1e-12 * np.eye(3)
        v = A.T @ y
        sol = np.linalg.solve(M, v)
        coef.append(sol)
        rss.append(y @ y - sol @ v if sol[2] > 0 else np.inf)
    return np.array(coef), np.array(rss)


@pytest.mark.parametrize("p", [1.75, 1.5, 2.2])
def test_fit_grid_equals_the_normal_equations_by_lapack(p):
    rng = np.random.default_rng(7)
    x = np.linspace(0, 1, 400) + 0.001 * rng.normal(size=400)  # measured: not monotonic
    y = 0.05 * x + 3.0 * np.clip(x - 0.55, 0, None) ** p + 0.002 * rng.normal(size=400)
    cands = np.linspace(0.35, 0.75, 61)
    coef, rss = K.fit_grid(x, y, cands, p)
    coef_ref, rss_ref = _fit_grid_numpy(x, y, cands, p)
    fin = np.isfinite(rss_ref)
    assert np.array_equal(np.isfinite(rss), fin)
    np.testing.assert_allclose(rss[fin], rss_ref[fin], rtol=1e-9)
    np.testing.assert_allclose(coef, coef_ref, rtol=1e-8, atol=1e-12)
    assert np.argmin(rss) == np.argmin(rss_ref)


def _soft_contact_numpy(zi, di, exponent=1.75, force_fraction=0.65, window=0.15, grid=121, max_points=500):
    """The soft contact point as numpy computes it (the code before the compiled kernel)."""
    def block(x, n):
        m = x.size // n
        return x if m <= 1 else x[:(x.size // m) * m].reshape(x.size // m, m).mean(1)

    m = max(zi.size // max_points, 1)
    jb = int(np.argmax(block(di, max_points)))
    imax = min((jb + 1) * m - 1, zi.size - 1) if m > 1 else int(np.argmax(di))
    zb, db = block(zi[: imax + 1], max_points), block(di[: imax + 1], max_points)
    above = np.flatnonzero(db - db.min() > force_fraction * np.ptp(db))
    cut = int(above[0]) + 1 if above.size and above[0] > 8 else db.size
    zb, db = zb[:cut], db[:cut]
    span = zb[-1] - zb[0]
    x = (zb - zb[0]) / span
    y = (db - db.min()) / max(np.ptp(db), 1e-300)
    x_init = float(x[int(np.argmin(y - np.linspace(0.0, 1.0, x.size)))])
    coarse = np.linspace(max(x_init - window, 0.0), min(x_init + window, 1.0), grid)
    _, coarse_rss = _fit_grid_numpy(x, y, coarse, exponent)
    j = int(np.argmin(coarse_rss))
    step = coarse[1] - coarse[0]
    cands = np.linspace(max(coarse[j] - step, 0.0), min(coarse[j] + step, 1.0), 41)
    coef, rss = _fit_grid_numpy(x, y, cands, exponent)
    j = int(np.argmin(rss))
    zc = float(zb[0] + cands[j] * span)
    near = coarse[coarse_rss <= rss[j] + 4.0 * rss[j] / max(x.size - 4, 1)]
    low = float(zb[0] + min(near.min(), cands[j]) * span) if near.size else zc
    high = float(zb[0] + max(near.max(), cands[j]) * span) if near.size else zc
    zr = zi[: imax + 1]
    k = int(np.searchsorted(zr, zc)) if np.all(np.diff(zr) >= 0) else int(np.argmin(np.abs(zr - zc)))
    k = min(max(k - 1, 0), zr.size - 1)
    d_c = float(db.min() + (coef[j, 0] + coef[j, 1] * cands[j]) * np.ptp(db))
    return k, zc, d_c, float((zi[imax] - zc) - (di[imax] - d_c)), low, high


@pytest.mark.parametrize("n,noisy_z,fraction", [(300, False, 0.65), (2000, True, 0.65), (6001, False, 1.0)])
def test_soft_contact_point_equals_numpy(n, noisy_z, fraction):
    rng = np.random.default_rng(n)
    z = np.linspace(-3e-6, 1e-6, n) + (2e-9 * rng.normal(size=n) if noisy_z else 0.0)
    d = 2e-8 * np.clip((z + 0.4e-6) / 1e-6, 0, None) ** 1.6 + 1e-10 * rng.normal(size=n) + 1e-10 * z / 1e-6
    index = np.arange(n)
    cp = soft_contact_point(z, d, index, force_fraction=fraction)
    k, zc, d_c, indentation, low, high = _soft_contact_numpy(z, d, force_fraction=fraction)
    assert (cp.index, cp.position, cp.position_low, cp.position_high) == (k, zc, low, high)
    assert cp.deflection == pytest.approx(d_c, rel=1e-9, abs=1e-20)
    assert cp.indentation == pytest.approx(indentation, rel=1e-9)


def test_curvature_ratio_equals_numpy():
    rng = np.random.default_rng(3)
    z = np.round(np.linspace(0, 1e-6, 900) + 1e-9 * rng.normal(size=900), 10)  # ties in position
    d = np.clip(z / 1e-6, 0, None) ** 1.8 * 1e-7 + 1e-10 * rng.normal(size=900)
    contact = np.arange(200, 900)
    order = contact[np.argsort(z[contact], kind="stable")]
    n3 = order.size // 3
    slope = [np.polyfit(z[o] - z[o].mean(), d[o], 1)[0] for o in (order[:n3], order[-n3:])]
    assert curvature_ratio(z, d, contact) == pytest.approx(slope[1] / slope[0], rel=1e-12)


def _running_mean_numpy(x, w):
    half = w // 2
    return np.array([x[i - h:i + h + 1].mean() for i, h in
                     ((i, min(half, i, x.size - 1 - i)) for i in range(x.size))])


@pytest.mark.parametrize("step", [0, 3, 7])
def test_smooth_kernels_equal_numpy(step):
    rng = np.random.default_rng(step)
    z = np.linspace(0, 1e-6, 1500) + 1e-9 * rng.normal(size=1500)
    if step:  # a digitized (staircase) channel
        z = np.repeat(z[::step], step)[:1500]
    assert SK.staircase_window(z, 11) == _staircase_window(z)
    seg = np.repeat(np.array([0, 1, 2], np.int8), [700, 700, 100])
    out, change = SK.smooth_runs(z, seg, 11)
    expect = z.copy()
    for s in (0, 1, 2):
        expect[seg == s] = _running_mean_numpy(z[seg == s], 11)
    np.testing.assert_allclose(out, expect, rtol=1e-12, atol=1e-21)
    for s in (0, 1, 2):  # the step's own per-run path (running_mean) bit for bit
        assert np.array_equal(out[seg == s], _smooth_run(z[seg == s], 11))
    assert change == np.max(np.abs(out - z))


def test_compliance_line_equals_numpy():
    rng = np.random.default_rng(11)
    z = np.linspace(0, 2e-7, 600)
    s = 3e6 * z + 1e-3 * rng.normal(size=600)
    s[100] += 0.5  # a spike: the robust line ignores it
    index = np.arange(50, 600)
    region = np.zeros(index.size, bool)
    region[200:] = True
    sat = np.zeros(index.size, bool)
    sat[-5:] = True
    out = SK.compliance_line(z, s, index, region, sat)
    idx = index[region & ~sat]
    x, y = z[idx], s[idx]
    xm = x.mean()
    assert out[0] == idx.size and out[11] == xm
    assert (out[7], out[8], out[9], out[10]) == (x.min(), x.max(), y.min(), y.max())
    a, b, se_a, se_b, sigma, n_used = robust_line(x - xm, y)  # the shared robust fit on numpy's samples
    assert tuple(out[[1, 2, 3, 4, 5, 6]]) == (a - b * xm, b, se_a, se_b, sigma, n_used)
    ls = np.polyfit(x - xm, y, 1)  # no outlier in this region: close to the least-squares line
    assert out[2] == pytest.approx(ls[0], rel=1e-3)


def test_masks_and_indices_equal_numpy():
    rng = np.random.default_rng(2)
    seg = rng.integers(0, 3, 500).astype(np.int8)
    for w in (0, 1, 2, 3):
        assert np.array_equal(RK.run_index(seg, w), np.flatnonzero(seg == w))
    s = np.round(rng.normal(size=500), 1)
    s[:4] = s.max()
    expect = np.zeros(500, bool)
    for ext in (s.max(), s.min()):
        if (s == ext).sum() >= 3:
            expect |= s == ext
    assert np.array_equal(RK.saturated_kernel(s, 3), expect)


def _approach(kind: str, n: int = 1200, seed: int = 0):
    """An approach (z rising) with a free baseline, then contact: a straight line, a Hertz onset
    (curved: a repulsive onset before the two lines' split) or a double-layer rise (a surface force)."""
    rng = np.random.default_rng(seed)
    z = np.linspace(-200e-9, 50e-9, n)
    s = 1e-3 * rng.normal(size=n) + 1e-4 * z / 1e-9 * 0.01
    if kind == "line":
        s += np.clip(z, 0, None) / 1e-9 * 0.05
    elif kind == "hertz":
        s += (np.clip(z + 30e-9, 0, None) / 1e-9) ** 1.5 * 0.01
    else:
        s += 2.0 * np.exp(z / 10e-9) * (z < 0) + (z >= 0) * (2.0 + z / 1e-9 * 0.2)
    return z, s


@pytest.mark.parametrize("shape", ["line", "hertz", "double_layer"])
@pytest.mark.parametrize("kind", ["approach", "retract"])
def test_run_regions_kernel_equals_numpy_path(shape, kind):
    z, s = _approach(shape)
    if kind == "retract":
        z, s = z[::-1].copy(), s[::-1].copy()
    index = np.arange(z.size)
    sat = regions.saturated_mask(s)
    kw = dict(saturated=sat, min_points=5, baseline_fraction=0.7, compliance_fraction=0.5, min_contrast=10.0,
              noise=None)
    fast = regions.find_run_regions(z, s, index, kind, **kw)
    ref = regions._find_run_regions(z, s, index, kind, **kw)
    assert fast.split == ref.split and fast.noise == ref.noise
    for name in ("contact", "zero_force", "compliance", "saturated"):
        assert np.array_equal(getattr(fast, name), getattr(ref, name)), name
    for region in (ref.compliance, ref.zero_force):
        idx = index[region & ~ref.saturated]
        expect = regions._slope(z[idx], s[idx])
        got = RK.region_slope(z, s, index, region, ref.saturated)
        assert got == expect or (math.isnan(got) and math.isnan(expect))


def test_thinned_robust_line_picks_numpy_linspace_samples():
    from afmforce.analysis._numeric import robust_line_thin

    rng = np.random.default_rng(4)
    x = np.linspace(-1, 1, 9001)
    y = 2 * x + 0.01 * rng.normal(size=x.size)
    assert RK.thin_robust_line(x, y, 4001) == robust_line_thin(x, y)
