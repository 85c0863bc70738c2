"""Heat maps of force-map quantities (:func:`afmforce.analysis.maps.map_images`).

Built on :class:`matplotlib.figure.Figure`, never pyplot; every function takes ``ax=None``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path, atomic_write_text
from ..analysis.maps import EXTENT_KEY, MAP_DISPLAY_UNITS, MapImage, MapPoints, map_histogram

__all__ = ["plot_map", "write_map_png", "plot_map_histogram", "write_map_histograms", "plot_map_points",
           "write_map_points_png"]


def _display(unit: str) -> tuple[float, str]:
    return MAP_DISPLAY_UNITS.get(unit, (1.0, unit))


def plot_map(image: MapImage, ax=None):
    """Heat map of ``image`` over the grid (x to the right, y upwards, grey: no value).

    Cells are centred on the curves' positions, axes in µm, when the map records them
    (``position_x``, ``position_y``), else on the integer grid indices; lengths are shown in nm,
    forces in nN, moduli in kPa. Returns the matplotlib Axes.
    """
    import matplotlib as mpl

    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6, 5), layout="constrained").add_subplot()
    factor, shown = _display(image.quantity.unit)
    ny, nx = image.shape
    shown_values = image.values
    cmap = mpl.colormaps["viridis"].with_extremes(bad="lightgrey")
    if image.has_positions:  # axes in um: cells centred on the curves' positions
        x0, y0, dx, dy = (v * 1e6 for v in (image.x0, image.y0, image.dx, image.dy))
        if dx < 0:   # positions falling with the column index: drawn from the last column, x increasing
            shown_values, x0, dx = shown_values[:, ::-1], x0 + (nx - 1) * dx, -dx
        if dy < 0:
            shown_values, y0, dy = shown_values[::-1], y0 + (ny - 1) * dy, -dy
        extent = (x0 - dx / 2, x0 + (nx - 0.5) * dx, y0 - dy / 2, y0 + (ny - 0.5) * dy)
    else:
        extent = (-0.5, nx - 0.5, -0.5, ny - 0.5)
    values = np.ma.masked_invalid(shown_values * factor)
    im = ax.imshow(values, origin="lower", interpolation="nearest", cmap=cmap, aspect="equal", extent=extent)
    label = image.quantity.label + (f" [{shown}]" if shown else "")
    ax.figure.colorbar(im, ax=ax, label=label, shrink=0.9)
    ax.set_xlabel("x [µm]" if image.has_positions else "x (column index)")
    ax.set_ylabel("y [µm]" if image.has_positions else "y (row index)")
    finite = int(np.isfinite(image.values).sum())
    name = image.name if len(image.name) <= 48 else image.name[:22] + "..." + image.name[-23:]
    pitch = f", {abs(image.dx) * 1e6:.3g} x {abs(image.dy) * 1e6:.3g} µm pixels" if image.has_positions else ""
    ax.set_title(f"{name}\n{image.quantity.identifier}: {finite} of {nx * ny} points{pitch}", fontsize="small")
    if image.note:      # all "no value": say why on the image (its colour bar's range means nothing)
        import textwrap

        ax.text(0.5, 0.5, "\n".join(textwrap.wrap(image.note, 40)), transform=ax.transAxes, ha="center",
                va="center", fontsize="small", bbox={"facecolor": "white", "alpha": 0.9, "edgecolor": "grey"})
    return ax


def write_map_png(image: MapImage, path: str | os.PathLike, *, dpi: int = 100, force: bool = True) -> Path:
    """Write :func:`plot_map` of ``image`` as PNG, atomically.

    The PNG's text chunk :data:`EXTENT_KEY` gives the pixel box of the heat map
    in the image ("left top right bottom", pixels from the top left corner), so
    that tools can read the values' colours back.
    """
    ax = plot_map(image)
    fig = ax.figure
    fig.set_dpi(dpi)
    fig.draw_without_rendering()  # lay out (constrained), then freeze it: the saved box is the measured one
    fig.set_layout_engine("none")
    fig.draw_without_rendering()
    box = ax.get_window_extent()
    height = fig.bbox.height
    extent = f"{box.x0:.2f} {height - box.y1:.2f} {box.x1:.2f} {height - box.y0:.2f}"
    meta: dict[str, Any] = {"Title": f"{image.name}: {image.quantity.label}", "Software": "afmforce",
                            EXTENT_KEY: extent}
    path = Path(path)
    with atomic_path(path, force) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", metadata=meta)
    return path


def plot_map_points(points: MapPoints, ax=None):
    """The values of a map whose positions make no grid (:class:`~afmforce.analysis.maps.MapPoints`),
    each a dot at its recorded position (axes in µm, x to the right, y upwards; open grey circles:
    no value), with a colour bar in the display unit and why it is no grid. Returns the Axes."""
    import matplotlib as mpl

    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6, 5), layout="constrained").add_subplot()
    factor, shown = _display(points.quantity.unit)
    x, y = points.x * 1e6, points.y * 1e6
    good = np.isfinite(points.values)
    if (~good).any():
        ax.scatter(x[~good], y[~good], s=40, facecolors="none", edgecolors="grey", label="no value")
    sc = ax.scatter(x[good], y[good], c=points.values[good] * factor, s=40, cmap=mpl.colormaps["viridis"])
    label = points.quantity.label + (f" [{shown}]" if shown else "")
    ax.figure.colorbar(sc, ax=ax, label=label, shrink=0.9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [µm]")
    ax.set_ylabel("y [µm]")
    name = points.name if len(points.name) <= 48 else points.name[:22] + "..." + points.name[-23:]
    ax.set_title(f"{name}\n{points.quantity.identifier}: {int(good.sum())} of {good.size} points at their "
                 f"recorded positions (no grid)", fontsize="small")
    if points.note:
        import textwrap

        ax.text(0.5, 0.5, "\n".join(textwrap.wrap(points.note, 40)), transform=ax.transAxes, ha="center",
                va="center", fontsize="small", bbox={"facecolor": "white", "alpha": 0.9, "edgecolor": "grey"})
    return ax


def write_map_points_png(points: MapPoints, path: str | os.PathLike, *, dpi: int = 100,
                         force: bool = True) -> Path:
    """Write :func:`plot_map_points` of ``points`` as PNG, atomically."""
    fig = plot_map_points(points).figure
    path = Path(path)
    with atomic_path(path, force) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", metadata={"Title": f"{points.name}: {points.quantity.label}",
                                                          "Software": "afmforce", "Description": points.why})
    return path


def plot_map_histogram(image: MapImage, bins: int = 50, ax=None):
    """Histogram of the map's values (in the heat map's display unit), with the median and the
    number of points. Returns the matplotlib Axes."""
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6, 4), layout="constrained").add_subplot()
    factor, shown = _display(image.quantity.unit)
    counts, edges = map_histogram(image, bins)
    finite = image.values[np.isfinite(image.values)] * factor
    if finite.size:
        ax.stairs(counts, edges * factor, fill=True, alpha=0.8)
        med = float(np.median(finite))
        ax.axvline(med, color="k", lw=1, ls="--", label=f"median {med:.4g} {shown}")
        ax.legend(fontsize="small")
    ax.set_xlabel(image.quantity.label + (f" [{shown}]" if shown else ""))
    ax.set_ylabel("curves")
    ax.set_title(f"{image.name}: {image.quantity.identifier}, {finite.size} of {image.values.size} points",
                 fontsize="small")
    return ax


def write_map_histograms(images: list[MapImage], stem: str | os.PathLike, *, bins: int = 50, dpi: int = 100,
                         force: bool = True) -> list[Path]:
    """Write each image's histogram as ``<stem>.<quantity>.hist.png`` and every count in one table,
    ``<stem>.histograms.csv`` (columns ``quantity``, ``unit``, ``low``, ``high`` [SI], ``count``),
    atomically. Returns the paths (the PNGs, then the CSV)."""
    stem = Path(stem)
    out: list[Path] = []
    lines = ["quantity,unit,low,high,count"]
    for image in images:
        ax = plot_map_histogram(image, bins)
        path = stem.with_name(f"{stem.name}.{image.quantity.identifier}.hist.png")
        with atomic_path(path, force) as tmp:
            ax.figure.savefig(tmp, dpi=dpi, format="png", metadata={"Software": "afmforce"})
        out.append(path)
        counts, edges = map_histogram(image, bins)
        lines += [f"{image.quantity.identifier},{image.quantity.unit},{lo!r},{hi!r},{int(c)}"
                  for c, lo, hi in zip(counts, edges[:-1].tolist(), edges[1:].tolist())]
    path = stem.with_name(f"{stem.name}.histograms.csv")
    atomic_write_text(path, "\n".join(lines) + "\n", force=force)
    out.append(path)
    return out
