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

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ParameterError
from .registry import LiveDict, result_fields

__all__ = ["MapQuantity", "MAP_QUANTITIES", "map_quantity", "MapImage", "map_images", "write_map_hdf5", "EXTENT_KEY",
           "map_histogram", "MapPoints", "map_points", "write_points_hdf5", "GRID_TOLERANCE"]

#: How far the curves' recorded positions may lie from the grid their indices give, as a fraction of the
#: grid step [-]: further (a rotated grid, free points, indices made up row by row), the map is no grid in
#: micrometres, and is drawn as the positions it records (:func:`map_points`), never forced into one.
GRID_TOLERANCE = 0.25

#: PNG text key holding the heat map's pixel box in the image: "left top right bottom".
EXTENT_KEY = "afmforce.map_extent"

#: SI unit -> (factor, unit shown on the image).
MAP_DISPLAY_UNITS = {"m": (1e9, "nm"), "N": (1e9, "nN"), "m/V": (1e9, "nm/V"), "J/m^2": (1e3, "mJ/m^2"),
            "J m": (1e27, "1e-27 J m"), "J": (1e21, "zJ"), "m/s": (1e6, "µm/s"), "Pa": (1e-3, "kPa")}


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
    needs : str
        The curves that give it, where not every curve may (said when a map has no value).
    """

    identifier: str
    column: str
    label: str
    unit: str
    sign: float = 1.0
    needs: str = ""


#: What the indentation fit's quantities need (its step skips hard contacts: ``analysis.indentation``).
_SOFT = "soft contacts: the indentation fit skips hard ones (the tip does not indent the sample)"


def _quantities() -> dict[str, "MapQuantity"]:
    return {q.identifier: q for q in (
        MapQuantity("adhesion", "adhesion_force", "adhesion (depth of the retract dip below its baseline)", "N", -1.0),
        MapQuantity("jump_in_distance", "jump_in_separation", "jump-in distance (separation before the jump)", "m"),
        *(MapQuantity(f.name, f.name, f.label, f.unit or "") for f in result_fields().values() if f.mapped),
        MapQuantity("jump_in_deflection", "jump_in_deflection", "jump-in deflection", "m"),
        MapQuantity("modulus", "youngs_modulus", "Young's modulus (indentation fit)", "Pa", needs=_SOFT),
        MapQuantity("topography", "contact_point", "height: minus the piezo position at contact", "m", -1.0,
                    needs=_SOFT),
        # the fast map's further columns (afmforce.sweep.map_fast.PIXEL_COLUMNS)
        MapQuantity("topography_se", "contact_point_se", "standard error of the contact point", "m", needs=_SOFT),
        MapQuantity("max_indentation", "max_indentation", "deepest indentation (fit)", "m", needs=_SOFT),
        MapQuantity("max_force", "max_force", "force at the deepest indentation, above the baseline", "N",
                    needs=_SOFT),
        MapQuantity("adhesion_noise", "adhesion_noise", "baseline noise (force, rms)", "N"),
        MapQuantity("work_of_adhesion_se", "work_of_adhesion_se", "uncertainty of the work of adhesion", "J/m^2"),
    )}


#: The registry: the named map quantities, then every field the steps' records map (by default those
#: both in the printed summary and in the summary table: :mod:`.registry`) by its own name (kept up to
#: date with the registered steps).
MAP_QUANTITIES: dict[str, MapQuantity] = LiveDict(_quantities)


#: The quantities mapped when none is asked for (``afmforce analyze MAP --out``, the web's analyse view):
#: each one some curve of the map gave (the CLI leaves out those no curve gave; asked for, they are
#: drawn all "no value", with :attr:`MapImage.note`).
DEFAULT_MAPS = ("adhesion", "modulus", "topography", "indentation", "jump_in_distance", "hamaker_radius")


def map_quantity(name: str) -> MapQuantity:
    """The registered quantity ``name`` (ParameterError listing the choices otherwise)."""
    try:
        return MAP_QUANTITIES[name]
    except KeyError:
        raise ParameterError(f"`map_quantity` {name}: unknown; choose from {', '.join(MAP_QUANTITIES)}") from None


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
    x0, y0, dx, dy : float
        Position of grid point (0, 0) and the grid steps [m], from the curves' ``position_x``,
        ``position_y``; NaN when the map does not record them (the axes show grid indices). A step
        is negative where the positions fall as the index grows (column ``x`` lies at ``x0 + x dx``
        whatever the sign: the image is drawn with its axes increasing, the HDF5 keeps the positions).
        When only the scanned area's size is known (``map_width``, ``map_height``), the
        grid is centred in it: ``x0 = dx / 2``, ``dx = width / nx``.
    note : str
        Why no pixel has a value (``""`` when some has): the curves' contact kinds and failures,
        and which curves give the quantity (:attr:`MapQuantity.needs`). The image is then all
        "no value", never zeros; the PNG, the CLI and the web page say this note.
    """

    source: str
    quantity: MapQuantity
    values: np.ndarray
    n_curves: int
    x0: float = float("nan")
    y0: float = float("nan")
    dx: float = float("nan")
    dy: float = float("nan")
    note: str = ""

    @property
    def has_positions(self) -> bool:
        """The grid's positions are known (axes in um)."""
        return bool(np.isfinite([self.x0, self.y0, self.dx, self.dy]).all() and self.dx != 0 and self.dy != 0)

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
    grid indices are skipped; failed rows give NaN pixels). A file whose recorded positions
    do not lie on the grid of its indices (:data:`GRID_TOLERANCE`) gives no image: :func:`map_points`."""
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
        fit = _grid_fit(rows, x, y)
        if fit is None:             # positions off the grid: drawn as points (map_points)
            continue
        ok = (x >= 0) & (x < nx) & (y >= 0) & (y < ny)
        values[y[ok], x[ok]] = q.sign * col.to_numpy(float)[ok]
        axes = fit
        if not all(np.isfinite(a).all() for a in axes):        # no positions: the scanned area's size
            size = [float(pd.to_numeric(rows[c], errors="coerce").median()) if c in rows else math.nan
                    for c in ("map_width", "map_height")]
            if all(math.isfinite(v) and v > 0 for v in size):
                axes = [(s / n / 2, s / n) for s, n in zip(size, (nx, ny))]
        note = "" if np.isfinite(values).any() else _empty_note(rows, q)
        out.append(MapImage(str(source), q, values, int(len(rows)), axes[0][0], axes[1][0], axes[0][1],
                            axes[1][1], note))
    return out


def _positions(rows) -> tuple[np.ndarray, np.ndarray]:
    """The rows' ``position_x``, ``position_y`` [m] (NaN where not recorded)."""
    import pandas as pd

    return tuple(pd.to_numeric(rows[c], errors="coerce").to_numpy(float) if c in rows
                 else np.full(len(rows), np.nan) for c in ("position_x", "position_y"))


