"""Force maps: a quantity of every analysed curve as an image over the map's grid.

The batch analysis (:mod:`afmforce.sweep.analysis`) gives one row per curve
with its grid indices (``map_x`` column, ``map_y`` row, ``map_nx`` x ``map_ny``
grid; -1 for curves outside maps). :func:`map_images` turns a chosen quantity
(:data:`MAP_QUANTITIES`) into one :class:`MapImage` per map file;
:func:`plot_map` draws it, :func:`write_map_png` writes it atomically.

>>> from afmforce.analysis.mapping import map_images, write_map_png
>>> for image in map_images(table, "adhesion"):                    # doctest: +SKIP
...     write_map_png(image, f"{image.name}.adhesion.png")
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_path
from ..errors import ParameterError
from .result import SUMMARY_FIELDS

__all__ = ["MapQuantity", "MAP_QUANTITIES", "map_quantity", "MapImage", "map_images", "plot_map",
           "write_map_png", "EXTENT_KEY"]

#: PNG text key holding the heat map's pixel box in the image: "left top right bottom".
EXTENT_KEY = "afmforce.map_extent"

#: SI unit -> (factor, unit shown on the image).
_DISPLAY = {"m": (1e9, "nm"), "N": (1e9, "nN"), "m/V": (1e9, "nm/V"), "J/m^2": (1e3, "mJ/m^2"),
            "J m": (1e27, "1e-27 J m"), "J": (1e21, "zJ"), "m/s": (1e6, "µm/s")}


@dataclass(frozen=True)
class MapQuantity:
    """A quantity that can be mapped: a column of the summary table, maybe negated.

    Attributes
    ----------
    identifier : str
        Name for ``--map-quantity``.
    column : str
        Column of the batch summary table (an :class:`AnalysisResult` field).
    label : str
        Human-readable name.
    unit : str
        SI unit of the mapped value.
    sign : float
        Factor applied to the column (-1: adhesion is minus the pull-off force).
    """

    identifier: str
    column: str
    label: str
    unit: str
    sign: float = 1.0


#: The registry: the named map quantities, then every numeric summary field by its own name.
MAP_QUANTITIES: dict[str, MapQuantity] = {q.identifier: q for q in (
    MapQuantity("adhesion", "adhesion_force", "adhesion (depth of the retract dip below its baseline)", "N", -1.0),
    MapQuantity("jump_in_distance", "jump_in_separation", "jump-in distance (separation before the jump)", "m"),
    *(MapQuantity(name, name, label, unit) for name, label, unit in SUMMARY_FIELDS),
    MapQuantity("jump_in_deflection", "jump_in_deflection", "jump-in deflection", "m"),
)}


def map_quantity(name: str) -> MapQuantity:
    """The registered quantity ``name`` (ParameterError listing the choices otherwise)."""
    try:
        return MAP_QUANTITIES[name]
    except KeyError:
        raise ParameterError(f"--map-quantity {name}: unknown; choose from {', '.join(MAP_QUANTITIES)}") from None


@dataclass(frozen=True)
class MapImage:
    """One map's values of one quantity on its grid.

    Attributes
    ----------
    source : str
        The map file.
    quantity : MapQuantity
    values : ndarray, shape (ny, nx)
        ``values[y, x]`` in SI (``quantity.unit``); NaN where the grid point has
        no curve, its analysis failed or found nothing.
    n_curves : int
        Curves of this map in the table [-].
    """

    source: str
    quantity: MapQuantity
    values: np.ndarray
    n_curves: int

    @property
    def shape(self) -> tuple[int, int]:
        """(rows ny, columns nx)."""
        return self.values.shape

    @property
    def name(self) -> str:
        """File name of the map."""
        return Path(self.source).name


def map_images(table, quantity: str | MapQuantity) -> list[MapImage]:
    """One :class:`MapImage` per map file in a batch summary table (rows without
    grid indices are skipped; failed rows give NaN pixels)."""
    import pandas as pd

    q = quantity if isinstance(quantity, MapQuantity) else map_quantity(quantity)
    needed = ("file", "map_x", "map_y", "map_nx", "map_ny")
    if table is None or len(table) == 0 or any(c not in table.columns for c in needed):
        return []
    grid = table.loc[(pd.to_numeric(table["map_x"], errors="coerce").fillna(-1) >= 0)
                     & (pd.to_numeric(table["map_y"], errors="coerce").fillna(-1) >= 0)]
    out = []
    for source, rows in grid.groupby("file", sort=True):  # shape: stored, else the largest indices
        ny = int(max(rows["map_ny"].max(), rows["map_y"].max() + 1))
        nx = int(max(rows["map_nx"].max(), rows["map_x"].max() + 1))
        values = np.full((ny, nx), np.nan)
        col = pd.to_numeric(rows[q.column], errors="coerce") if q.column in rows else pd.Series(np.nan, rows.index)
        x = rows["map_x"].to_numpy(int)
        y = rows["map_y"].to_numpy(int)
        ok = (x >= 0) & (x < nx) & (y >= 0) & (y < ny)
        values[y[ok], x[ok]] = q.sign * col.to_numpy(float)[ok]
        out.append(MapImage(str(source), q, values, int(len(rows))))
    return out


def _display(unit: str) -> tuple[float, str]:
    return _DISPLAY.get(unit, (1.0, unit))


def plot_map(image: MapImage, ax=None):
    """Heat map of ``image`` over the grid (x to the right, y upwards, grey: no value).

    Cells are centred on the integer grid indices; lengths are shown in nm,
    forces in nN. Returns the matplotlib Axes.
    """
    import matplotlib as mpl

    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(6, 5), layout="constrained").add_subplot()
    factor, shown = _display(image.quantity.unit)
    ny, nx = image.shape
    values = np.ma.masked_invalid(image.values * factor)
    cmap = mpl.colormaps["viridis"].with_extremes(bad="lightgrey")
    im = ax.imshow(values, origin="lower", interpolation="nearest", cmap=cmap, aspect="equal",
                   extent=(-0.5, nx - 0.5, -0.5, ny - 0.5))
    label = image.quantity.label + (f" [{shown}]" if shown else "")
    ax.figure.colorbar(im, ax=ax, label=label, shrink=0.9)
    ax.set_xlabel("x (column index)")
    ax.set_ylabel("y (row index)")
    finite = int(np.isfinite(image.values).sum())
    ax.set_title(f"{image.name}: {image.quantity.identifier} ({finite} of {nx * ny} points)", fontsize="medium")
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
