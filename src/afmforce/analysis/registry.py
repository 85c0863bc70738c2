"""The registry of analysis steps: one record per step, declared in the step's own module.

An :class:`AnalysisStep` says everything about a step once: its identifier and name, the
function ``func(state, options) -> state``, its options record (a
:class:`~.options.StepOptions` subclass), the steps it requires, the steps it runs after when
they run, the state channels it needs, its reference, and its result fields
(:class:`ResultField`: name, SI unit, label, whether it is a row of the printed summary, a
column of the batch summary table, a map quantity) with ``collect(state) -> {field: value}``
that reads them off the step's details. Everything else is derived from these records: the
pipeline's order (:func:`order`), the fields and units of
:class:`~.result.AnalysisResult` (``UNITS``, ``SUMMARY_FIELDS``), the columns of the batch
summary (:data:`afmforce.sweep.summary.SUMMARY_COLUMNS`), the map quantities
(:data:`afmforce.analysis.maps.MAP_QUANTITIES`), the choices of ``afmforce analyze --steps``
and the web's step list.

Add a step: write one module that defines its options record (a ``StepOptions`` subclass:
:data:`~.options.OPTIONS` registers it), its function and its ``AnalysisStep`` record
(docs/architecture.md, "Analysis steps"): in :mod:`afmforce.analysis.steps` (one module per step;
on first use the registry imports every module there, those of :data:`BUILTIN_MODULES` first, in
that order, and registers the records they define), or anywhere else, calling
:func:`register_step` with the record.

This module imports nothing heavy.
"""

from __future__ import annotations

import importlib
import math
import pkgutil
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator

from ..errors import ParameterError

__all__ = ["ResultField", "AnalysisStep", "register_step", "unregister_step", "steps", "order",
           "result_fields", "BUILTIN_MODULES", "LiveDict", "LiveTuple"]


@dataclass(frozen=True)
class ResultField:
    """One field of :class:`~.result.AnalysisResult` that a step fills.

    Attributes
    ----------
    name : str
        Attribute and JSON key.
    unit : str
        SI unit (``""`` for plain numbers); ``None``: a word or a flag (no unit, not in ``UNITS``).
    label : str
        Human-readable name (the printed summary, the map's title).
    default : Any
        Its value when the step did not run or found nothing (NaN for numbers).
    summary : bool
        A row of the printed summary (:data:`~.result.SUMMARY_FIELDS`).
    column : bool
        A float column of the batch summary table.
    map : bool or None
        A map quantity (:data:`afmforce.analysis.maps.MAP_QUANTITIES`; maps are drawn from the
        summary table's columns); None: when both ``summary`` and ``column``.
    compute : callable, optional
        ``compute(result) -> value`` for a field computed from other fields (not stored).
    bound : str, optional
        The field holding this one's bound (a half-width, same unit): this field NaN with that one finite
        means the data left it undetermined (:func:`afmforce.analysis.plausibility.undetermined`); the
        table's cell says so with the bound.
    """

    name: str
    unit: str | None = ""
    label: str = ""
    default: Any = math.nan
    summary: bool = False
    column: bool = False
    map: bool | None = None
    compute: Callable[[Any], Any] | None = field(default=None, compare=False)
    bound: str | None = None


    @property
    def mapped(self) -> bool:
        """A map quantity (see :attr:`map`)."""
        return (self.summary and self.column) if self.map is None else (self.map and self.column)


@dataclass(frozen=True)
class AnalysisStep:
    """One analysis step, declared once (see the module's doc).

    Attributes
    ----------
    identifier : str
        Name used in ``steps=``, ``--steps`` and ``state.details``.
    name : str
        Human-readable name.
    func : callable
        ``func(state, options) -> state``; ``options`` an instance of :attr:`options`.
    options : type
        The step's options record (its field defaults are the step's defaults).
    requires : tuple of str
        Steps that must run before (added when this one is asked for).
    after : tuple of str
        Steps this one runs after when they run (not added: e.g. the smoothing of the position).
    channels : tuple of str
        State arrays it needs (``deflection``, ``separation``, ...), checked before it runs.
    reference : str
        Where the method comes from.
    fields : tuple of ResultField
        The result fields it fills.
    collect : callable, optional
        ``collect(state) -> {field: value}``, called when the step left its details.
    runs : tuple of str
        The runs (``"approach"``, ``"retract"``) it reads. On a curve of one run (an export of the
        retract or of the approach alone) a step that needs the missing run is skipped, reported
        ``"not available: no approach run"`` (docs/analysis.md, "Curves of one run"); ``()``: it
        works on whichever run the curve has.
    """

    identifier: str
    name: str
    func: Callable[[Any, Any], Any]
    options: type
    requires: tuple[str, ...] = ()
    after: tuple[str, ...] = ()
    channels: tuple[str, ...] = ()
    reference: str = ""
    fields: tuple[ResultField, ...] = ()
    collect: Callable[[Any], Mapping[str, Any]] | None = field(default=None, compare=False)
    runs: tuple[str, ...] = ("approach", "retract")

    def run(self, state, options):
        """The step on ``state`` (AnalysisError naming a missing channel first)."""
        if self.channels:
            state.require(*self.channels, step=self.identifier)
        return self.func(state, options)


