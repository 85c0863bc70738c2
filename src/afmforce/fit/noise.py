"""Correlated (1/f) detector noise in the fit: estimate it, and whiten the residuals.

The noise of a deflection signal is white only at high frequencies: amplifiers
and lasers add 1/f ("pink") noise, which the second differences the fit takes
its noise from (:func:`afmforce.fit.data._noise_sigma`) barely see. On the
``typical`` virtual AFM (0.05 nm white + 0.05 nm 1/f) a white-noise fit stops at
a reduced chi-square of 1.4 with A 16 % and xi 16 % high: the slow wander of the
baseline is fitted as physics.

Model: ``C = sigma_w^2 I + sigma_p^2 K``, ``K`` the autocorrelation of unit-variance
noise with a power spectrum ``1/f`` from the record's lowest frequency ``1/(N dt)``
up (as :func:`afmforce.instrument.noise.pink_noise` makes it). ``sigma_p^2`` is
estimated from a first, white-noise fit: the excess of the residuals of the free
approach over the white noise, divided by what unit 1/f noise leaves there after
the fit (:func:`estimate_pink`), pooled over the curves (one detector). When the
excess is significant the fit is repeated with generalised least squares: the
residual of curve *i* is ``W_i (data - model - X beta)``, ``W_i`` the whitening filter
of its noise (:class:`ARWhitener`), so the chi-square, the profiles and the model test
keep their meaning.

**Memory linear in the samples** (issue 34). Nothing here is dense in the samples: the
expectation of :func:`estimate_pink` is exact, with the projections written as low-rank
updates of the identity and ``K`` applied as a Toeplitz product by FFT; the whitening is
the innovations filter of an autoregressive model of order ``AR_ORDER`` fitted to ``C``'s
autocorrelation by Levinson-Durbin (exact for the first ``AR_ORDER`` samples of each
contiguous run of fitted samples, the maximum-entropy extension beyond; a gap in the
fitted samples restarts it). Memory ``O(n)``, time ``O(n p)`` per whitened vector.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["pink_correlation", "estimate_pink", "baseline_pink", "baseline_samples",
           "BASELINE_FRACTION", "baseline_refusal", "set_noise_model", "ARWhitener",
           "PINK_SIGNIFICANCE", "PINK_MAX_RATIO", "pink_refusal", "AR_ORDER"]

#: The 1/f term is used when the pooled excess exceeds this many of its standard deviations.
PINK_SIGNIFICANCE = 3.0
#: The largest plausible ratio of the 1/f rms to the white rms of a deflection signal [-]. An
#: AFM's detector has 1/f noise of the order of its white noise over a record (the ``typical``
#: virtual AFM: 1:1); a fitted 1/f level far above it is a misfit of the model (a wrong spring
#: constant, a missing force) taken for noise, and whitening with it would make any model pass.
PINK_MAX_RATIO = 10.0
#: The free baseline (:func:`baseline_samples`): where the model's deflection stays within this
#: fraction of the white rms of its far value [-].
BASELINE_FRACTION = 1.0
#: Order of the autoregressive whitening filter (lags of C matched exactly).
AR_ORDER = 200


def pink_correlation(n_record: int) -> np.ndarray:
    """Autocorrelation ``K[lag]`` (lag 0 .. n_record-1) of unit-variance 1/f noise [-]."""
    n = max(int(n_record), 4)
    k = np.arange(n // 2 + 1, dtype=float)
    psd = np.zeros(k.size)
    psd[1:] = 1.0 / k[1:]     # the record's frequencies k / (n dt), as the instrument makes it
    acf = np.fft.irfft(psd, n)
    return acf / acf[0]


def _toeplitz_matvec(K: np.ndarray, idx: np.ndarray, V: np.ndarray) -> np.ndarray:
    """``K[|idx_a - idx_b|] @ V`` (``V``: rows on ``idx``) by FFT, without the matrix."""
    V = np.asarray(V, float).reshape(idx.size, -1)
    L = int(idx[-1] - idx[0]) + 1
    nfft = 1 << int(math.ceil(math.log2(2 * L)))
    lags = np.zeros(nfft)
    m = min(L, K.size)
    lags[:m] = K[:m]
    lags[nfft - m + 1:] = K[1:m][::-1]          # symmetric: K[-l] = K[l]
    full = np.zeros((nfft, V.shape[1]))
    full[idx - idx[0]] = V
    out = np.fft.irfft(np.fft.rfft(lags)[:, None] * np.fft.rfft(full, axis=0), nfft, axis=0)
    return out[idx - idx[0]]


def baseline_samples(prob, x) -> list[np.ndarray]:
    """Per curve, which fitted samples lie on its free baseline: before the jump-in, where the
    model's deflection at ``x`` stays within :data:`BASELINE_FRACTION` of the curve's white
    rms of its value at the start (the model is a line there, trivially right)."""
    ev = prob.ev
    values, shifts = prob.unpack(x)
    out = []
    for i, c in enumerate(ev.curves):
        idx = np.flatnonzero(c.mask)
        pred = prob.curve_prediction(i, values, shifts[i])
        free = idx < c.jump_index
        if pred is None or not free.any():
            out.append(np.zeros(idx.size, bool))
            continue
        y = np.asarray(pred, float)[idx]
        ref = float(np.median(y[free][: max(5, int(free.sum()) // 10)]))
        out.append(free & (np.abs(y - ref) < BASELINE_FRACTION * c.sigma))
    return out


def estimate_pink(prob, x, drift: bool = True) -> tuple[float, float]:
    """``(sigma_p^2 [m^2], significance)`` from the residuals of the white fit at ``x``.

    The residuals ``r = D b``, ``D = P - H`` (``b`` the data noise in units of each curve's
    white rms, ``P`` the projection that removes each curve's offset and drift, ``H`` the
    hat matrix of the fit's Jacobian ``J``: the fitted parameters absorb part of the
    noise), have on the free approach ``S`` the expectation ``E[r_S' r_S] = tr_S(D) +
    sigma_p^2 tr_S(D G D)``, ``G`` the 1/f covariance per unit sigma_p^2 in the same
    units; solved for ``sigma_p^2``. The white rms of each curve came from second
    differences, which also see the top of the 1/f spectrum: ``sigma_est^2 = sigma_w^2 +
    c2 sigma_p^2``, ``c2 = (6 - 8 K[1] + 2 K[2]) / 6`` (0.16-0.22 for records of
    600-6000 samples), so the white part of the residuals is ``(1 - c2 sigma_p^2 /
    sigma_est^2) tr_S(D)``; solved jointly. ``D = I - U V'`` with ``U = [Q, J M]``,
    ``V = [Q, J]`` (``Q`` the orthonormal designs, ``M = (J'J)^-1``), so the diagonal of
    ``D G D`` needs only ``G V`` (Toeplitz products by FFT) and ``V' G V``: O(n) memory.
    ``drift`` is unused (the evaluator's design holds it). A misfit leaves an excess here too:
    :func:`baseline_pink` tells the two apart.
    """
    ev = prob.ev
    rs = prob.curve_residuals(x)
    J = prob.jacobian(x)
    M = np.linalg.pinv(J.T @ J, rcond=1e-12)
    JM = J @ M
    diagH = np.einsum("ij,ij->i", JM, J)
    sizes = [int(c.mask.sum()) for c in ev.curves]
    starts = np.concatenate([[0], np.cumsum(sizes)])
    Qs = [np.linalg.qr(ev.design(i)[c.mask])[0] for i, c in enumerate(ev.curves)]
    nq = sum(q.shape[1] for q in Qs)
    N = int(starts[-1])
    Qblk = np.zeros((N, nq))      # block-diagonal designs: N x (a few per curve)
    col = 0
    for i, Q in enumerate(Qs):
        Qblk[starts[i]:starts[i + 1], col:col + Q.shape[1]] = Q
        col += Q.shape[1]
    U = np.hstack([Qblk, JM])
    V = np.hstack([Qblk, J])
    GV = np.zeros_like(V)
    gdiag, c2w, sel = np.zeros(N), np.zeros(N), np.zeros(N, bool)
    for i, c in enumerate(ev.curves):
        s = slice(starts[i], starts[i + 1])
        idx = np.flatnonzero(c.mask)
        K = pink_correlation(c.metadata.get("record_samples", c.n))
        GV[s] = _toeplitz_matvec(K, idx, V[s]) / c.sigma ** 2
        gdiag[s] = K[0] / c.sigma ** 2
        c2w[s] = (6.0 - 8.0 * K[1] + 2.0 * K[2]) / 6.0 / c.sigma ** 2
        sel[s] = idx < c.jump_index
    if sel.sum() < 10:
        return 0.0, 0.0
    W = V.T @ GV
    d = 1.0 - np.einsum("ij,ij->i", Qblk, Qblk) - diagH                 # diag(D)
    dgd = (gdiag - 2.0 * np.einsum("ij,ij->i", U, GV)
           + np.einsum("ij,jk,ik->i", U, W, U, optimize=True))          # diag(D G D)
    white = float(np.sum(d[sel]))
    white_c2 = float(np.sum((d * c2w)[sel]))   # what sigma_p^2 takes off it
    trace = float(np.sum(dgd[sel])) - white_c2
    r = np.concatenate(rs)[sel]
    excess = float(r @ r) - white
    if trace <= 0:
        return 0.0, 0.0
    return max(excess / trace, 0.0), excess / math.sqrt(2.0 * sel.sum())


def baseline_pink(prob, x) -> tuple[float, float, float]:
    """``(sigma_p^2 [m^2], significance, power [1/m^2])`` of the free baselines alone
    (:func:`baseline_samples`); ``power * s2`` is the significance a 1/f variance ``s2`` would
    have there on average (0: no baseline to measure on).

    The residuals of the joint fit at ``x`` on each curve's baseline, with that baseline's own
    offset and drift (the curve's design on those samples) projected out again: a misfit
    elsewhere (in contact, at the jump-in) tilts the joint fit's offset and drift and leaves a
    slow trend on the baseline that reads as 1/f noise; refitted on the baseline alone the
    trend is gone, and what is left is the detector's noise. Expectation as
    :func:`estimate_pink` with ``D = I - Q Q'`` (``Q`` an orthonormal basis of the baseline's
    design): ``tr(D) = n - rank``, ``tr(D G D) = tr(G) - tr(Q' G Q)``. The joint fit's hat
    matrix is left out (the free globals and shifts barely move a baseline): the estimate is
    low by their few degrees of freedom among the baselines' hundreds.
    """
    ev = prob.ev
    rs = prob.curve_residuals(x)
    flat = baseline_samples(prob, x)
    rr = white = trace = 0.0
    n_all = 0
    for i, c in enumerate(ev.curves):
        sel = flat[i]
        if int(sel.sum()) < 10:
            continue
        idx = np.flatnonzero(c.mask)[sel]
        X = ev.design(i)[idx]
        u, sv, _ = np.linalg.svd(X, full_matrices=False)
        Q = u[:, sv > sv[0] * 1e-10]
        r = np.asarray(rs[i])[sel]
        r = r - Q @ (Q.T @ r)
        K = pink_correlation(c.metadata.get("record_samples", c.n))
        dfree = idx.size - Q.shape[1]
        c2 = (6.0 - 8.0 * K[1] + 2.0 * K[2]) / 6.0
        trg = (idx.size * K[0] - float(np.sum(Q * _toeplitz_matvec(K, idx, Q)))) / c.sigma ** 2
        rr += float(r @ r)
        white += dfree
        trace += trg - c2 * dfree / c.sigma ** 2
        n_all += idx.size
    if n_all < 10 or trace <= 0:
        return 0.0, 0.0, 0.0
    excess = rr - white
    return max(excess / trace, 0.0), excess / math.sqrt(2.0 * n_all), trace / math.sqrt(2.0 * n_all)


def baseline_refusal(sigma_p2: float, sigma_b2: float, significance_b: float,
                     power: float = math.inf) -> str | None:
    """Why the 1/f level ``sigma_p2`` [m^2] of the free approach is not detector noise, given the
    baselines' own estimate (:func:`baseline_pink`: ``sigma_b2`` [m^2] at ``significance_b``
    standard deviations, ``power`` [1/m^2]), or None when the baselines show 1/f noise too (the
    fit then models ``min(sigma_p2, sigma_b2)``: the detector's noise is what the baselines show)
    or are too short to show ``sigma_p2`` at :data:`PINK_SIGNIFICANCE` on average (curves whose
    model is nowhere a line, e.g. drainage over the whole approach: not judged)."""
    if significance_b > PINK_SIGNIFICANCE or power * sigma_p2 <= PINK_SIGNIFICANCE:
        return None
    return (f"the residuals' slow excess, read as 1/f noise, would be {math.sqrt(sigma_p2) * 1e9:.3g} nm "
            f"rms, but the free baselines alone (where the model is a line) show none significant "
            f"({math.sqrt(max(sigma_b2, 0.0)) * 1e9:.3g} nm, {significance_b:.2g} standard deviations "
            f"< {PINK_SIGNIFICANCE:g}): the excess follows the model's features (the jump-in, "
            "contact), not time, so it is the model's misfit, not detector noise; the fit keeps "
            "the white noise model and its adequacy test judges the misfit")


def pink_refusal(sigma_p2: float, sigmas) -> str | None:
    """Why a fitted 1/f level is not detector noise, or None when it is plausible.

    ``sigma_p2`` [m^2] is the 1/f variance :func:`estimate_pink` found, ``sigmas`` [m] the
    curves' white noise rms. A 1/f rms above ``PINK_MAX_RATIO`` times the largest white rms
    is the model's misfit, not noise: the fit keeps the white noise model (its adequacy
    test then judges the misfit) and warns with the returned text.
    """
    white = max((float(s) for s in sigmas), default=0.0)
    pink = math.sqrt(max(float(sigma_p2), 0.0))
    if not (math.isfinite(pink) and pink > PINK_MAX_RATIO * white):
        return None
    return (f"the residuals' slow excess, read as 1/f noise, would be {pink * 1e9:.3g} nm rms against "
            f"{white * 1e9:.3g} nm of white noise (more than {PINK_MAX_RATIO:g} x: no AFM's detector "
            "has such 1/f noise): it is the model's misfit (a wrong spring constant or calibration, "
            "a force the model lacks), so the fit keeps the white noise model and its adequacy "
            "test judges the misfit")


def _levinson(acov: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Predictors of every order up to ``order`` for the autocovariance ``acov``.

    Returns ``(phi, v)``: ``phi[m, :m]`` the coefficients of the order-``m`` predictor
    (``x_t ~ sum_j phi[m, j] x_(t-1-j)``), ``v[m]`` its innovation variance.
    """
    phi = np.zeros((order + 1, order))
    v = np.zeros(order + 1)
    v[0] = acov[0]
    for m in range(1, order + 1):
        prev = phi[m - 1, :m - 1]
        kappa = (acov[m] - prev @ acov[1:m][::-1]) / v[m - 1]
        phi[m, :m - 1] = prev - kappa * prev[::-1]
        phi[m, m - 1] = kappa
        v[m] = v[m - 1] * (1.0 - kappa ** 2)
    return phi, v


class ARWhitener:
    """Whitening filter of stationary noise with autocovariance ``acov`` on the fitted samples.

    Each contiguous run of fitted samples (sample indices ``idx``) is filtered by the
    innovations of the autoregressive model of order ``p`` fitted to ``acov`` (Levinson-Durbin):
    sample ``t`` of a run becomes ``(x_t - sum_j phi_j x_(t-j)) / sqrt(v)``, with the predictor
    of order ``min(t, p)``; exact (the Cholesky factor of the covariance) for runs of at most
    ``p + 1`` samples. O(n p) time, O(n + p^2) memory.
    """

    def __init__(self, acov: np.ndarray, idx: np.ndarray, order: int = AR_ORDER):
        self.idx = np.asarray(idx)
        breaks = np.flatnonzero(np.diff(self.idx) != 1) + 1
        self.runs = np.split(np.arange(self.idx.size), breaks)
        self.p = int(min(order, max(len(r) for r in self.runs) - 1, acov.size - 1))
        self.phi, self.v = _levinson(np.asarray(acov, float), max(self.p, 0))
        p = self.p
        head = np.zeros((p, p))       # a run's first p samples: the predictors of order t < p
        for t in range(p):
            head[t, t] = 1.0
            head[t, :t] = -self.phi[t, :t][::-1]
            head[t] /= math.sqrt(self.v[t])
        self.head = head

    def __call__(self, a: np.ndarray) -> np.ndarray:
        """The whitened ``a`` (rows: the fitted samples; 1-D or 2-D)."""
        from scipy.signal import lfilter

        a = np.asarray(a, float)
        out = np.empty_like(a)
        p = self.p
        full = np.concatenate([[1.0], -self.phi[p, :p]]) / math.sqrt(self.v[p])
        for run in self.runs:
            x = a[run[0]:run[-1] + 1]
            y = lfilter(full, [1.0], x, axis=0)
            m = min(p, x.shape[0])
            y[:m] = self.head[:m, :m] @ x[:m]           # the run's start: lower orders
            out[run[0]:run[-1] + 1] = y
        return out


def set_noise_model(curves, sigma_p2: float) -> None:
    """Attach the whitening filter of ``C_i`` on the fitted samples to every curve (in place)."""
    for c in curves:
        if sigma_p2 <= 0:
            c.whitener = None
            c.pink = 0.0
            continue
        K = pink_correlation(c.metadata.get("record_samples", c.n))
        idx = np.flatnonzero(c.mask)
        c2 = (6.0 - 8.0 * K[1] + 2.0 * K[2]) / 6.0     # the 1/f part of the second differences
        lags = min(AR_ORDER + 1, K.size)
        acov = sigma_p2 * K[:lags]
        acov[0] += max(c.sigma ** 2 - c2 * sigma_p2, 0.25 * c.sigma ** 2)
        c.whitener = ARWhitener(acov, idx)
        c.pink = math.sqrt(sigma_p2)
