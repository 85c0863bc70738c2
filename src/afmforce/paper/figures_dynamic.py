"""The paper's dynamic figures: Fig 1 (inertia), Fig 5 (trajectory), Fig 6 (apparent vs
actual), and the theory curves of Figs 9-10. Each function takes ``ax=None`` (or
``axes=None``) and returns what it drew on. Units on the axes are the paper's
(nm, nN, rad, um/s).
"""

from __future__ import annotations

import numpy as np

from .. import constants as C
from ..dynamics import static_curve
from .runs import FIG1_RUN, FIG5_RUN, FIG9_EXPERIMENTS, FIG9_RUN, run

NM = 1e9


def _axes(ax, figsize=(5.5, 4.2)):
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=figsize, layout="constrained").add_subplot()
    return ax


def plot_static(ax, curve, label="static", color="k"):
    """Static deflection vs separation: solid where stable, dashed where unstable."""
    h, d, st = curve.separation * NM, curve.deflection * NM, curve.stable
    far = st & (curve.separation > curve.jump_in_separation)
    ax.plot(h[far], d[far], "-", color=color, lw=2, label=label)
    uns = ~st
    ax.plot(h[uns], d[uns], "--", color=color, lw=1.2, label=f"{label} (unstable)")
    return ax


def _approach(tr, after_contact: float = 0.0):
    """Approach samples up to ``after_contact`` seconds past first contact.

    In contact the nearly undamped high-frequency mode rings (spec section 7);
    the paper's figures show the approach to contact.
    """
    sel = tr.segment == 0
    tc = tr.events.contact_time
    if np.isfinite(tc):
        sel &= tr.time <= tc + after_contact
    return sel


