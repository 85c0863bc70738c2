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
import math
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
        slow = lambda value: spec.check(finite(name, value, unit), name)  # noqa: E731
    elif not domain_too:
        slow = lambda value: spec.check(value, name)  # noqa: E731
    else:
        check = DOMAINS[domain]
        slow = lambda value: check(name, spec.check(value, name), unit)  # noqa: E731
    return _fast(slow, spec, domain if domain_too else "any")


#: Domain -> (lower bound, bound open) a finite float must meet for it (``count``: none).
_FAST_DOMAINS = {"positive": (0.0, True), "optional_positive": (0.0, True),
                 "non_negative": (0.0, False), "finite": None, "optional_finite": None,
                 "range": None, "any": None}


def _fast(slow, spec, domain):
    """``slow`` (a field's check) with a fast path for a finite Python float inside the
    spec's range and the domain's bound: the value ``slow`` returns for it (the object itself:
    ``float(v) is v``), without its calls (~1 us a field of ``simulate(**flat)``, issue 35.5).
    Anything else (None, an int, a numpy scalar, a value out of range) takes ``slow``."""
    if domain not in _FAST_DOMAINS:
        return slow
    lo, lo_open, hi, hi_open = spec.lo, spec.lo_open, spec.hi, spec.hi_open
    bound = _FAST_DOMAINS[domain]
    if bound is not None:           # the domain's bound and the spec's lower bound, both met
        if lo is None or bound[0] > lo or (bound[0] == lo and bound[1]):
            lo, lo_open = bound
    lo = -math.inf if lo is None else float(lo)
    hi = math.inf if hi is None else float(hi)

    def check(value):
        if (type(value) is float and -math.inf < value < math.inf
                and (value > lo or (value == lo and not lo_open))
                and (value < hi or (value == hi and not hi_open))):
            return value
        return slow(value)
    return check


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


#: (the part :meth:`Part.replace` copies, the changes) per thread: the fields it copies
#: passed the same checks.
_SOURCE = threading.local()


def validate(part, skip: tuple[str, ...] = ()) -> None:
    """Check every field of ``part`` against its declared domain or registry; store floats.

    A field holding the very object the part being replaced holds there (:meth:`Part.replace`)
    passed the same check already and is not checked again (a check depends on the field and
    its value only; a fit or ``simulate(**flat)`` changes a few fields of a part: issue 35):
    in a replace only the changed fields are looked at."""
    d = part.__dict__
    src = getattr(_SOURCE, "src", None)
    if src is not None and type(src[0]) is type(part):
        known = src[0].__dict__
        checks = _check_map(type(part), skip)
        for name in src[1]:
            check = checks.get(name)
            value = d[name]
            if check is None or known[name] is value:
                continue
            checked = check(value)
            if checked is not value:
                object.__setattr__(part, name, checked)
        return
    for name, check in _checks(type(part), skip):
        value = d[name]
        checked = check(value)
        if checked is not value:
            object.__setattr__(part, name, checked)


@cache
def _check_map(cls, skip: tuple[str, ...]) -> dict:
    """:func:`_checks` as a dict by field name."""
    return dict(_checks(cls, skip))


class Part:
    """Shared behaviour of the parts: ``replace`` and the plain field dict."""

    def replace(self, **changes):
        """A copy with some fields changed (validated again)."""
        known = _names(type(self))
        if not known.issuperset(changes):
            raise ParameterError(f"{type(self).__name__} has no field(s) {sorted(set(changes) - known)}; "
                                 f"known: {', '.join(sorted(known))}")
        cls = type(self)
        before = getattr(_SOURCE, "src", None)
        _SOURCE.src = (self, changes)
        try:
            # what the dataclass __init__ does with every field given, without its keyword
            # call (a few us of a fit step, issue 35.5), then the same __post_init__, which
            # derives again whatever it keeps beside the fields (BeamProbe's _cant)
            new = object.__new__(cls)
            d = new.__dict__
            d.update(self.__dict__)     # the fields (and what __post_init__ derives again)
            d.update(changes)
            new.__post_init__()
            return new
        finally:
            _SOURCE.src = before

    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (SI values)."""
        d = self.__dict__
        return {n: d[n] for n in _field_order(type(self))}
