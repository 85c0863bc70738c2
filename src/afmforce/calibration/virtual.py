"""Thermal spectra of linear lever models, exact and sampled (the virtual AFM's thermal tune).

A lever model ``M q'' + C q' + K q = F(t)`` in thermal equilibrium is driven by a force noise of
one-sided spectral density ``4 kB T C`` (fluctuation-dissipation theorem). An output
``y = c . q`` (the measured deflection) then has the one-sided PSD

    S_y(f) = 4 kB T c^T H C H^H c,     H = (K - w^2 M + i w C)^-1,  w = 2 pi f,              (1)

whose integral over all frequencies is the equipartition value ``kB T c^T K^-1 c`` for any
damping. With proportional (Rayleigh) damping the modes decouple and mode ``i`` carries the
share ``(c . phi_i)^2 / (w_i^2 phi_i^T M phi_i) / (c^T K^-1 c)`` of it
(:func:`mode_shares`): the correction chi of the first mode's equipartition.

A measured spectrum is an average of ``N`` periodograms: each bin is ``S_y`` times a
chi-square variable of ``2N`` degrees of freedom divided by ``2N`` (:func:`sample_spectrum`).
"""

from __future__ import annotations

import numpy as np

from .thermal import BOLTZMANN

__all__ = ["linear_thermal_psd", "mode_shares", "sample_spectrum"]


def linear_thermal_psd(frequency, stiffness, mass, damping, output, temperature: float):
    """Eq (1): the one-sided thermal PSD of ``y = output . q`` [m^2/Hz].

    Parameters
    ----------
    frequency : array_like  [Hz]
    stiffness, mass, damping : array_like
        n x n matrices K [N/m], M [kg], C [kg/s] in the generalised coordinates (scalars for
        one degree of freedom).
    output : array_like
        ``dy/dq`` (n-vector) [-].
    temperature : float  [K]
    """
    f = np.atleast_1d(np.asarray(frequency, dtype=float))
    K, M, C = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (stiffness, mass, damping))
    c = np.atleast_1d(np.asarray(output, dtype=float))
    w = 2.0 * np.pi * f
    D = K[None] - (w * w)[:, None, None] * M[None] + 1j * w[:, None, None] * C[None]
    h = np.linalg.solve(np.transpose(D, (0, 2, 1)), np.broadcast_to(c, (f.size, c.size))[..., None])[..., 0]
    # h = H^T c (H symmetric for symmetric K, M, C): S = 4 kB T h^T C conj(h)
    s = 4.0 * BOLTZMANN * temperature * np.real(np.einsum("fi,ij,fj->f", h, C, np.conj(h)))
    return s


def mode_shares(stiffness, mass, output) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies [Hz], shares [-]) of the free modes, ascending: each mode's part of
    ``<y^2>`` (they sum to 1)."""
    K, M = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (stiffness, mass))
    c = np.atleast_1d(np.asarray(output, dtype=float))
    from scipy.linalg import eigh

    w2, phi = eigh(K, M)                       # phi^T M phi = 1
    parts = (c @ phi) ** 2 / w2
    return np.sqrt(w2) / (2.0 * np.pi), parts / float(c @ np.linalg.solve(K, c))


def sample_spectrum(psd, averages: int, rng: np.random.Generator, white: float = 0.0):
    """A measured spectrum: ``(psd + white)`` times chi-square(2N)/(2N) per bin [unit^2/Hz]."""
    if averages < 1:
        raise ValueError("averages must be at least 1")
    mean = np.asarray(psd, dtype=float) + white
    return mean * rng.gamma(shape=averages, scale=1.0 / averages, size=mean.shape)
