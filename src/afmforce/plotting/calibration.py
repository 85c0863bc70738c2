"""A thermal spectrum with its fitted resonance (``afmforce calibrate thermal --plot``;
docs/calibration.md). Built on :class:`matplotlib.figure.Figure`, never pyplot; takes ``ax=None``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._files import atomic_path

__all__ = ["plot_thermal", "write_thermal_png"]


def plot_thermal(frequency, psd, fit, ax=None, unit: str = "m^2/Hz"):
    """The spectrum (grey), the fitted window (black), the model (red, with k, f0 and Q in the
    legend) on log-log axes [kHz, ``unit``]. ``fit`` is a
    :class:`~afmforce.calibration.thermal.ThermalFit`; returns the Axes."""
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6.5, 4.5), layout="constrained").add_subplot()
    f = np.asarray(frequency, float)
    p = np.asarray(psd, float)
    ok = (f > 0) & (p > 0)
    inside = ok & (f >= fit.f_min) & (f <= fit.f_max)
    ax.loglog(f[ok] * 1e-3, p[ok], "-", color="0.75", lw=0.6, label="spectrum")
    ax.loglog(f[inside] * 1e-3, p[inside], "-", color="0.2", lw=0.7, label="fitted window")
    grid = np.geomspace(fit.f_min, fit.f_max, 800)
    label = (f"SHO + floor: k = {fit.spring_constant * 1e3:.4g} ± {fit.spring_constant_se * 1e3:.2g} mN/m, "
             f"f0 = {fit.resonance_frequency * 1e-3:.4g} kHz, Q = {fit.quality_factor:.3g}")
    ax.loglog(grid * 1e-3, fit.model(grid), "-", color="C3", lw=1.5, label=label)
    ax.set_xlabel("frequency [kHz]")
    ax.set_ylabel(f"PSD [{unit}]")
    ax.legend(fontsize="small", loc="lower left")
    return ax


def write_thermal_png(frequency, psd, fit, path: str | os.PathLike, *, force: bool = True,
                      dpi: int = 120) -> Path:
    """:func:`plot_thermal` written atomically as a PNG; returns the path."""
    ax = plot_thermal(frequency, psd, fit)
    path = Path(path)
    with atomic_path(path, force) as tmp:
        ax.figure.savefig(tmp, dpi=dpi, format="png")
    return path
