"""A virtual Fig 7: one fast run through the ``paper`` instrument preset (section 3, Figs 7-8).

The paper's Fig 7 plots the photodiode signal of a 17 um/s measurement against
(A) the nominal piezo position, (B) the position detector's reading and (C)
the reading with the inward run shifted to overlay the outward one, after an
11-point running average. Here the same three views of a simulated run
recorded with :func:`afmforce.instrument.get_preset` ``("paper")`` show the
same phenomena: piezo hysteresis (A), detector backlash (B) and fringes.
"""

from __future__ import annotations

import numpy as np

NM = 1e9
UM = 1e6

#: The run: 17 um/s over about 4 um, in the paper's order (start in contact, out, back in).
FIG7_RUN = dict(xi=0.001, velocity=17e-6, start=-3.7e-6, turn=0.3e-6, end=-3.7e-6, sample_rate=20e3)


def running_average(x: np.ndarray, n: int = 11) -> np.ndarray:
    """Centred n-point running average (edges averaged over the available points)."""
    x = np.asarray(x, dtype=float)
    k = np.ones(n)
    num = np.convolve(x, k, mode="same")
    den = np.convolve(np.ones_like(x), k, mode="same")
    return num / den


def virtual_fig7_curve(seed: int = 7):
    """Simulate and record the virtual Fig 7 run; returns the RawCurve."""
    from ..dynamics import simulate
    from ..instrument import get_preset
    from ..instrument.protocols import out_then_in

    traj = simulate(**FIG7_RUN)
    return get_preset("paper").record(out_then_in(traj), seed=seed)


def fig7_virtual(fast: bool = False, seed: int = 7):
    """Three panels: signal vs nominal position, vs measured, vs measured with the inward shift."""
    from matplotlib.figure import Figure

    from ..instrument.detector import PAPER_BACKLASH

    raw = virtual_fig7_curve(seed)
    fig = Figure(figsize=(14, 4.3), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    inward = raw.segment == 0
    outward = raw.segment == 1
    sig = np.asarray(raw.deflection_signal)
    shift = dict(PAPER_BACKLASH)[17e-6]  # the paper's +57 nm at 17 um/s (Fig 7C)
    measured = running_average(raw.piezo_measured, 11)
    views = [
        (raw.piezo_nominal, 0.0, "A: nominal piezo position"),
        (raw.piezo_measured, 0.0, "B: measured position (detector)"),
        (measured, shift, f"C: measured, 11-point average, inward shifted {shift * NM:+.0f} nm"),
    ]
    for ax, (x, dx, title) in zip(axes, views):
        ax.plot((x[outward]) * UM, sig[outward], ".", ms=1.2, color="C3", label="outward run")
        ax.plot((x[inward] + dx) * UM, sig[inward], ".", ms=1.2, color="C0", label="inward run")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("position [$\\mu$m]")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("photodiode signal [V]")
    axes[0].legend(frameon=False, fontsize=8, markerscale=6, loc="upper left")
    fig.suptitle("virtual Fig 7: 17 $\\mu$m/s through the 'paper' instrument (hysteresis, backlash, "
                 "fringes, saturation)", fontsize=11)
    return fig