def _grid_fit(rows, ix: np.ndarray, iy: np.ndarray):
    """``[(x0, dx), (y0, dy)]`` [m] of the grid the rows' positions give (signed steps; NaN: not
    recorded, or one column or row only), or None when the positions lie off the grid of the
    indices: a rotated grid (each position moving with both indices), points off their cells by more
    than :data:`GRID_TOLERANCE` of a step, or two grid cells at one place."""
    px, py = _positions(rows)
    ok = np.isfinite(px) & np.isfinite(py)
    nan = [(math.nan, math.nan), (math.nan, math.nan)]
    if ok.sum() < 2 or (np.ptp(px[ok]) == 0 and np.ptp(py[ok]) == 0):
        return nan                            # no positions, or one place for all: the axes show indices
    i, j = ix[ok].astype(float), iy[ok].astype(float)
    many = (np.unique(i).size >= 2, np.unique(j).size >= 2)
    if not any(many):
        return nan
    names = ["origin"] + [n for n, m in zip(("i", "j"), many) if m]
    a = np.column_stack([np.ones_like(i)] + [v for v, m in zip((i, j), many) if m])
    cx = dict(zip(names, np.linalg.lstsq(a, px[ok], rcond=None)[0]))
    cy = dict(zip(names, np.linalg.lstsq(a, py[ok], rcond=None)[0]))
    dx, dy = cx.get("i", math.nan), cy.get("j", math.nan)       # signed steps
    cross = (cx.get("j", 0.0), cy.get("i", 0.0))                 # x moving with the row: a rotated grid
    step = min(abs(s) for s in (dx, dy) if math.isfinite(s))
    if not step > 0:
        return None                           # the positions do not move with the index: no grid
    off = np.hypot(px[ok] - a @ [cx[n] for n in names], py[ok] - a @ [cy[n] for n in names])
    if max(abs(c) for c in cross) > GRID_TOLERANCE * step or off.max() > GRID_TOLERANCE * step:
        return None
    # on the grid: each axis from its own index alone (a column's place is the line through every row's
    # positions of it, as the image draws it: no cross term, which the check above found within tolerance)
    axes = []
    for v, idx, m in ((px[ok], i, many[0]), (py[ok], j, many[1])):
        if not m:
            axes.append((math.nan, math.nan))
            continue
        o, d = np.linalg.lstsq(np.column_stack((np.ones_like(idx), idx)), v, rcond=None)[0]
        axes.append((float(o), float(d)))
    return axes


