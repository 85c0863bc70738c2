"""The virtual AFM's thermal tune: the thermal spectrum of a probe with a known k (issue 34).

The probe's linearised equations of motion (the same matrices the dynamics integrate:
:func:`~afmforce.dynamics.models.beam_matrices` and the lever damping of
:mod:`~afmforce.dynamics.damping`) give the exact one-sided PSD of the measured deflection
(the probe's vertical displacement ``h``, :func:`afmforce.calibration.virtual.linear_thermal_psd`):
one mode for the spring, both free modes for the beam. A recorded spectrum averages ``N``
periodograms (chi-square of 2N degrees of freedom per bin) over a white detector floor.

The spectrum stores the first mode's share of ``<h^2>`` as its ``correction`` (1 for the spring;
for the beam the share of its first mode), so that equipartition on the first mode,
``k = correction kB T / <h1^2>``, gives the probe's force-measuring k.
"""

from __future__ import annotations

import math

import numpy as np

from ..calibration.spectrum import ThermalSpectrum
from ..calibration.thermal import DEFAULT_TEMPERATURE
from ..calibration.virtual import linear_thermal_psd, mode_shares, sample_spectrum
from .._validate import non_negative
from ..errors import ParameterError
from .damping import beam_damping, spring_damping
from .models import beam_couplings, beam_matrices
from .parts import BeamProbe, SpringProbe

__all__ = ["probe_matrices", "free_resonance", "thermal_spectrum", "MAX_BINS"]

#: the most bins a default spectrum has
MAX_BINS = 1 << 17


def probe_matrices(probe) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(K [N/m], M [kg], C [kg/s], dh/dq [-]) of the probe's linearised motion."""
    if isinstance(probe, SpringProbe):
        c = spring_damping(probe.spring_constant, probe.mass, probe.quality_factor)
        return (np.array([[probe.spring_constant]]), np.array([[probe.mass]]), np.array([[c]]),
                np.array([1.0]))
    if isinstance(probe, BeamProbe):
        A, masses = beam_matrices(probe.cantilever, probe.m_joint, probe.m_base)
        C = beam_damping(A, masses, probe.quality_factor, probe.quality_factor_2)
        hq = beam_couplings(probe.cantilever)[0]
        return -np.asarray(A), np.diag(masses), np.asarray(C), np.asarray(hq)
    raise ParameterError(f"a thermal spectrum needs a SpringProbe or BeamProbe, got {type(probe).__name__}")


def free_resonance(probe) -> tuple[float, float | None]:
    """(f1 [Hz], Q1 [-] or None) of the probe's first free mode: what its thermal tune records.

    ``f1`` is the undamped natural frequency of the probe's own mass and stiffness (the matrices of
    :func:`probe_matrices`): ``sqrt(k/m) / (2 pi)`` for the spring, the lower eigenfrequency of the
    beam's ``K q = w^2 M q`` (about 4.06 kHz for the paper's beam). ``Q1`` is the lever damping's
    quality factor of that mode (``quality_factor``; the beam's Rayleigh damping gives its first
    mode exactly that Q), None for the paper's undamped lever. The drag on the lever in a liquid
    (``lever_drag``) and the paper's friction (which acts on the tip) are forces of the surface,
    not of the lever: they are not counted, as in :func:`thermal_spectrum`.
    """
    K, M, _, out = probe_matrices(probe)
    freqs, _ = mode_shares(K, M, out)
    q = probe.quality_factor
    return float(freqs[0]), (None if q is None else float(q))


def thermal_spectrum(probe, *, temperature: float = DEFAULT_TEMPERATURE, f_max: float | None = None,
                     bins: int | None = None, averages: int = 64, white: float = 0.0,
                     seed: int | None = 0, medium: str | None = None) -> ThermalSpectrum:
    """A recorded thermal spectrum of ``probe`` (its lever damping must be set: Q not None).

    Parameters
    ----------
    probe : SpringProbe or BeamProbe
    temperature : float  [K]
    f_max : float, optional
        Highest frequency [Hz]; default 1.5 x the highest free mode (both of the beam's) when
        that needs at most :data:`MAX_BINS` bins, else 5 x the first mode.
    bins : int, optional
        Bins from f_max/bins to f_max; default: eight per line width of the first mode
        (``f1 / Q1``), at least 1024.
    averages : int  periodograms averaged (None of noise: pass ``seed=None`` for the exact PSD)
    white : float  detector floor [m^2/Hz]
    seed : int or None  random seed; None: the exact PSD without chi-square scatter
    medium : str, optional  stored in the spectrum
    """
    if probe.quality_factor is None and getattr(probe, "quality_factor_2", None) is None:
        raise ParameterError("an undamped probe has no thermal spectrum: give the quality_factor")
    white = non_negative("white", white, "m^2/Hz")     # finite too: inf gave a spectrum of infinite bins
    K, M, C, out = probe_matrices(probe)
    freqs, shares = mode_shares(K, M, out)
    q1 = probe.quality_factor if probe.quality_factor is not None else probe.quality_factor_2
    step = float(freqs[0]) / (8.0 * q1)
    top = f_max if f_max is not None else 1.5 * float(freqs[-1])
    if f_max is None and top / step > MAX_BINS:
        top = 5.0 * float(freqs[0])
    n = bins if bins is not None else int(min(max(1024, math.ceil(top / step)), MAX_BINS))
    f = np.linspace(top / n, top, n)
    psd = linear_thermal_psd(f, K, M, C, out, temperature)
    if seed is not None:
        psd = sample_spectrum(psd, averages, np.random.default_rng(seed), white)
    elif white:
        psd = psd + white
    k = float(probe.force_constant)
    f1, q_first = free_resonance(probe)
    vendor = {"spring_constant": k, "resonance_frequency": f1}
    if q_first is not None:
        vendor["quality_factor"] = q_first
    if len(freqs) > 1:
        vendor["resonance_frequency_2"] = float(freqs[1])
    return ThermalSpectrum(f, psd, unit="m^2/Hz", temperature=float(temperature), medium=medium,
                           correction=float(shares[0]),
                           averages=None if seed is None else int(averages), vendor=vendor,
                           source=f"afmforce virtual AFM, {probe.model} probe, k = {k:.6g} N/m")

