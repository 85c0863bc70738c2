"""Figures of a dynamic fit: data, model and residuals per curve; the residuals of all
curves in noise units side by side; profile likelihoods."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .._files import atomic_path

__all__ = ["plot_curves", "plot_profiles", "plot_residuals"]


def _save(fig, path: Path, force: bool) -> Path:
    with atomic_path(path, force) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    return path


def plot_curves(result, curves, directory: str | os.PathLike, force: bool = False) -> list[Path]:
    """One PNG per curve: deflection vs position (data, model), residuals below.

    ``curves`` are the prepared :class:`~afmforce.fit.FitCurve` objects
    (``result._problem.ev.curves``). Returns the paths written.
    """
    from matplotlib.figure import Figure

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    preds = result.predictions()
    out = []
    nm = 1e9
    for i, (c, cf, m) in enumerate(zip(curves, result.curves, preds)):
        fig = Figure(figsize=(7, 6))
        a0, a1 = fig.subplots(2, 1, sharex=True,
                                     gridspec_kw={"height_ratios": [3, 1.3]})
        z = (c.position - cf.shift) * nm
        a0.plot(z, c.deflection * nm, ".", ms=3, color="0.45", label="data")
        a0.plot(z[~c.mask], c.deflection[~c.mask] * nm, "x", ms=4, color="C1",
                label="left out (jump-in, landing)")
        if m is not None:
            a0.plot(z, m * nm, "-", color="C0", lw=1.2, label=f"{result.model} model")
            a1.plot(z[c.mask], (c.deflection - m)[c.mask] * nm, ".", ms=3, color="C3")
        a1.axhline(0, color="k", lw=0.6)
        a0.set_ylabel("apparent deflection [nm]")
        a1.set_ylabel("residual [nm]")
        a1.set_xlabel("piezo position z − shift [nm]")
        a0.set_title(f"{c.name}: {c.velocity * 1e6:.3g} µm/s, {c.sample_rate:.4g} Hz")
        a0.legend(fontsize=8, loc="upper left")
        lo = min(np.min(c.deflection), 0) * nm
        a0.set_ylim(lo - 1.0, max(5.0, -3 * lo))
        fig.tight_layout()
        stem = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in Path(c.name).stem)
        out.append(_save(fig, directory / f"fit_curve{i + 1}_{stem}.png", force))
    return out


def plot_profiles(result, path: str | os.PathLike, force: bool = False) -> Path | None:
    """Profile likelihood (delta chi-square) of every profiled parameter; None if none."""
    if not result.profiles:
        return None
    from matplotlib.figure import Figure
    from scipy.stats import chi2

    names = list(result.profiles)
    fig = Figure(figsize=(4.5 * len(names), 3.8))
    axes = fig.subplots(1, len(names), squeeze=False)
    thr = chi2.ppf(result.level, 1)
    for ax, name in zip(axes[0], names):
        p = result.profiles[name]
        e = result.parameters[name]
        ax.plot(p["value"], p["delta_chi2"], "o-", color="C0", ms=4)
        ax.axhline(thr, color="C3", lw=0.8, ls="--", label=f"{result.level:.0%} threshold")
        for v in e.interval:
            if v is not None:             # a None end: one-sided interval (search bound reached)
                ax.axvline(v, color="C3", lw=0.6)
        ax.axvline(e.value, color="k", lw=0.6)
        ax.set_xlabel(f"{name} [{e.unit}]")
        ax.set_ylabel("Δχ² (profiled)")
        ax.set_ylim(0, max(2 * thr, min(max(p["delta_chi2"]), 5 * thr)))
        ax.legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    _save(fig, path, force)
    return path


def plot_residuals(result, curves, path: str | os.PathLike, force: bool = False) -> Path:
    """All curves' residuals in noise units against ``z - shift``, one panel per curve.

    The residuals are those the fit minimises (whitened where the noise model has a
    1/f part); the title of each panel gives the curve's reduced chi-square, the
    figure's title the fit's and its threshold (:mod:`afmforce.fit.adequacy`).
    """
    from matplotlib.figure import Figure

    prob, x = result._problem, result._x
    values, shifts = prob.unpack(x)
    fig = Figure(figsize=(7, 1.9 * len(curves) + 0.8))
    axes = fig.subplots(len(curves), 1, squeeze=False)[:, 0]
    for i, (ax, c, r) in enumerate(zip(axes, curves, prob.curve_residuals(x))):
        z = (c.position[c.mask] - shifts[i]) * 1e9
        ax.plot(z, r, ".", ms=2.5, color="C3")
        ax.axhline(0, color="k", lw=0.6)
        for yy in (-3, 3):
            ax.axhline(yy, color="0.6", lw=0.5, ls="--")
        ax.set_ylabel("residual / noise")
        ax.set_title(f"{c.name}: {c.velocity * 1e6:.3g} µm/s, reduced χ² "
                     f"{float(np.mean(r ** 2)):.3g}", fontsize=9)
    axes[-1].set_xlabel("piezo position z − shift [nm]")
    adq = result.adequacy or {}
    fig.suptitle(f"reduced χ² {result.redchi:.3g} (threshold {adq.get('threshold', np.nan):.3g}): "
                 + ("the model describes the data" if adq.get("adequate", True)
                    else "the model does NOT describe the data"), fontsize=10)
    fig.tight_layout()
    path = Path(path)
    _save(fig, path, force)
    return path