@dataclass(frozen=True)
class MapPoints:
    """A map's values at the places its curves record, where they form no grid (free points, a rotated
    grid, positions off the cells of their indices): drawn as points, never forced into a grid.

    Attributes
    ----------
    source : str
    quantity : MapQuantity
    x, y : ndarray, shape (n,)
        Recorded positions [m] (``position_x``, ``position_y``).
    values : ndarray, shape (n,)
        The quantity in SI; NaN where the curve's analysis failed or found nothing.
    curves : ndarray, shape (n,)
        The curves' indices in the file [-] (-1 when unknown).
    why : str
        Why no grid (said on the figure and in the HDF5).
    note : str
        As :attr:`MapImage.note`: why no point has a value (``""`` when some has).
    """

    source: str
    quantity: MapQuantity
    x: np.ndarray
    y: np.ndarray
    values: np.ndarray
    curves: np.ndarray
    why: str
    note: str = ""

    @property
    def name(self) -> str:
        """File name of the map."""
        return Path(self.source).name


def map_points(table, quantity: str | MapQuantity) -> list[MapPoints]:
    """One :class:`MapPoints` per file of two or more curves whose recorded positions make no grid
    (no grid indices, or indices whose grid the positions do not follow: :func:`map_images` gives
    no image of those)."""
    import pandas as pd

    q = quantity if isinstance(quantity, MapQuantity) else map_quantity(quantity)
    if table is None or len(table) == 0 or "file" not in table.columns:
        return []
    out = []
    for source, rows in table.groupby("file", sort=True):
        px, py = _positions(rows)
        ok = np.isfinite(px) & np.isfinite(py)
        if ok.sum() < 2 or (np.ptp(px[ok]) == 0 and np.ptp(py[ok]) == 0):
            continue
        ix = pd.to_numeric(rows["map_x"], errors="coerce").fillna(-1).to_numpy(int) if "map_x" in rows \
            else np.full(len(rows), -1)
        iy = pd.to_numeric(rows["map_y"], errors="coerce").fillna(-1).to_numpy(int) if "map_y" in rows \
            else np.full(len(rows), -1)
        gridded = (ix >= 0) & (iy >= 0)
        if gridded.any():
            if _grid_fit(rows[gridded], ix[gridded], iy[gridded]) is not None:
                continue                                    # a grid: map_images draws it
            why = "the recorded positions do not lie on the grid of the curves' indices (rotated or free points)"
        else:
            why = "the file records positions, no grid"
        col = pd.to_numeric(rows[q.column], errors="coerce") if q.column in rows else pd.Series(np.nan, rows.index)
        values = q.sign * col.to_numpy(float)[ok]
        curves = pd.to_numeric(rows["curve"], errors="coerce").fillna(-1).to_numpy(int)[ok] if "curve" in rows \
            else np.full(int(ok.sum()), -1)
        note = "" if np.isfinite(values).any() else _empty_note(rows, q)
        out.append(MapPoints(str(source), q, px[ok], py[ok], values, curves, why, note))
    return out