#: The order of the built-in steps: their modules in :mod:`afmforce.analysis.steps`, imported on first
#: use in this order (which breaks the ties of :func:`order`); any other module of that package is
#: imported after them (sorted by name), so a new step needs no edit here.
BUILTIN_MODULES = ("smooth", "contact", "drift", "fringes", "compliance", "calibration", "kind", "shift", "zero",
                   "force", "jumps", "adhesion", "surface_energy", "vdw", "oscillation", "friction", "indentation",
                   "diagnosis", "liquid")

_STEPS: dict[str, AnalysisStep] = {}
_ORDER: list[str] = []
_STATE = {"version": 0, "loading": False, "loaded": False}
_CACHE: dict[str, tuple[int, Any]] = {}


#: Held while the step modules are imported: reentrant (a step module may read the registry while
#: it is imported, in the same thread), and another thread (the web server's warm-up and a request)
#: waits for the whole registry instead of reading a half-loaded one.
_LOCK = threading.RLock()


def _load() -> None:
    if _STATE["loaded"]:
        return
    with _LOCK:
        if _STATE["loaded"] or _STATE["loading"]:
            return
        _load_locked()


def _load_locked() -> None:
    _STATE["loading"] = True
    try:
        package = importlib.import_module(f"{__package__}.steps")
        found = sorted(m.name for m in pkgutil.iter_modules(package.__path__) if not m.name.startswith("_"))
        for name in (*BUILTIN_MODULES, *(n for n in found if n not in BUILTIN_MODULES)):
            module = importlib.import_module(f"{package.__name__}.{name}")
            records = [r for r in vars(module).values() if isinstance(r, AnalysisStep)]
            if not records:
                raise TypeError(f"{module.__name__} defines no AnalysisStep record")
            for rec in records:
                if _STEPS.get(rec.identifier) is not rec:
                    _add(rec)
        _STATE["loaded"] = True
    finally:
        _STATE["loading"] = False


def version() -> int:
    """Changes whenever a step is registered or removed (derived tables rebuild then)."""
    _load()
    return _STATE["version"]


def register_step(step: AnalysisStep) -> AnalysisStep:
    """Add ``step`` to the registry (the public way to add a step; returns it).

    Raises
    ------
    TypeError
        A step of that identifier exists, a required step is not registered, the options
        record names another step, or a result field is declared by another step.
    """
    if not isinstance(step, AnalysisStep):
        raise TypeError(f"register_step expects an AnalysisStep, got {step!r}")
    _load()
    return _add(step)


def _add(step: AnalysisStep) -> AnalysisStep:
    if step.identifier in _STEPS:
        raise TypeError(f"analysis step {step.identifier!r} is registered already")
    missing = [r for r in step.requires if r not in _STEPS]
    if missing:
        raise TypeError(f"step {step.identifier!r} requires unregistered step(s) {', '.join(missing)}")
    if getattr(step.options, "step", None) != step.identifier:
        raise TypeError(f"step {step.identifier!r}: its options record {step.options.__name__} is for step "
                        f"{getattr(step.options, 'step', None)!r}")
    taken = {f.name: s.identifier for s in _STEPS.values() for f in s.fields}
    for f in step.fields:
        if f.name in taken:
            raise TypeError(f"step {step.identifier!r}: result field {f.name!r} is declared by step "
                            f"{taken[f.name]!r}")
    order = _sorted({**_STEPS, step.identifier: step})   # a cycle refuses the step, the registry unchanged
    _STEPS[step.identifier] = step
    _ORDER[:] = order
    _STATE["version"] += 1
    return step


