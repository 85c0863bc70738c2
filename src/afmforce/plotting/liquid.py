"""Liquid curves (step ``liquid``, docs/liquid.md): the double layer on a log scale with the DLVO fit.

Built on :class:`matplotlib.figure.Figure`, never pyplot; takes ``ax=None``.
"""

from __future__ import annotations

import math

import numpy as np

from ..analysis.result import AnalysisResult

__all__ = ["plot_liquid"]


def plot_liquid(result: AnalysisResult, ax=None):
    """Repulsive force [nN, log scale] against separation [nm]: the approach's static force (velocity
    force taken off), the static force of approach and retract at equal separation, the velocity force,
    and the DLVO fit with psi, 1/kappa and A in the legend. Returns the Axes."""
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6, 4.5), layout="constrained").add_subplot()
    q = result.details.get("liquid")
    if q is None or q.fit_force.size == 0:
        why = result.not_applicable.get("liquid", "the liquid step did not run")
        ax.text(0.5, 0.5, f"no DLVO fit:\n{why}", ha="center", va="center", wrap=True, transform=ax.transAxes,
                fontsize="small")
        ax.set_axis_off()
        return ax
    pos = lambda f: np.where(f > 0, f, np.nan) * 1e9  # noqa: E731 - log scale: the repulsion only
    ax.semilogy(q.static_separation * 1e9, pos(q.static_force), ".", ms=2, color="0.6",
                label="static (approach + retract)/2")
    ax.semilogy(q.static_separation * 1e9, pos(q.velocity_force), ".", ms=2, color="C2",
                label="velocity force (approach - retract)/2")
    ax.semilogy(q.dlvo_separation * 1e9, pos(q.dlvo_force), ".", ms=2.5, color="C0",
                label="approach, velocity force off")
    order = np.argsort(q.dlvo_separation)
    label = (f"DLVO ({q.double_layer}): psi = {q.surface_potential * 1e3:.3g} mV, "
             f"1/kappa = {q.debye_length * 1e9:.3g} nm, A = {q.hamaker:.2g} J")
    ax.semilogy(q.dlvo_separation[order] * 1e9, pos(q.fit_force[order]), "-", color="C3", lw=1.5, label=label)
    if math.isfinite(q.force_noise) and q.force_noise > 0:
        ax.axhline(q.force_noise * 1e9, color="0.6", lw=0.8, ls=":", label="noise (static force)")
    ax.set_xlim(0, 1.05 * float(np.max(q.dlvo_separation)) * 1e9)
    ax.set_xlabel("separation [nm]")
    ax.set_ylabel("repulsive force [nN]")
    ax.legend(fontsize="x-small", loc="upper right")
    ax.set_title(f"lever drag {q.lever_drag:.3g} N s/m (offset {q.drag_offset * 1e9:.3g} nm)", fontsize="small")
    return ax
