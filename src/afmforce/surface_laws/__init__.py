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

The laws the model computes itself, the paper's eq 2 (``van_der_waals``) and the double layer of
issue 25 (``double_layer``), are records of the registry too, without a kernel
(:attr:`SurfaceLaw.compiled` False; :data:`COMPILED` holds the others): their parameters are the
configuration's own fields, whose defaults and domains (``dynamics.parts.Surface``), flags
(``afmforce simulate``), fit scales (``fit.params``) and docs (:func:`laws_markdown`) come from
these records.

Add a law: write ``surface_laws/<name>.py`` with ``LAW = SurfaceLaw(...)`` and its
parameters' lines in ``QUANTITIES`` (docs/architecture.md, "Surface force laws").
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Mapping

import numpy as np

from ..errors import ParameterError
from ._record import LawParameter, LawSwitch, SurfaceLaw

__all__ = ["LAWS", "COMPILED", "SLOTS", "N_SLOTS", "PARAMETERS", "MODEL_PARAMETERS", "LawParameter",
           "LawSwitch", "SurfaceLaw", "law", "active_laws", "pack", "total_force", "reach", "laws_markdown"]


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
    return dict(sorted(out.items(), key=lambda item: item[1].compiled))   # the model's laws first


#: Law name -> record: the model's own laws (eq 2, the double layer), then the others in the
#: order of their slots.
LAWS: dict[str, SurfaceLaw] = _discover()
#: The laws with a kernel of their own (name -> record), in the order of their slots.
COMPILED: dict[str, SurfaceLaw] = {n: r for n, r in LAWS.items() if r.compiled}


def _slots() -> tuple[dict[str, int], int]:
    slots, n = {}, 1                    # slot 0: any law on
    for name, rec in COMPILED.items():
        slots[name] = n
        n += 1 + rec.n_slots
    return slots, n


#: Law name -> offset of its switch in the laws block (its parameters follow; offset 0 is the
#: block's "any law on"); the block's size.
SLOTS, N_SLOTS = _slots()


def _parameters(laws) -> dict[str, LawParameter]:
    out: dict[str, LawParameter] = {}
    for rec in laws:
        for p in rec.parameters:
            known = out.setdefault(p.name, p)
            if known.default != p.default or known.domain != p.domain:
                raise TypeError(f"parameter {p.name} is declared twice with different defaults")
    return out


#: Parameter name -> record of the compiled laws (a name shared by two laws, e.g. temperature,
#: appears once): the configuration's fields made from the records.
PARAMETERS: dict[str, LawParameter] = _parameters(COMPILED.values())
#: Parameter name -> record of the model's own laws (eq 2, the double layer): the configuration
#: declares these fields itself and takes their defaults and domains from here.
MODEL_PARAMETERS: dict[str, LawParameter] = _parameters(r for r in LAWS.values() if not r.compiled)
if set(PARAMETERS) & set(MODEL_PARAMETERS):
    raise TypeError(f"parameters of a compiled law and of the model: {set(PARAMETERS) & set(MODEL_PARAMETERS)}")


def law(name: str) -> SurfaceLaw:
    """The record of law ``name``."""
    try:
        return LAWS[name]
    except KeyError:
        raise ParameterError(f"unknown surface force law {name!r}; known: {', '.join(LAWS)}") from None


def _of(values: Mapping[str, float], rec: SurfaceLaw) -> dict[str, float]:
    return {p.name: float(values.get(p.name, p.default)) for p in rec.parameters}


def active_laws(values: Mapping[str, float]) -> tuple[str, ...]:
    """Names of the compiled laws that act with these parameter values (missing: the defaults)."""
    return tuple(n for n, rec in COMPILED.items() if rec.active(_of(values, rec)))


def pack(values: Mapping[str, float], radius_eff: float) -> np.ndarray:
    """The laws block of the packed parameter vector (``N_SLOTS`` floats; zeros: no law on)."""
    out = np.zeros(N_SLOTS)
    for name, rec in COMPILED.items():
        v = _of(values, rec)
        if rec.active(v):
            o = SLOTS[name]
            out[0] = out[o] = 1.0
            out[o + 1:o + 1 + rec.n_slots] = rec.pack(radius_eff, v)
    return out


def total_force(h, radius_eff: float, values: Mapping[str, float]):
    """(F [N], dF/dh [N/m]) of every active compiled law, summed; zeros when none acts (eq 2 and
    the double layer are the model's: its callers add them)."""
    h = np.asarray(h, dtype=float)
    f, df = np.zeros_like(h), np.zeros_like(h)
    for rec in COMPILED.values():
        v = _of(values, rec)
        if rec.active(v):
            a, b = rec.force(h, radius_eff, v)
            f, df = f + a, df + b
    return f, df


def reach(values: Mapping[str, float]) -> float:
    """The largest separation at which an active compiled law still acts [m] (0 when none)."""
    return max((rec.reach(_of(values, rec)) for rec in COMPILED.values()
                if rec.active(_of(values, rec))), default=0.0)


def laws_markdown() -> str:
    """The docs' table of the surface force laws (docs/dynamics.md), made from the records: each
    law's name, what it is and where it holds, its parameters with their flags' units, defaults
    and ranges (``QUANTITIES``; *fit*: a free parameter of ``afmforce fit --free``), reference."""
    from .._fields import QUANTITIES

    lines = ["| law | what (valid) | parameters: default, range | reference |", "|---|---|---|---|"]
    for name, rec in LAWS.items():
        parts = []
        if rec.switch is not None:
            sw = rec.switch
            parts.append(f"`{sw.name}`: {', '.join(sw.choices)} (default {sw.default}; {sw.off}: off)")
        for p in rec.parameters:
            spec = QUANTITIES[p.name]
            parts.append(f"`{p.name}` [{spec.unit or '-'}]: {spec.show(p.default)}, {spec.range_text()}"
                         + ("; *fit*" if p.fit else ""))
        where = "" if rec.compiled else " (computed by the model itself)"
        cells = (f"`{name}`", f"{rec.title}{where}. Valid: {rec.validity}", "<br>".join(parts), rec.reference)
        lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(lines)
