"""What a sweep runs: grids, random and Latin-hypercube samples of parameters.

A :class:`SweepSpec` turns into a parameter table (:meth:`SweepSpec.table`),
one row per run, whose columns are the keyword arguments of the function the
sweep calls. Values are SI floats (or text, e.g. ``model = "spring"``); the
command line and TOML files accept units through
:func:`afmforce.units.parse_value`.

Text forms (command line and TOML)::

    velocity=0.1um/s:10um/s:20:log     grid: 20 log-spaced values from lo to hi
    xi=0.001:0.1:10                    grid: 10 linearly spaced values
    model=spring,beam                  grid: the listed values
    m_joint=1e-11kg:1e-9kg:log         range sampled by --sample random|lhs
    start=-20nm                        fixed setting (--set)
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from .._files import read_settings
from ..errors import FileFormatError, ParameterError
from ..limits import MAX_RUNS, check_count
from ..units import normalize_number_text, parse_value

__all__ = [
    "GridAxis",
    "SampledRange",
    "SweepSpec",
    "SAMPLERS",
    "parse_grid",
    "parse_range",
    "parse_setting",
    "build_spec",
    "chunk_size_from_config",
]

#: Parameter name -> dimension for :func:`afmforce.units.parse_value`, or
#: ``None`` for a text parameter. A sweep over an unlisted name is refused.
Dimensions = Mapping[str, "str | None"]


def _uniform_random(n: int, d: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((n, d))


def _latin_hypercube(n: int, d: int, seed: int) -> np.ndarray:
    from scipy.stats import qmc

    return qmc.LatinHypercube(d=d, rng=np.random.default_rng(seed)).random(n)


#: Samplers of the unit hypercube, ``(n, d, seed) -> array (n, d)`` in [0, 1).
SAMPLERS: dict[str, Callable[[int, int, int], np.ndarray]] = {
    "random": _uniform_random,
    "lhs": _latin_hypercube,  # McKay, Beckman & Conover, Technometrics 21, 239 (1979)
}


@dataclass(frozen=True)
class GridAxis:
    """One axis of a grid: a parameter and the values it takes.

    Parameters
    ----------
    name : str
        Keyword argument of the swept function (e.g. ``velocity``).
    values : tuple
        Values in SI units (floats) or text.
    log : bool
        Whether the values are log-spaced (used for plot axes).
    """

    name: str
    values: tuple
    log: bool = False

    def __post_init__(self) -> None:
        if not self.values:
            raise ParameterError(f"grid axis {self.name!r} has no values")
        object.__setattr__(self, "values", tuple(self.values))

    @classmethod
    def spaced(cls, name: str, lo: float, hi: float, n: int, log: bool = False) -> "GridAxis":
        """``n`` values from ``lo`` to ``hi`` inclusive, linear or logarithmic."""
        if int(n) != n or n < 1:
            raise ParameterError(f"grid {name}: the number of values must be a positive integer, got {n}")
        if log and (lo <= 0 or hi <= 0):
            raise ParameterError(f"grid {name}: log spacing needs positive bounds, got {lo:g} and {hi:g}")
        values = np.geomspace(lo, hi, int(n)) if log else np.linspace(lo, hi, int(n))
        return cls(name, tuple(float(v) for v in values), log)


@dataclass(frozen=True)
class SampledRange:
    """A parameter drawn between ``lo`` and ``hi`` [SI], uniformly or in log."""

    name: str
    lo: float
    hi: float
    log: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.lo) and math.isfinite(self.hi)) or self.lo == self.hi:
            raise ParameterError(f"range {self.name}: need two different finite bounds, got {self.lo:g} and {self.hi:g}")
        if self.log and (self.lo <= 0 or self.hi <= 0):
            raise ParameterError(f"range {self.name}: log sampling needs positive bounds")

    def scale(self, u: np.ndarray) -> np.ndarray:
        """Map unit-interval samples onto the range."""
        if self.log:
            a, b = math.log(self.lo), math.log(self.hi)
            return np.exp(a + u * (b - a))
        return self.lo + u * (self.hi - self.lo)


@dataclass(frozen=True)
class SweepSpec:
    """A sweep: grid axes, sampled ranges and fixed settings.

    The runs are the grid's points (first axis slowest) crossed with ``n``
    samples of the ranges drawn by ``sample`` (a key of :data:`SAMPLERS`,
    reproducible through ``seed``). Every run also gets the ``fixed`` settings.

    Parameters
    ----------
    grid : tuple of GridAxis
    ranges : tuple of SampledRange
    sample : str or None
        ``"random"`` or ``"lhs"``; required when ``ranges`` are given.
    n : int
        Number of samples.
    seed : int
        Seed of the sampler.
    fixed : tuple of (name, value)
        Settings shared by every run.
    origins : mapping
        Parameter -> where its values were written, when a settings file gave them (``--config sweep.toml:
        [grid] velocity``), for the messages of later checks; not part of the runs (nor of the fingerprint).
    """

    grid: tuple[GridAxis, ...] = ()
    ranges: tuple[SampledRange, ...] = ()
    sample: str | None = None
    n: int = 0
    seed: int = 0
    fixed: tuple[tuple[str, Any], ...] = field(default=())
    origins: Mapping[str, str] = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        names = [a.name for a in self.grid] + [r.name for r in self.ranges] + [k for k, _ in self.fixed]
        dup = sorted({x for x in names if names.count(x) > 1})
        if dup:
            raise ParameterError(f"parameter(s) {', '.join(dup)} given more than once (`grid`, `ranges` or `sets`)")
        if self.ranges:
            if self.sample not in SAMPLERS:
                raise ParameterError(f"ranges need a sampler: `sample` {' or '.join(SAMPLERS)} (got {self.sample!r})")
            if self.n < 1:
                raise ParameterError(f"`sample` {self.sample} needs `n`, a positive number of samples")
        elif self.sample is not None:
            raise ParameterError(f"`sample` {self.sample} needs at least one `ranges` entry name=lo:hi")
        if not self.grid and not self.ranges:
            raise ParameterError("nothing to sweep: give at least one `grid` or `ranges` entry")
        check_count("runs", self.n_runs, MAX_RUNS, "runs in one sweep")   # before the table is built
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ParameterError(f"seed must be a whole number >= 0 (the sampler's seed), got {self.seed!r}")

    @property
    def is_grid(self) -> bool:
        """True when the runs form a full grid (no sampled ranges)."""
        return not self.ranges

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape (axis lengths), ``()`` without grid axes."""
        return tuple(len(a.values) for a in self.grid)

    @property
    def n_runs(self) -> int:
        """Number of runs."""
        return math.prod(self.shape) * (self.n if self.ranges else 1)

    def table(self):
        """Parameter table: a pandas DataFrame, one row per run, index ``run``."""
        import pandas as pd

        cols: dict[str, Any] = {}
        points = list(itertools.product(*(a.values for a in self.grid))) or [()]
        reps = self.n if self.ranges else 1
        for i, axis in enumerate(self.grid):
            cols[axis.name] = np.repeat([p[i] for p in points], reps)
        if self.ranges:
            u = SAMPLERS[self.sample](self.n, len(self.ranges), self.seed)
            for j, r in enumerate(self.ranges):
                cols[r.name] = np.tile(r.scale(u[:, j]), len(points))
        for name, value in self.fixed:
            cols[name] = [value] * self.n_runs
        frame = pd.DataFrame(cols)
        frame.index.name = "run"
        return frame

    def to_dict(self) -> dict:
        """JSON-friendly description (used for the store key and ``spec.json``)."""
        return {
            "grid": [{"name": a.name, "values": list(a.values), "log": a.log} for a in self.grid],
            "ranges": [{"name": r.name, "lo": r.lo, "hi": r.hi, "log": r.log} for r in self.ranges],
            "sample": self.sample,
            "n": self.n,
            "seed": self.seed,
            "fixed": {k: v for k, v in self.fixed},
        }

    def fingerprint(self) -> str:
        """Hex digest identifying the runs of this spec."""
        text = json.dumps(self.to_dict(), sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()


def _value(name: str, text: Any, dimensions: Dimensions | None, where: str, key: str | None = None):
    """Parse one value of parameter ``key`` (default ``name``) into SI (or keep text); ``name`` is how the
    messages call it (``velocity.lo``: a bound of a settings file's inline table)."""
    key = key or name
    if dimensions is not None and key not in dimensions:
        known = ", ".join(sorted(dimensions))
        raise ParameterError(f"{where}: unknown parameter {key!r}; known parameters: {known}")
    dim = dimensions.get(key, "dimensionless") if dimensions is not None else None
    if dimensions is not None and dim is None:
        return str(text)  # a text parameter such as model
    if isinstance(text, bool):
        return text
    if isinstance(text, (int, float)):
        if not math.isfinite(float(text)):     # a TOML 1e400, inf or nan: named where it was written
            raise ParameterError(f"{where} {name} = {text!r} is not a finite number (a TOML number beyond "
                                 "1.8e308, inf or nan); give a value in the parameter's range")
        return float(text)
    if dim is None:  # generic use without a dimension table: a plain number or text
        try:
            return float(normalize_number_text(text))
        except ValueError:
            return str(text).strip()
    return parse_value(str(text).strip(), dim, f"{where} {name}")


def _split(item: str, flag: str) -> tuple[str, str]:
    name, sep, rest = str(item).partition("=")
    if not sep or not name.strip() or not rest.strip():
        raise ParameterError(f"{flag} expects name=value, got {item!r}")
    return name.strip(), rest.strip()


def _grid_from_text(name: str, rest: str, dimensions: Dimensions | None, flag: str) -> GridAxis:
    if "," in rest or ":" not in rest:
        values = [_value(name, v, dimensions, flag) for v in rest.split(",") if v.strip()]
        return GridAxis(name, tuple(values))
    parts = rest.split(":")
    log = parts[-1].strip().lower() in ("log", "lin")
    spacing = parts.pop().strip().lower() if log else "lin"
    if len(parts) != 3:
        raise ParameterError(f"{flag} expects name=lo:hi:n[:log] or name=v1,v2,..., got {name}={rest}")
    lo, hi = (_value(name, p, dimensions, flag) for p in parts[:2])
    try:
        n = int(parts[2])
    except ValueError:
        raise ParameterError(f"{flag} {name}: the number of values must be an integer, got {parts[2]!r}") from None
    if isinstance(lo, str) or isinstance(hi, str):
        raise ParameterError(f"{flag} {name}: a spaced grid needs numeric bounds")
    check_count(f"{flag} {name}", n, MAX_RUNS, "values")      # before the axis is allocated
    return GridAxis.spaced(name, lo, hi, n, log=spacing == "log")


def parse_grid(item: str, dimensions: Dimensions | None = None) -> GridAxis:
    """Parse ``name=lo:hi:n[:log]`` or ``name=v1,v2,...`` into a :class:`GridAxis`."""
    name, rest = _split(item, "`grid`")
    return _grid_from_text(name, rest, dimensions, "`grid`")


def parse_range(item: str, dimensions: Dimensions | None = None) -> SampledRange:
    """Parse ``name=lo:hi[:log]`` into a :class:`SampledRange`."""
    name, rest = _split(item, "`ranges`")
    return _range_from_text(name, rest, dimensions, "`ranges`")


def _range_from_text(name: str, rest: str, dimensions: Dimensions | None, flag: str) -> SampledRange:
    parts = [p.strip() for p in rest.split(":")]
    log = parts[-1].lower() in ("log", "lin") and parts.pop().lower() == "log"
    if len(parts) != 2:
        raise ParameterError(f"{flag} expects name=lo:hi[:log], got {name}={rest}")
    lo, hi = (_value(name, p, dimensions, flag) for p in parts)
    if isinstance(lo, str) or isinstance(hi, str):
        raise ParameterError(f"{flag} {name}: needs numeric bounds")
    return SampledRange(name, lo, hi, log)


def parse_setting(item: str, dimensions: Dimensions | None = None) -> tuple[str, Any]:
    """Parse ``name=value`` into ``(name, SI value)``."""
    name, rest = _split(item, "`sets`")
    return name, _value(name, rest, dimensions, "`sets`")


def _from_toml(path: Path, dimensions: Dimensions | None) -> dict:
    """Read a sweep file: ``[sweep]`` options, ``[grid]``, ``[range]``, ``[set]`` tables."""
    try:
        data = tomllib.loads(read_settings(path, "a TOML sweep file"))
    except FileNotFoundError:
        raise ParameterError(f"`config` {path}: no such file") from None
    except IsADirectoryError:
        raise ParameterError(f"`config` {path} is a folder; give a .toml sweep file") from None
    except UnicodeDecodeError:
        raise ParameterError(f"`config` {path}: not a UTF-8 text file (TOML sweep file expected; "
                             "save it as UTF-8)") from None
    except OSError as exc:
        raise ParameterError(f"`config` {path}: cannot read ({exc.strerror or exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"`config` {path}: not valid TOML ({exc})") from None
    unknown = set(data) - {"sweep", "grid", "range", "set"}
    if unknown:
        raise ParameterError(f"`config` {path}: unknown table(s) {sorted(unknown)}; "
                             "use [sweep], [grid], [range], [set]")
    for table in ("sweep", "grid", "range", "set"):
        if not isinstance(data.get(table, {}), dict):
            raise ParameterError(f"`config` {path}: {table} must be a table ([{table}]), got {data[table]!r}")
    out: dict[str, Any] = _sweep_options(path, data.get("sweep", {}))
    at = f"`config` {path}:"      # every message names the file and the key written there
    grid = []
    for name, v in data.get("grid", {}).items():
        if isinstance(v, list):
            grid.append(GridAxis(name, tuple(_value(name, x, dimensions, f"{at} [grid]") for x in v)))
        elif isinstance(v, dict):
            lo, hi, n, log = _bounds(path, "grid", name, v, dimensions)
            grid.append(GridAxis.spaced(name, lo, hi, n, log))
        else:
            grid.append(_grid_from_text(name, str(v), dimensions, f"{at} [grid]"))
    ranges = []
    for name, v in data.get("range", {}).items():
        if isinstance(v, dict):
            lo, hi, _, log = _bounds(path, "range", name, v, dimensions)
            ranges.append(SampledRange(name, lo, hi, log))
        else:
            ranges.append(_range_from_text(name, str(v), dimensions, f"{at} [range]"))
    fixed = [(k, _value(k, v, dimensions, f"{at} [set]")) for k, v in data.get("set", {}).items()]
    out["origins"] = {name: f"{at} [{table}] {name}" for table in ("grid", "range", "set")
                      for name in data.get(table, {})}
    out.update(grid=grid, ranges=ranges, fixed=fixed)
    return out


#: The options of a sweep file's ``[sweep]`` table: name -> (whole number?, what it is).
_SWEEP_OPTIONS = {"sample": (False, "the sampler, 'random' or 'lhs'"), "n": (True, "the number of samples"),
                  "seed": (True, "the sampler's seed"), "chunk_size": (True, "runs per chunk")}


def _sweep_options(path: Path, table: dict) -> dict[str, Any]:
    """The ``[sweep]`` table checked: whole numbers (TOML integers, not 1e400 or "4") and a sampler."""
    unknown = set(table) - set(_SWEEP_OPTIONS)
    if unknown:
        raise ParameterError(f"`config` {path}: unknown [sweep] option(s) {sorted(unknown)}; "
                             f"use {', '.join(_SWEEP_OPTIONS)}")
    for name, value in table.items():
        whole, what = _SWEEP_OPTIONS[name]
        if whole and (isinstance(value, bool) or not isinstance(value, int) or value < 0):
            raise ParameterError(f"`config` {path}: [sweep] {name} ({what}) must be a whole number "
                                 f">= 0, got {value!r}")
        if not whole and value not in ("random", "lhs"):
            raise ParameterError(f"`config` {path}: [sweep] {name} must be {what}, got {value!r}")
    return dict(table)


def _bounds(path: Path, table: str, name: str, v: dict, dimensions: Dimensions | None):
    """``(lo, hi, n, log)`` of an inline table ``name = { lo = ..., hi = ..., n = ..., log = ... }``."""
    keys = {"lo", "hi", "log"} | ({"n"} if table == "grid" else set())
    form = "{ lo = ..., hi = ...%s, log = true }" % (", n = ..." if table == "grid" else "")
    if set(v) - keys or not {"lo", "hi"} <= set(v):
        raise ParameterError(f"`config` {path}: [{table}] {name} must be a table {form}, got keys "
                             f"{sorted(v)}")
    lo, hi = (_value(f"{name}.{k}", v[k], dimensions, f"`config` {path}: [{table}]", key=name) for k in ("lo", "hi"))
    if isinstance(lo, str) or isinstance(hi, str):
        raise ParameterError(f"`config` {path}: [{table}] {name}: lo and hi must be numbers")
    n, log = v.get("n", 1), v.get("log", False)
    if isinstance(n, bool) or not isinstance(n, int):
        raise ParameterError(f"`config` {path}: [{table}] {name}: n must be a whole number, got {n!r}")
    if not isinstance(log, bool):
        raise ParameterError(f"`config` {path}: [{table}] {name}: log must be true or false, got {log!r}")
    return lo, hi, n, log


def _merge(first: list, second: list, key: Callable) -> list:
    """Entries of ``second`` replace those of ``first`` with the same name."""
    names = {key(x) for x in second}
    return [x for x in first if key(x) not in names] + list(second)


def build_spec(
    grid: list[str] = (),
    ranges: list[str] = (),
    sets: list[str] = (),
    *,
    sample: str | None = None,
    n: int | None = None,
    seed: int | None = None,
    config: str | Path | None = None,
    dimensions: Dimensions | None = None,
) -> SweepSpec:
    """Build a :class:`SweepSpec` from text forms and an optional TOML file.

    Flags given here add to the file's entries and replace those of the same name.
    """
    base: dict[str, Any] = _from_toml(config, dimensions) if config else {}
    unknown = set(base) - {"grid", "ranges", "fixed", "sample", "n", "seed", "chunk_size", "origins"}
    if unknown:
        raise ParameterError(f"`config` {config}: unknown [sweep] option(s) {sorted(unknown)}")
    axes = _merge(base.get("grid", []), [parse_grid(g, dimensions) for g in grid], lambda a: a.name)
    rngs = _merge(base.get("ranges", []), [parse_range(r, dimensions) for r in ranges], lambda r: r.name)
    fixed = _merge(base.get("fixed", []), [parse_setting(s, dimensions) for s in sets], lambda f: f[0])
    typed = {_split(t, "")[0] for t in (*grid, *ranges, *sets)}     # a flag's entry replaces the file's
    origins = {k: v for k, v in base.get("origins", {}).items() if k not in typed}
    sample = sample if sample is not None else base.get("sample")
    if rngs and sample is None:
        sample = "lhs"
    return SweepSpec(
        grid=tuple(axes),
        ranges=tuple(rngs),
        sample=sample,
        n=int(n if n is not None else base.get("n", 0)),
        seed=int(seed if seed is not None else base.get("seed", 0)),
        fixed=tuple(fixed),
        origins=origins,
    )


def chunk_size_from_config(config: str | Path | None) -> int | None:
    """The ``[sweep] chunk_size`` of a TOML sweep file, if any."""
    if not config:
        return None
    try:
        table = tomllib.loads(read_settings(config, "a TOML sweep file")).get("sweep", {})
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, FileFormatError):
        return None  # build_spec reports unreadable files
    value = _sweep_options(Path(config), table if isinstance(table, dict) else {}).get("chunk_size")
    if value is not None and value < 1:
        raise ParameterError(f"`config` {config}: [sweep] chunk_size must be at least 1, got {value}")
    return value
