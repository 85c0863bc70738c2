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
residual of curve *i* is ``L_i^-1 (data - model - X beta)``, ``C_i = L_i L_i^T`` on
its fitted samples, so the chi-square, the profiles and the model test keep their
meaning.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["pink_correlation", "estimate_pink", "set_noise_model", "PINK_SIGNIFICANCE"]

#: The 1/f term is used when the pooled excess exceeds this many of its standard deviations.
PINK_SIGNIFICANCE = 3.0


def pink_correlation(n_record: int) -> np.ndarray:
    """Autocorrelation ``K[lag]`` (lag 0 .. n_record-1) of unit-variance 1/f noise [-]."""
    n = max(int(n_record), 4)
    k = np.arange(n // 2 + 1, dtype=float)
    psd = np.zeros(k.size)
    psd[1:] = 1.0 / k[1:]     # the record's frequencies k / (n dt), as the instrument makes it
    acf = np.fft.irfft(psd, n)
    return acf / acf[0]


def _free(c) -> np.ndarray:
    """Fitted samples of the free approach (before the jump-in)."""
    idx = np.flatnonzero(c.mask)
    return idx[idx < c.jump_index]


def estimate_pink(prob, x, drift: bool = True) -> tuple[float, float]:
    """``(sigma_p^2 [m^2], significance)`` from the residuals of the white fit at ``x``.

    The residuals ``r = (P - H) b`` of the free approach (``b`` the data noise in units of
    each curve's white rms, ``P`` the projection that removes each curve's offset and
    drift, ``H`` the hat matrix of the fit's Jacobian ``J``: the fitted parameters absorb
    part of the noise) have the expectation ``E[r_S' r_S] = tr_S(P - H) + sigma_p^2
    tr_S((P - H) G (P - H))``, ``G`` the 1/f covariance per unit sigma_p^2 in the same
    units; solved for ``sigma_p^2``. The white rms of each curve came from second
    differences, which also see the top of the 1/f spectrum: ``sigma_est^2 = sigma_w^2 +
    c2 sigma_p^2``, ``c2 = (6 - 8 K[1] + 2 K[2]) / 6`` (0.16-0.22 for records of
    600-6000 samples), so the white part of the residuals is ``(1 - c2 sigma_p^2 /
    sigma_est^2) tr_S(P - H)``; solved jointly. ``drift`` is unused (the evaluator's
    design holds it).
    """
    values, shifts = prob.unpack(x)
    ev = prob.ev
    blocks, rs, sel, c2w = [], [], [], []
    for i, (c, r) in enumerate(zip(ev.curves, prob.curve_residuals(x))):
        idx = np.flatnonzero(c.mask)
        Q, _ = np.linalg.qr(ev.design(i)[c.mask])
        K = pink_correlation(c.metadata.get("record_samples", c.n))
        blocks.append((np.eye(idx.size) - Q @ Q.T, K[np.abs(idx[:, None] - idx[None, :])]
                       / c.sigma ** 2))
        rs.append(r)
        sel.append(idx < c.jump_index)
        c2w.append(np.full(idx.size, (6.0 - 8.0 * K[1] + 2.0 * K[2]) / 6.0 / c.sigma ** 2))
    sel = np.concatenate(sel)
    if sel.sum() < 10:
        return 0.0, 0.0
    from scipy.linalg import block_diag

    P = block_diag(*[b[0] for b in blocks])
    G = block_diag(*[b[1] for b in blocks])
    J = prob.jacobian(x)
    H = J @ np.linalg.pinv(J.T @ J, rcond=1e-12) @ J.T
    A = (P - H)[sel]
    r = np.concatenate(rs)[sel]
    diag = np.diag(A[:, sel])
    white = float(np.sum(diag))
    white_c2 = float(np.sum(diag * np.concatenate(c2w)[sel]))   # what sigma_p^2 takes off it
    trace = float(np.sum((A @ G) * A)) - white_c2
    excess = float(r @ r) - white
    if trace <= 0:
        return 0.0, 0.0
    return max(excess / trace, 0.0), excess / math.sqrt(2.0 * sel.sum())


def set_noise_model(curves, sigma_p2: float) -> None:
    """Attach the Cholesky factor of ``C_i`` on the fitted samples to every curve (in place)."""
    for c in curves:
        if sigma_p2 <= 0:
            c.noise_chol = None
            continue
        K = pink_correlation(c.metadata.get("record_samples", c.n))
        idx = np.flatnonzero(c.mask)
        C = sigma_p2 * K[np.abs(idx[:, None] - idx[None, :])]
        c2 = (6.0 - 8.0 * K[1] + 2.0 * K[2]) / 6.0     # the 1/f part of the second differences
        C[np.diag_indices_from(C)] += max(c.sigma ** 2 - c2 * sigma_p2, 0.25 * c.sigma ** 2)
        c.noise_chol = np.linalg.cholesky(C)
        c.pink = math.sqrt(sigma_p2)
