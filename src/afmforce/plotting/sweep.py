"""Figures of sweep results (:class:`afmforce.sweep.SweepResult`, used by duck typing: the
plotting layer never imports the sweep): heat map, line or scatter of a metric."""

from __future__ import annotations

from typing import Mapping

import numpy as np

__all__ = ["plot_metric", "DISPLAY_UNITS"]

#: SI unit -> (factor, unit shown on plots).
DISPLAY_UNITS: dict[str, tuple[float, str]] = {
    "m": (1e9, "nm"), "N": (1e9, "nN"), "m/s": (1e6, "µm/s"), "rad": (180 / np.pi, "deg"),
    "kg": (1.0, "kg"), "s": (1.0, "s"), "kg/s": (1.0, "kg/s"),
}


def _label(name: str, units: Mapping[str, str]) -> tuple[float, str]:
    unit = units.get(name, "")
    factor, shown = DISPLAY_UNITS.get(unit, (1.0, unit))
    return factor, f"{name} [{shown}]" if shown else name


def _edges(centres: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around grid values (geometric midpoints on log axes)."""
    c = np.log(centres) if log else np.asarray(centres, float)
    if len(c) == 1:
        mid = np.array([c[0] - 0.5, c[0] + 0.5]) if not log else np.array([c[0] - 0.1, c[0] + 0.1])
    else:
        inner = (c[1:] + c[:-1]) / 2
        mid = np.concatenate([[2 * c[0] - inner[0]], inner, [2 * c[-1] - inner[-1]]])
    return np.exp(mid) if log else mid


def _is_log(result, name: str) -> bool:
    spec = result.spec
    if spec is None:
        return False
    return any(a.name == name and a.log for a in spec.grid) or any(r.name == name and r.log for r in spec.ranges)


def plot_metric(result, metric: str, *, x: str | None = None, y: str | None = None,
                units: Mapping[str, str] | None = None, ax=None):
    """Plot ``metric`` over the swept parameters; returns the matplotlib Axes.

    A grid with two or more varying axes gives a heat map over ``x`` and ``y``
    (default: the first two varying axes; other axes are held at their first
    value, named in the title); one varying axis gives a line; sampled sweeps
    give a scatter coloured by the metric. Lengths are shown in nm, forces in
    nN, speeds in µm/s.
    """
    table = result.table
    if metric not in table.columns:
        names = ", ".join(result.output_names)
        raise KeyError(f"no metric {metric!r} in the results; choose one of: {names}")
    units = dict(units or {})
    varying = [n for n in result.parameter_names if table[n].nunique() > 1]
    numeric = [n for n in varying if np.issubdtype(table[n].dtype, np.number)]
    x = x or (numeric[0] if numeric else varying[0])
    y = y or next((n for n in numeric if n != x), None)
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6, 4.5)).add_subplot()
    mf, mlabel = _label(metric, units)
    xf, xlabel = _label(x, units)
    held = []
    if y is not None and result.is_grid:
        ds = result.to_xarray()
        sel = {d: 0 for d in ds[metric].dims if d not in (x, y)}
        held = [f"{d}={ds[d].values[0]:.3g}" for d in sel]
        grid = ds[metric].isel(sel).transpose(y, x)
        yf, ylabel = _label(y, units)
        xs, ys = np.asarray(ds[x].values, float), np.asarray(ds[y].values, float)
        mesh = ax.pcolormesh(_edges(xs, _is_log(result, x)) * xf, _edges(ys, _is_log(result, y)) * yf,
                             np.asarray(grid.values, float) * mf, shading="flat")
        ax.figure.colorbar(mesh, ax=ax, label=mlabel)
        ax.set_ylabel(ylabel)
    elif y is not None:
        yf, ylabel = _label(y, units)
        sc = ax.scatter(table[x] * xf, table[y] * yf, c=table[metric].astype(float) * mf, s=18)
        ax.figure.colorbar(sc, ax=ax, label=mlabel)
        ax.set_ylabel(ylabel)
    else:
        order = np.argsort(table[x].to_numpy())
        ax.plot(table[x].to_numpy()[order] * xf, table[metric].to_numpy(float)[order] * mf, "o-")
        ax.set_ylabel(mlabel)
    if _is_log(result, x):
        ax.set_xscale("log")
    if y is not None and _is_log(result, y):
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_title(metric + (f" ({', '.join(held)})" if held else ""))
    return ax
