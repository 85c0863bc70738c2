"""Validation machinery of the configuration parts (:mod:`afmforce.dynamics.parts`).

A part field declares its quantity's metadata (:data:`afmforce._fields.QUANTITIES`:
dimension, SI unit, help, valid range) and the ``domain`` the model itself
needs, once (:func:`quantity`); :func:`validate` checks every field of a part
against it: first the declared valid range (the message of
:meth:`afmforce._fields.FieldSpec.check`, the same the command line and the web give),
then the domain, with the one message style of :mod:`afmforce._validate`.
"""

from __future__ import annotations

import dataclasses
import threading
from functools import cache
from typing import Any

from .._fields import qfield
from .._validate import finite, non_negative, positive
from ..errors import ParameterError

__all__ = ["DOMAINS", "Part", "choice", "quantity", "validate"]


def quantity(name: str, default: Any, domain: str) -> Any:
    """A numeric part field: :func:`afmforce._fields.qfield`'s metadata of
    ``QUANTITIES[name]`` (dimension, unit, help, range) plus the model's ``domain``."""
    return dataclasses.field(default=default, metadata={**qfield(name).metadata, "domain": domain})


def choice(default: str, registry: dict, help: str, name: str | None = None) -> Any:
    """A text part field naming an entry of ``registry`` (``name``: its flat name in messages)."""
    return dataclasses.field(default=default, metadata={"choices": registry, "help": help, "name": name})


def _count(name: str, value, unit: str):
    if value is None:
        return None
    try:
        whole = not isinstance(value, bool) and float(value).is_integer() and value >= 1
    except (TypeError, ValueError):
        whole = False
    if not whole:
        raise ParameterError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _optional(check):
    return lambda name, value, unit: None if value is None else check(name, value, unit)


#: Domain -> check(name, value, unit) returning the value as stored (float) or raising.
DOMAINS = {
    "positive": positive,
    "non_negative": non_negative,
    "finite": finite,
    "optional_positive": _optional(positive),
    "optional_finite": _optional(finite),
    "count": _count,
}


def _checker(f: dataclasses.Field, domain_too: bool = True):
    """check(value) of one field: its registry, or its spec's valid range (the message of
    :meth:`afmforce._fields.FieldSpec.check`, the same the command line gives) and then the
    model's domain (``domain_too``)."""
    name, md = f.name, f.metadata
    if "choices" in md:
        choices, name = md["choices"], md["name"] or name

        def check_choice(value):
            if value not in choices:
                raise ParameterError(f"{name} must be one of {sorted(choices)}, got {value!r}")
            return value
        return check_choice
    unit, domain, spec = md["unit"], md["domain"], md["spec"]
    if domain == "range":
        return lambda value: spec.check(finite(name, value, unit), name)
    check = DOMAINS[domain]
    if not domain_too:
        return lambda value: spec.check(value, name)
    return lambda value: check(name, spec.check(value, name), unit)


@cache
def _checks(cls, skip: tuple[str, ...]) -> tuple:
    """(name, check) of every field of part class ``cls`` checked on construction
    (``skip``: fields whose domain another check owns; their range is still checked here)."""
    return tuple((f.name, _checker(f, f.name not in skip)) for f in dataclasses.fields(cls)
                 if "domain" in f.metadata or "choices" in f.metadata)


@cache
def _field_order(cls) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls))


@cache
def _names(cls) -> frozenset[str]:
    return frozenset(f.name for f in dataclasses.fields(cls))


#: The part :meth:`Part.replace` copies (per thread): its fields passed the same checks.
_SOURCE = threading.local()
_MISSING = object()


def validate(part, skip: tuple[str, ...] = ()) -> None:
    """Check every field of ``part`` against its declared domain or registry; store floats.

    A field holding the very object the part being replaced holds there (:meth:`Part.replace`)
    passed the same check already and is not checked again (a check depends on the field and
    its value only; a fit or ``simulate(**flat)`` changes a few fields of a part: issue 35)."""
    d = part.__dict__
    src = getattr(_SOURCE, "part", None)
    known = src.__dict__ if src is not None and type(src) is type(part) else {}
    for name, check in _checks(type(part), skip):
        value = d[name]
        if known.get(name, _MISSING) is value:
            continue
        checked = check(value)
        if checked is not value:
            object.__setattr__(part, name, checked)


class Part:
    """Shared behaviour of the parts: ``replace`` and the plain field dict."""

    def replace(self, **changes):
        """A copy with some fields changed (validated again)."""
        known = _names(type(self))
        if not known.issuperset(changes):
            raise ParameterError(f"{type(self).__name__} has no field(s) {sorted(set(changes) - known)}; "
                                 f"known: {', '.join(sorted(known))}")
        cls = type(self)
        before = getattr(_SOURCE, "part", None)
        _SOURCE.part = self
        try:
            # what the dataclass __init__ does with every field given, without its keyword
            # call (a few us of a fit step, issue 35.5), then the same __post_init__
            new = object.__new__(cls)
            d = new.__dict__
            d.update(self.to_dict())
            d.update(changes)
            new.__post_init__()
            return new
        finally:
            _SOURCE.part = before

    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (SI values)."""
        d = self.__dict__
        return {n: d[n] for n in _field_order(type(self))}
