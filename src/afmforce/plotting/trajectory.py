"""Figures of a simulated cycle (:class:`afmforce.dynamics.Trajectory`).

Built on :class:`matplotlib.figure.Figure`, never pyplot; ``axes=None`` makes a figure.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._files import atomic_path

__all__ = ["plot_trajectory", "write_trajectory_png"]


def plot_trajectory(traj, axes=None):
    """Deflection vs drive position (full cycle) and vs separation near contact, with the
    static curve; apparent (beta theta) dashed for the beam. Returns the two Axes."""
    from ..dynamics import static_curve

    if axes is None:
        from matplotlib.figure import Figure

        axes = Figure(figsize=(11, 4.5), layout="tight").subplots(1, 2)
    ax0, ax1 = axes
    cfg = traj.config
    nm = 1e9
    for seg, name, color in ((0, "approach", "C0"), (1, "retract", "C3")):
        m = traj.segment == seg
        ax0.plot(traj.piezo_position[m] * nm, traj.deflection[m] * nm, color=color, lw=1,
                 label=f"{name}: actual $z_2$")
        ax1.plot(traj.separation[m] * nm, traj.deflection[m] * nm, color=color, lw=1,
                 label=f"{name}: actual")
        if cfg.model == "beam":
            ax0.plot(traj.piezo_position[m] * nm, traj.apparent_deflection[m] * nm, color=color,
                     lw=1, ls="--", label=rf"{name}: apparent $\beta\theta$")
            ax1.plot(traj.apparent_separation[m] * nm, traj.apparent_deflection[m] * nm,
                     color=color, lw=1, ls="--", label=f"{name}: apparent")
    s = cfg.surface
    if s.eq2_only:                 # eq 2 on the geometry (issue 25: 2R on a flat)
        sc = static_curve(traj.spring_constant, s.paper_radius, cfg.hamaker, cfg.z0, h_max=40e-9)
        hs, ds, st, jd, hmax = sc.separation, sc.deflection, sc.stable, sc.jump_in_deflection, 12.0
    else:                          # with a double layer: the static force of the surface
        from ..dynamics.static import surface_static_force
        hs = np.geomspace(0.8 * cfg.z0, max(40e-9, 8 * s.debye_length, s.law_reach), 2000)
        f, df = surface_static_force(s, hs)
        ds, st = f / traj.spring_constant, df < traj.spring_constant
        from ..dynamics.static import surface_jump_in
        jd = surface_jump_in(traj.spring_constant, s)[2]
        hmax = max(12.0, 4 * s.debye_length * nm)
    ax1.plot(hs * nm, np.where(st, ds, np.nan) * nm, "k", lw=2, label="static")
    ax1.plot(hs * nm, np.where(~st, ds, np.nan) * nm, "k:", lw=1.5, label="static (unstable)")
    ax0.set_xlabel("piezo position z [nm]")
    ax0.set_ylabel("deflection [nm]")
    ax0.set_title("full cycle")
    ax1.set_xlabel("separation [nm]")
    ax1.set_ylabel("deflection [nm]")
    ax1.set_title("near contact")
    ax1.set_xlim(-2, hmax)
    lo = np.nanmin([traj.events.min_deflection, traj.events.min_apparent_deflection, jd]) * nm
    top = max(1.0, -0.8 * lo)
    if np.isfinite(traj.events.spike_height):
        top = max(top, 1.15 * traj.events.spike_height * nm)
    ax1.set_ylim(min(-1.0, 1.6 * lo), top)
    ax1.axhline(0, color="0.7", lw=0.5)
    ax1.legend(fontsize=7)
    ax0.legend(fontsize=7)
    return ax0, ax1


def write_trajectory_png(traj, path: str | os.PathLike, *, force: bool = False, dpi: int = 120) -> Path:
    """:func:`plot_trajectory` written atomically as a PNG; returns the path."""
    ax0, _ = plot_trajectory(traj)
    path = Path(path)
    with atomic_path(path, force) as tmp:
        ax0.figure.savefig(tmp, dpi=dpi, format="png")
    return path
