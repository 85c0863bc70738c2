"""Force maps: a quantity of every analysed curve as an image over the map's grid.

The batch analysis (:mod:`afmforce.sweep.files`) gives one row per curve
with its grid indices (``map_x`` column, ``map_y`` row, ``map_nx`` x ``map_ny``
grid; -1 for curves outside maps). :func:`map_images` turns a chosen quantity
(:data:`MAP_QUANTITIES`) into one :class:`MapImage` per map file;
:func:`afmforce.plotting.plot_map` draws it, :func:`afmforce.plotting.write_map_png`
writes it atomically.

>>> from afmforce.analysis.maps import map_images
>>> from afmforce.plotting import write_map_png
>>> for image in map_images(table, "adhesion"):                    # doctest: +SKIP
...     write_map_png(image, f"{image.name}.adhesion.png")
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from .result import SUMMARY_FIELDS

__all__ = ["MapQuantity", "MAP_QUANTITIES", "map_quantity", "MapImage", "map_images", "EXTENT_KEY"]

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
    width, height : float
        Size of the scanned area [m] (NaN: not in the file; the image then shows grid indices).
    """

    source: str
    quantity: MapQuantity
    values: np.ndarray
    n_curves: int
    width: float = float("nan")
    height: float = float("nan")

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
        size = [float(pd.to_numeric(rows[c], errors="coerce").median()) if c in rows else float("nan")
                for c in ("map_width", "map_height")]
        out.append(MapImage(str(source), q, values, int(len(rows)), *size))
    return out
