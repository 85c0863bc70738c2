"""Force against indentation with the fitted indentation model (docs/contact.md).

Built on :class:`matplotlib.figure.Figure`, never pyplot; takes ``ax=None``.
"""

from __future__ import annotations

import math

import numpy as np

from ..analysis.result import AnalysisResult

__all__ = ["plot_indentation"]


def plot_indentation(result: AnalysisResult, ax=None):
    """The fitted run's force above the baseline [nN] against the indentation [µm]: data, the model's
    fit, the contact point at zero, E with its 95 % interval (and w) in the legend. Returns the Axes."""
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6, 4.5), layout="constrained").add_subplot()
    fit = result.details.get("indentation")
    if fit is None or fit.indentation.size == 0:
        why = result.not_applicable.get("indentation", "the indentation step did not run")
        ax.text(0.5, 0.5, f"no modulus fit:\n{why}", ha="center", va="center", wrap=True,
                transform=ax.transAxes, fontsize="small")
        ax.set_axis_off()
        return ax
    d = fit.indentation * 1e6
    data = (fit.fit_force + fit.residuals - fit.baseline) * 1e9
    model = (fit.fit_force - fit.baseline) * 1e9
    order = np.argsort(d)
    ax.plot(d, data, ".", ms=2.5, color="0.45", label=f"{fit.run} (data)")
    label = (f"{fit.model}: E = {fit.youngs_modulus / 1e3:.4g} kPa "
             f"[{fit.youngs_modulus_low / 1e3:.3g}, {fit.youngs_modulus_high / 1e3:.3g}]"
             if math.isfinite(fit.youngs_modulus_high) else
             f"{fit.model}: E undetermined ({fit.youngs_modulus / 1e3:.3g} kPa, interval [0, open])")
    if math.isfinite(fit.work_of_adhesion):
        label += f", w = {fit.work_of_adhesion * 1e3:.3g} mJ/m²"
    ax.plot(d[order], model[order], "-", color="C3", lw=1.5, label=label)
    ax.axvline(0.0, color="0.6", lw=0.8, ls=":")
    ax.axhline(0.0, color="0.6", lw=0.8, ls=":")
    ax.set_xlabel("indentation [µm]")
    ax.set_ylabel("force above the baseline [nN]")
    ax.legend(fontsize="small", loc="upper left")
    if fit.warnings:
        ax.set_title("; ".join(fit.warnings)[:110], fontsize="x-small", color="C3")
    return ax
