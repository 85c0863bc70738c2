"""Registry of the surface force laws added to the paper's eq 2 (issue 31, item 2).

One module per law in this package, each defining ``LAW``, a :class:`SurfaceLaw`: its pure
vectorised force (and dF/dh), its parameters (keys of :data:`afmforce._fields.QUANTITIES`),
its compiled kernel ``(h, p, o)``, its reference and validity. The registry imports every
module of the package (sorted by name: no list to edit) and assigns each law its slots in the
laws block of the packed parameter vector: slot 0 of the block says whether any law acts (the
paper's runs test that one slot only), slot ``SLOTS[name]`` is the law's switch (1.0: on), the
next ``law.n_slots`` are what ``law.pack`` returns. Everything else comes from these
records: the configuration's fields (``dynamics.parts.Surface``), the compiled vector field and
its Jacobian (``dynamics.models``), the non-compiled reference (``dynamics.reference``), the
static solve, ``afmforce simulate``'s flags and the fit's free parameters (``fit.params``).

Add a law: write ``surface_laws/<name>.py`` with ``LAW = SurfaceLaw(...)`` and its
parameters' lines in ``QUANTITIES`` (docs/architecture.md, "Surface force laws").
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Mapping

import numpy as np

from ..errors import ParameterError
from ._record import LawParameter, SurfaceLaw

__all__ = ["LAWS", "SLOTS", "N_SLOTS", "PARAMETERS", "LawParameter", "SurfaceLaw", "law",
           "active_laws", "pack", "total_force", "reach"]


def _discover() -> dict[str, SurfaceLaw]:
    out = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        record = getattr(module, "LAW", None)
        if not isinstance(record, SurfaceLaw):
            raise TypeError(f"{module.__name__} defines no LAW = SurfaceLaw(...)")
        if record.name != info.name:
            raise TypeError(f"{module.__name__}: LAW.name must be the module's name {info.name!r}")
        out[record.name] = record
    return out


#: Law name -> record, in the order of their slots.
LAWS: dict[str, SurfaceLaw] = _discover()


def _slots() -> tuple[dict[str, int], int]:
    slots, n = {}, 1                    # slot 0: any law on
    for name, rec in LAWS.items():
        slots[name] = n
        n += 1 + rec.n_slots
    return slots, n


#: Law name -> offset of its switch in the laws block (its parameters follow; offset 0 is the
#: block's "any law on"); the block's size.
SLOTS, N_SLOTS = _slots()


def _parameters() -> dict[str, LawParameter]:
    out: dict[str, LawParameter] = {}
    for rec in LAWS.values():
        for p in rec.parameters:
            known = out.setdefault(p.name, p)
            if known.default != p.default or known.domain != p.domain:
                raise TypeError(f"parameter {p.name} is declared twice with different defaults")
    return out


#: Parameter name -> record (a name shared by two laws, e.g. temperature, appears once).
PARAMETERS: dict[str, LawParameter] = _parameters()


def law(name: str) -> SurfaceLaw:
    """The record of law ``name``."""
    try:
        return LAWS[name]
    except KeyError:
        raise ParameterError(f"unknown surface force law {name!r}; known: {', '.join(LAWS)}") from None


def _of(values: Mapping[str, float], rec: SurfaceLaw) -> dict[str, float]:
    return {p.name: float(values.get(p.name, p.default)) for p in rec.parameters}


def active_laws(values: Mapping[str, float]) -> tuple[str, ...]:
    """Names of the laws that act with these parameter values (missing: the defaults)."""
    return tuple(n for n, rec in LAWS.items() if rec.active(_of(values, rec)))


def pack(values: Mapping[str, float], radius_eff: float) -> np.ndarray:
    """The laws block of the packed parameter vector (``N_SLOTS`` floats; zeros: no law on)."""
    out = np.zeros(N_SLOTS)
    for name, rec in LAWS.items():
        v = _of(values, rec)
        if rec.active(v):
            o = SLOTS[name]
            out[0] = out[o] = 1.0
            out[o + 1:o + 1 + rec.n_slots] = rec.pack(radius_eff, v)
    return out


def total_force(h, radius_eff: float, values: Mapping[str, float]):
    """(F [N], dF/dh [N/m]) of every active law, summed; zeros when none acts."""
    h = np.asarray(h, dtype=float)
    f, df = np.zeros_like(h), np.zeros_like(h)
    for rec in LAWS.values():
        v = _of(values, rec)
        if rec.active(v):
            a, b = rec.force(h, radius_eff, v)
            f, df = f + a, df + b
    return f, df


def reach(values: Mapping[str, float]) -> float:
    """The largest separation at which an active law still acts [m] (0 when none)."""
    return max((rec.reach(_of(values, rec)) for rec in LAWS.values()
                if rec.active(_of(values, rec))), default=0.0)
