"""Text forms of the step options (:mod:`.options`): ``--option STEP.NAME=VALUE`` and the docs table.

Imports nothing heavy (the command line uses it while checking its arguments).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from .._fields import FieldSpec, spec_of
from ..errors import ParameterError
from .options import OPTIONS, ProbeCalibration

__all__ = ["step_options", "option_spec", "show_default", "parse_option", "options_markdown"]


def step_options() -> dict[str, type]:
    """Step -> options class of every registered step (a step declared in its own module, options
    included, is found once the registry has imported the step modules)."""
    from .registry import steps

    return {k: s.options for k, s in steps().items()}


def _options_of(step: str) -> type | None:
    cls = OPTIONS.get(step)   # the records of options.py: no step module imported
    return cls if cls is not None else step_options().get(step)


def option_spec(cls: type, name: str) -> tuple[FieldSpec, tuple, Any]:
    """``(spec, choices, default)`` of option ``name`` of record class ``cls``."""
    for f in dataclasses.fields(cls):
        if f.name == name:
            return f.metadata["spec"], f.metadata.get("choices", ()), f.default
    known = ", ".join(f.name for f in dataclasses.fields(cls)) or "none"
    raise ParameterError(f"unknown option {name!r} for step {getattr(cls, 'step', '')!r}; known: {known}")


def show_default(f: dataclasses.Field) -> str:
    """A field's default as the user would write it (``30 nm``, ``auto``, ``none``)."""
    v = f.default
    if isinstance(v, bool):
        return "true" if v else "false"
    spec = spec_of(f)
    if isinstance(v, str) or v is None or spec is None:
        return "none" if v is None else str(v)
    if not spec.unit:
        return f"{v:g}" if isinstance(v, float) else str(v)
    return spec.show(v)


def parse_option(text: str, where: str = "option") -> tuple[str, str, Any]:
    """``"vdw.max_separation=20nm"`` -> ``("vdw", "max_separation", 2e-08)`` (SI, checked).

    Words (``auto``, ``line``), ``true``/``false`` and ``none`` are accepted where
    the option takes them; numbers take the option's units.
    """
    key, sep, value = text.partition("=")
    step, dot, name = key.strip().partition(".")
    if not (sep and dot and step and name):
        raise ParameterError(f"{where} {text!r}: expected STEP.NAME=VALUE, e.g. vdw.max_separation=20nm")
    cls = _options_of(step)
    if cls is None:
        raise ParameterError(f"{where} {key}: unknown step {step!r}; steps with options: "
                             + ", ".join(s for s, c in step_options().items() if dataclasses.fields(c)))
    spec, choices, default = option_spec(cls, name)
    value = value.strip()
    flag = f"{where} {key}"
    low = value.lower()
    if spec.dimension == "flag":
        if low not in ("true", "false", "yes", "no", "1", "0"):
            raise ParameterError(f"{flag}: expected true or false, got {value!r}")
        return step, name, low in ("true", "yes", "1")
    if value in choices or spec.dimension == "text":
        return step, name, value
    if low == "none" and default is None:
        return step, name, None
    if spec.dimension == "choice":
        raise ParameterError(f"{flag} = {value!r} is not valid: {name}, the {spec.help}, must be "
                             + ", ".join(str(c) for c in choices))
    from ..units import parse_typed

    number: Any = parse_typed(value, spec.dimension, flag)
    if not (isinstance(number, float) and math.isnan(number)):
        spec.check(number, name, flag, typed=value)
    return step, name, number


def options_markdown() -> str:
    """The docs table of the probe's fields and every step option: meaning, SI unit, default, valid range."""
    lines = ["| option | meaning | SI unit | default | valid values |", "|---|---|---|---|---|"]
    for prefix, cls in (("probe", ProbeCalibration), *step_options().items()):
        for f in dataclasses.fields(cls):
            spec = spec_of(f)
            choices = f.metadata.get("choices", ())
            if spec.dimension == "choice":
                valid = ", ".join(str(c) for c in choices)
            elif spec.dimension == "flag":
                valid = "true, false"
            elif spec.dimension == "text":
                valid = "a registered name"
            else:
                valid = spec.range_text() + "".join(f", {c}" for c in choices)
            lines.append(f"| `{prefix}.{f.name}` | {spec.help} | {spec.unit or '-'} | {show_default(f)} | {valid} |")
    return "\n".join(lines)
