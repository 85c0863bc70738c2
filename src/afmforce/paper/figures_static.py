"""The paper's static figures: Fig 3 (constant friction) and Fig 4 (friction proportional to load).

Each function takes ``ax=None`` and returns the axes it drew on.
Angle vs tip displacement along the inward (solid) and outward (dashed)
constant-compliance lines, from the compliance matrix of eqs 7-12.
"""

from __future__ import annotations

import numpy as np

from .. import constants as C
from ..cantilever import InclinedCantilever
from ..statics import constant_friction_offset, load_friction_constants


def _axes(ax):
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(5.5, 4.2), layout="constrained").add_subplot()
    return ax


def constant_friction_lines(cantilever: InclinedCantilever, mu: float, z2: np.ndarray):
    """Angle theta [rad] along the inward (Fy = +mu) and outward (Fy = -mu) lines at deflections z2 [m]."""
    Cm, g = cantilever.compliance_matrix, cantilever.angle_compliance
    out = []
    for sign in (+1, -1):
        fz = (z2 - sign * mu * Cm[0, 1]) / Cm[0, 0]
        out.append(g[0] * fz + g[1] * sign * mu)
    return out[0], out[1]


def load_friction_lines(cantilever: InclinedCantilever, lam: float, z2: np.ndarray):
    """Angle theta [rad] along the inward and outward lines for Fy = +-lambda Fz (eqs 18-19)."""
    th = []
    for sign in (+1, -1):
        _, beta = load_friction_constants(cantilever, lam, sign)
        th.append(z2 / beta)
    return th[0], th[1]


def fig3(ax=None, mu: float = C.FIG3_MU):
    """Fig 3: hysteresis due to constant friction, mu = 5 nN (eqs 16-17)."""
    ax = _axes(ax)
    c = InclinedCantilever(**C.FIG3)
    z2 = np.linspace(0.0, 10e-9, 101)
    t_in, t_out = constant_friction_lines(c, mu, z2)
    ax.plot(z2 * 1e9, t_in * 1e5, "-", color="C0", label="inward (loading, $\\dot z>0$)")
    ax.plot(z2 * 1e9, t_out * 1e5, "--", color="C3", label="outward (unloading, $\\dot z<0$)")
    off = constant_friction_offset(c, mu)
    ax.set_xlabel("tip displacement $z_2$ [nm]")
    ax.set_ylabel("deflection angle $\\theta$ [$10^{-5}$ rad]")
    ax.set_title(f"Fig 3: constant friction $\\mu$ = {mu * 1e9:g} nN\n"
                 f"lines offset by {off * 1e9:.3f} nm at fixed $\\theta$ (paper 0.76 nm)", fontsize=10)
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    return ax


def fig4(ax=None, lam: float = C.FIG4_LAMBDA):
    """Fig 4: friction proportional to load, lambda = 2 (eqs 18-19): non-parallel lines."""
    ax = _axes(ax)
    c = InclinedCantilever(**C.FIG3)
    z2 = np.linspace(0.0, 10e-9, 101)
    t_in, t_out = load_friction_lines(c, lam, z2)
    k_in, b_in = load_friction_constants(c, lam, +1)
    k_out, b_out = load_friction_constants(c, lam, -1)
    ax.plot(z2 * 1e9, t_in * 1e5, "-", color="C0",
            label=f"inward: k = {k_in:.4f} N/m, $\\beta$ = {b_in * 1e9:.4g} nm/rad")
    ax.plot(z2 * 1e9, t_out * 1e5, "--", color="C3",
            label=f"outward: k = {k_out:.4f} N/m, $\\beta$ = {b_out * 1e9:.4g} nm/rad")
    ax.set_xlabel("tip displacement $z_2$ [nm]")
    ax.set_ylabel("deflection angle $\\theta$ [$10^{-5}$ rad]")
    ax.set_title(f"Fig 4: friction $\\propto$ load, $\\lambda$ = {lam:g}", fontsize=10)
    ax.legend(frameon=False, fontsize=8)
    ax.grid(alpha=0.3)
    return ax