def unregister_step(identifier: str) -> None:
    """Remove a step added with :func:`register_step` (no step may require it)."""
    _load()
    users = [s.identifier for s in _STEPS.values() if identifier in s.requires]
    if users:
        raise TypeError(f"step {identifier!r} is required by {', '.join(users)}")
    del _STEPS[identifier]
    _ORDER[:] = _sorted(_STEPS)
    _STATE["version"] += 1


def _sorted(steps: dict[str, AnalysisStep]) -> list[str]:
    """Registration order, each step moved after its requirements and the ``after`` steps present."""
    done: list[str] = []
    left = list(steps)
    while left:
        for n in left:
            s = steps[n]
            if all(r in done or r not in steps for r in (*s.requires, *s.after)):
                done.append(n)
                left.remove(n)
                break
        else:
            raise TypeError(f"analysis steps {', '.join(left)} require each other in a cycle")
    return done


def steps() -> dict[str, AnalysisStep]:
    """Identifier -> record, in the pipeline's order (one dict per state of the registry: read it, do not
    change it)."""
    return _cached("steps", lambda: {n: _STEPS[n] for n in _ORDER})


def _cached(key: str, build: Callable[[], Any]) -> Any:
    """``build()``, computed once per state of the registry (results read per curve and per field)."""
    v = version()
    hit = _CACHE.get(key)
    if hit is None or hit[0] != v:
        hit = _CACHE[key] = (v, build())
    return hit[1]


def order() -> tuple[str, ...]:
    """Step identifiers in the order the pipeline runs them."""
    _load()
    return tuple(_ORDER)


def step(identifier: str) -> AnalysisStep:
    """The record of ``identifier`` (ParameterError listing the steps otherwise)."""
    _load()
    try:
        return _STEPS[identifier]
    except KeyError:
        raise ParameterError(f"unknown analysis step {identifier!r}; choose from {', '.join(_ORDER)}") from None


def result_fields() -> dict[str, ResultField]:
    """Every step's result fields, name -> record, in the pipeline's order (one dict per state of the
    registry: read it, do not change it)."""
    return _cached("fields", lambda: {f.name: f for n in _ORDER for f in _STEPS[n].fields})


class LiveDict(dict):
    """A dict rebuilt by ``builder()`` whenever the registry changed (a plain dict to its readers:
    ``json.dumps``, ``dict(...)``, pandas)."""

    def __init__(self, builder: Callable[[], Mapping]) -> None:
        super().__init__()
        self._builder = builder
        self._version = -1

    def _fresh(self) -> "LiveDict":
        v = version()
        if v != self._version:
            data = dict(self._builder())
            dict.clear(self)
            dict.update(self, data)
            self._version = v
        return self

    def __getitem__(self, key):
        return dict.__getitem__(self._fresh(), key)

    def __iter__(self) -> Iterator:
        return dict.__iter__(self._fresh())

    def __len__(self) -> int:
        return dict.__len__(self._fresh())

    def __contains__(self, key) -> bool:
        return dict.__contains__(self._fresh(), key)

    def __repr__(self) -> str:
        return dict.__repr__(self._fresh())

    def __eq__(self, other) -> bool:
        return dict.__eq__(self._fresh(), other)

    __hash__ = None  # type: ignore[assignment]

    def get(self, key, default=None):
        return dict.get(self._fresh(), key, default)

    def keys(self):
        return dict.keys(self._fresh())

    def values(self):
        return dict.values(self._fresh())

    def items(self):
        return dict.items(self._fresh())

    def copy(self) -> dict:
        return dict(dict.items(self._fresh()))

    def __reduce__(self):
        return (dict, (self.copy(),))


class LiveTuple(Sequence):
    """A tuple rebuilt by ``builder()`` whenever the registry changed."""

    def __init__(self, builder: Callable[[], Sequence]) -> None:
        self._builder = builder
        self._version = -1
        self._data: tuple = ()

    def _fresh(self) -> tuple:
        v = version()
        if v != self._version:
            self._data = tuple(self._builder())
            self._version = v
        return self._data

    def __getitem__(self, i):
        return self._fresh()[i]

    def __len__(self) -> int:
        return len(self._fresh())

    def __iter__(self):
        return iter(self._fresh())

    def __repr__(self) -> str:
        return repr(self._fresh())

    def __eq__(self, other) -> bool:
        return self._fresh() == (tuple(other) if isinstance(other, (list, LiveTuple)) else other)

    __hash__ = None  # type: ignore[assignment]