def write_points_hdf5(points: list[MapPoints], path, *, force: bool = True) -> Path:
    """The numbers of one file's :class:`MapPoints` in one HDF5 file, atomically: ``x``, ``y``
    (positions [m]) and ``curve`` per point, and one dataset per quantity (``values[i]`` at
    ``(x[i], y[i])``, SI; attributes ``unit``, ``label``, ``column``). Root attributes: ``format`` =
    ``afmforce-map-points``, ``layout`` = ``points``, ``why`` (no grid)."""
    import h5py

    from .._files import atomic_path

    if not points:
        raise ParameterError("no map points to write")
    first = points[0]
    path = Path(path)
    with atomic_path(path, force) as tmp, h5py.File(tmp, "w") as h5:
        h5.attrs.update(format="afmforce-map-points", layout="points", source=first.source, why=first.why)
        for name, data in (("x", first.x), ("y", first.y)):
            h5.create_dataset(name, data=data).attrs["unit"] = "m"
        h5.create_dataset("curve", data=first.curves)
        for p in points:
            d = h5.create_dataset(p.quantity.identifier, data=p.values)
            d.attrs.update(unit=p.quantity.unit, label=p.quantity.label, column=p.quantity.column)
            if p.note:
                d.attrs["note"] = p.note
    return path


def _empty_note(rows, q: MapQuantity) -> str:
    """Why none of a map's ``rows`` gave ``q``: their contact kinds and failures, what gives ``q``."""
    import pandas as pd

    failed = (rows["error"].notna() & (rows["error"].astype(str) != "")) if "error" in rows else \
        pd.Series(False, index=rows.index)
    parts = [f"{int(failed.sum())} failed"] if failed.any() else []
    if "contact_kind" in rows:
        kinds = rows.loc[~failed, "contact_kind"].fillna("unknown").astype(str).value_counts()
        parts += [f"{n} {kind} contact{'s' if n > 1 else ''}" for kind, n in kinds.items()]
    text = f"no curve gave it ({len(rows)} curves" + (": " + ", ".join(parts) if parts else "") + ")"
    return text + (f"; it comes from {q.needs}" if q.needs else "")


def write_map_hdf5(images: list[MapImage], path, *, force: bool = True) -> Path:
    """The numbers of one map's images in one HDF5 file, atomically.

    One dataset per quantity (``values[y, x]``, SI; attributes ``unit``, ``label``, ``column``),
    and the grid: ``x`` and ``y`` (positions of the columns and rows [m], or their indices when
    the map records no positions: attribute ``unit`` is then ``""``), ``map_x``/``map_y`` indices.
    """
    import h5py

    from .._files import atomic_path

    if not images:
        raise ParameterError("no map images to write")
    first = images[0]
    ny, nx = first.shape
    path = Path(path)
    with atomic_path(path, force) as tmp, h5py.File(tmp, "w") as h5:
        h5.attrs["format"] = "afmforce-map-images"
        h5.attrs["source"] = first.source
        for name, n, origin, step in (("x", nx, first.x0, first.dx), ("y", ny, first.y0, first.dy)):
            idx = np.arange(n)
            h5.create_dataset(f"map_{name}", data=idx)
            known = first.has_positions
            d = h5.create_dataset(name, data=origin + step * idx if known else idx.astype(float))
            d.attrs["unit"] = "m" if known else ""
        for image in images:
            d = h5.create_dataset(image.quantity.identifier, data=image.values, compression="gzip")
            d.attrs.update(unit=image.quantity.unit, label=image.quantity.label, column=image.quantity.column)
            if image.note:              # all NaN: why (MapImage.note)
                d.attrs["note"] = image.note
    return path


def map_histogram(image: MapImage, bins: int = 50) -> tuple[np.ndarray, np.ndarray]:
    """Histogram of the map's finite values: ``(counts, edges)``, edges in SI (``quantity.unit``);
    ``bins`` equal bins from the smallest to the largest value (``numpy.histogram``)."""
    if not (isinstance(bins, int) and bins >= 1):
        raise ParameterError(f"bins must be a positive integer, got {bins!r}")
    values = image.values[np.isfinite(image.values)]
    if values.size == 0:
        return np.zeros(bins, dtype=int), np.full(bins + 1, np.nan)
    return np.histogram(values, bins=bins)