def fig1(ax=None, velocities=C.FIG1["velocities"]):
    """Fig 1: deflection vs separation for the simple spring (m = 10 ug, k = 0.21 N/m, R = 100 nm)."""
    ax = _axes(ax)
    curve = static_curve(C.FIG1["spring_constant"], C.FIG1["radius"], h_max=30e-9)
    plot_static(ax, curve)
    for i, v in enumerate(velocities):
        tr = run(velocity=v, **FIG1_RUN)
        a = _approach(tr)
        ax.plot(tr.separation[a] * NM, tr.deflection[a] * NM, color=f"C{i}", lw=1.2,
                label=f"{v * 1e6:g} $\\mu$m/s")
    ax.set_xlim(0, 20)
    ax.set_ylim(-6, 0.5)
    ax.set_xlabel("separation $h$ [nm]")
    ax.set_ylabel("deflection $x$ [nm]")
    ax.set_title("Fig 1: simple spring, m = 10 $\\mu$g, k = 0.21 N/m, R = 100 nm", fontsize=10)
    ax.legend(frameon=False, fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    return ax


def fig5(ax=None, xi: float = 0.1, velocity: float = 0.1e-6):
    """Fig 5: deflection angle vs drive position over a full cycle, with a constant-compliance inset."""
    ax = _axes(ax, (6.5, 4.6))
    tr = run(xi=xi, velocity=velocity, **FIG5_RUN)
    a, r = tr.segment == 0, tr.segment == 1
    ax.plot(tr.piezo_position[a] * NM, tr.angle[a] * 1e5, "-", color="C0", lw=1, label="inward")
    ax.plot(tr.piezo_position[r] * NM, tr.angle[r] * 1e5, "--", color="C3", lw=1, label="outward")
    ev = tr.events
    if np.isfinite(ev.spike_position):
        ax.annotate("spike", xy=(ev.spike_position * NM, (ev.spike_height / tr.calibration_factor) * 1e5),
                    xytext=(-60, 20), textcoords="offset points", fontsize=8,
                    arrowprops=dict(arrowstyle="->", lw=0.8))
    ax.set_xlabel("drive position $z$ [nm]")
    ax.set_ylabel("deflection angle $\\theta$ [$10^{-5}$ rad]")
    ax.set_title(f"Fig 5: $\\xi$ = {xi:g} kg/s, $\\dot z$ = {velocity * 1e6:g} $\\mu$m/s", fontsize=10)
    ax.legend(frameon=False, fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    ins = ax.inset_axes([0.55, 0.08, 0.42, 0.38])
    sel_a = a & (tr.piezo_position > 10e-9) & (tr.piezo_position < 18e-9)
    sel_r = r & (tr.piezo_position > 10e-9) & (tr.piezo_position < 18e-9)
    ins.plot(tr.piezo_position[sel_a] * NM, tr.angle[sel_a] * 1e5, "-", color="C0", lw=1)
    ins.plot(tr.piezo_position[sel_r] * NM, tr.angle[sel_r] * 1e5, "--", color="C3", lw=1)
    ins.set_title(f"constant compliance: offset {ev.hysteresis_offset * NM:.2f} nm", fontsize=7)
    ins.tick_params(labelsize=6)
    return ax


def fig6(axes=None, velocities=(0.1e-6, 1e-6), xis=(0.01, 0.1)):
    """Fig 6 A/B: actual (full) and apparent (dashed) deflection vs separation.

    The curves are the 100 kHz samples; the spike of every dashed curve (about
    0.2 ms, with the 367 kHz contact ringing on it) is drawn from the integrator's
    dense output: its peak (``events.spike_height``, located on the collocation
    polynomial) is joined to the curve at the spike's drive position and marked,
    and the y range is set to include the highest spike.
    """
    if axes is None:
        from matplotlib.figure import Figure

        axes = Figure(figsize=(11, 4.4), layout="constrained").subplots(1, len(xis), sharey=True)
    tr0 = run(**FIG5_RUN)
    curve = static_curve(tr0.spring_constant, C.FIG5["radius"], h_max=30e-9)
    top = 2.0
    for ax, xi, panel in zip(np.atleast_1d(axes), xis, "AB"):
        plot_static(ax, curve, color="0.4")
        for i, v in enumerate(velocities):
            tr = run(xi=xi, velocity=v, **FIG5_RUN)
            a = _approach(tr, after_contact=1e-3)
            ax.plot(tr.separation[a] * NM, tr.deflection[a] * NM, "-", color=f"C{i}", lw=1.2,
                    label=f"actual, {v * 1e6:g} $\\mu$m/s")
            ax.plot(tr.apparent_separation[a] * NM, tr.apparent_deflection[a] * NM, "--",
                    color=f"C{i}", lw=1.2, label=f"apparent, {v * 1e6:g} $\\mu$m/s")
            ev = tr.events
            if np.isfinite(ev.spike_height):
                hs = (ev.spike_height - ev.spike_position) * NM
                j = int(np.argmin(np.abs(tr.piezo_position[a] - ev.spike_position)))
                ax.plot([tr.apparent_separation[a][j] * NM, hs],
                        [tr.apparent_deflection[a][j] * NM, ev.spike_height * NM], "--",
                        color=f"C{i}", lw=1.0)
                ax.plot([hs], [ev.spike_height * NM], "^", color=f"C{i}", ms=5,
                        label=f"spike {ev.spike_height * NM:.2f} nm (dense output)")
                top = max(top, ev.spike_height * NM + 0.4)
        ax.set_xlim(-2, 20)
        ax.set_xlabel("separation $h$ or $\\tilde h$ [nm]")
        ax.set_title(f"Fig 6{panel}: $\\xi$ = {xi:g} kg/s", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(frameon=False, fontsize=7, loc="lower right")
    for ax in np.atleast_1d(axes):
        ax.set_ylim(-4.5, top)
    np.atleast_1d(axes)[0].set_ylabel("deflection $z_2$ or $\\tilde z_2$ [nm]")
    return axes


def fig9_theory(ax=None, experiments=FIG9_EXPERIMENTS):
    """Figs 9-10 theory: static vdW deflection (R = 220 nm, k = 0.21 N/m) and the 1 ug dynamic
    trajectory sampled at the experiments' rates."""
    ax = _axes(ax, (6.0, 4.4))
    curve = static_curve(C.FIG9["spring_constant"], C.FIG9["radius"], h_max=30e-9)
    plot_static(ax, curve)
    markers = "o^sDv"
    for i, (v, fs) in enumerate(experiments):
        tr = run(velocity=v, sample_rate=fs, **FIG9_RUN)
        a = _approach(tr, after_contact=0.0)
        ax.plot(tr.separation[a] * NM, tr.deflection[a] * NM, markers[i % 5] + "-", ms=3.5, lw=0.8,
                color=f"C{i}", label=f"{v * 1e6:g} $\\mu$m/s at {fs / 1e3:g} kHz")
    ax.set_xlim(0, 25)
    ax.set_ylim(-8, 0.5)
    ax.set_xlabel("separation $h$ [nm]")
    ax.set_ylabel("deflection [nm]")
    ax.set_title("Figs 9-10 theory: A = 5e-19 J, k = 0.21 N/m, R = 220 nm, m = 1 $\\mu$g", fontsize=10)
    ax.legend(frameon=False, fontsize=7, loc="lower right")
    ax.grid(alpha=0.3)
    return ax
