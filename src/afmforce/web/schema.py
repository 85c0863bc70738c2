"""What the page's controls are: every field with its unit, shown unit and valid range.

Built from the declarations, never written twice: the simulation's flat names
(:data:`afmforce.dynamics.config.FLAT`, specs from :data:`afmforce._fields.QUANTITIES`),
the analysis steps and their options (:mod:`afmforce.analysis.registry`), the fit's
parameters (:data:`afmforce.fit.PARAMETERS`) and the shipped example files.
"""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache
from typing import Any

from .._fields import DISPLAY_UNITS, FieldSpec

__all__ = ["simulation_fields", "analysis_steps", "analysis_options", "analysis_settings", "calibration_fields", "fit_parameters",
           "fit_defaults", "examples", "schema"]

#: SI unit -> the unit a control shows when its spec names none.
_SHOWN = {"m": "nm", "N": "nN", "kg": "ng", "m/s": "um/s", "Hz": "kHz", "s": "s", "m/V": "nm/V", "rad": "deg"}


def _num(v):
    return v if v is None or isinstance(v, (str, bool)) or (isinstance(v, float) and math.isfinite(v)) \
        or isinstance(v, int) else None


def field_json(name: str, spec: FieldSpec | None, default: Any, *, choices=(), help: str = "",
               labels: dict[str, str] | None = None) -> dict[str, Any]:
    """One control: ``{name, unit (SI), shown, factor (SI per shown unit), lo, hi, default, help, choices, kind}``."""
    if spec is None:
        return {"name": name, "kind": "choice", "choices": list(choices), "default": default, "help": help,
                "unit": "", "shown": "", "factor": 1.0, "lo": None, "hi": None, "labels": labels or {}}
    shown = spec.display or _SHOWN.get(spec.unit, spec.unit)
    if shown == "nm" and isinstance(default, float) and abs(default) >= 1e-6:
        shown = "um"  # beam lengths
    factor = DISPLAY_UNITS.get(shown, 1.0) if shown != spec.unit else 1.0
    kind = {"integer": "integer", "flag": "flag", "choice": "choice", "text": "text"}.get(spec.dimension, "number")
    return {"name": name, "kind": kind, "unit": spec.unit, "shown": shown, "factor": factor,
            "lo": _num(spec.lo), "hi": _num(spec.hi), "lo_open": spec.lo_open, "hi_open": spec.hi_open,
            "range": spec.range_text(), "default": _num(default) if not isinstance(default, tuple) else None,
            "help": help or spec.help, "choices": [c for c in choices if isinstance(c, (str, int, float))],
            "log": bool(spec.lo is not None and spec.hi is not None and spec.lo > 0 and spec.hi / spec.lo > 1e3),
            "labels": labels or {}}


@lru_cache(maxsize=1)
def simulation_fields() -> list[dict[str, Any]]:
    """Every flat name of a :class:`~afmforce.dynamics.SimulationConfig`, in header order."""
    from ..dynamics.config import FLAT

    out = []
    for name, where in FLAT.items():
        d = field_json(name, where.spec, where.default, choices=where.choices,
                       help=name if where.spec is None else "")
        d.update(part=where.part, models=list(where.models))
        out.append(d)
    return out


def analysis_steps() -> list[dict[str, Any]]:
    """The analysis steps the page offers, from the registry (:mod:`afmforce.analysis.registry`), in
    the pipeline's order: identifier, name, required steps, reference, whether it has options."""
    from ..analysis.registry import steps

    return [{"identifier": s.identifier, "name": s.name, "requires": list(s.requires), "reference": s.reference,
             "options": bool(dataclasses.fields(s.options))} for s in steps().values()]


def analysis_options() -> dict[str, list[dict[str, Any]]]:
    """Step -> its options (the typed options of ``afmforce analyze --option``), for every registered step."""
    from ..analysis.registry import version

    return _analysis_options(version())


@lru_cache(maxsize=2)
def _analysis_options(version: int) -> dict[str, list[dict[str, Any]]]:
    from ..analysis.registry import steps

    out = {}
    for step, cls in ((s.identifier, s.options) for s in steps().values()):
        fields = []
        for f in dataclasses.fields(cls):
            spec = f.metadata.get("spec")
            default = f.default if f.default is not dataclasses.MISSING else None
            if (step, f.name) == ("indentation", "model"):     # a choice of the contact registry
                fields.append(contact_model_field(spec, default))
                continue
            fields.append(field_json(f.name, spec, default, choices=f.metadata.get("choices", ())))
        if fields:
            out[step] = fields
    return out


def contact_model_field(spec: FieldSpec | None, default: Any) -> dict[str, Any]:
    """The indentation model as a choice of :data:`afmforce.contact.INDENTATION_MODELS`, each with
    its name, the geometry it needs and where it holds (``models``)."""
    from ..contact import INDENTATION_MODELS

    d = field_json("model", spec, default, choices=tuple(INDENTATION_MODELS),
                   labels={k: m.name for k, m in INDENTATION_MODELS.items()})
    d["kind"] = "choice"
    d["models"] = {k: {"name": m.name, "geometry": list(m.geometry), "validity": m.validity,
                       "reference": m.reference, "adhesive": m.adhesive} for k, m in INDENTATION_MODELS.items()}
    return d


#: The probe's controls the analyse view shows first: every :class:`~afmforce.analysis.options.ProbeCalibration`
#: field (sent as ``probe``, as ``afmforce analyze --spring-constant ... --theta0 ... --L0``), in this order
#: and then any other field the record declares; then the indentation step's geometry and sample (sent as
#: options). ``PROBE_SHOWS``: the result keys of the values the analysis used, shown beside a field.
PROBE_FIRST = ("spring_constant", "sensitivity", "resonance_frequency", "radius", "theta0", "L0", "L1", "L2")
PROBE_SHOWS = {"spring_constant": ("spring_constant",), "sensitivity": ("sensitivity", "sensitivity_used"),
               "resonance_frequency": ("resonance_frequency",)}
OPTIONS_SHOWN = (("indentation.model", ("indentation_model",)), ("indentation.tip_radius", ()),
                 ("indentation.half_angle", ()), ("indentation.poisson", ()))


def _calibration_rows() -> tuple[tuple[str, str, tuple[str, ...]], ...]:
    from ..analysis.options import ProbeCalibration

    names = [f.name for f in dataclasses.fields(ProbeCalibration) if f.metadata.get("spec") is not None]
    ordered = [n for n in PROBE_FIRST if n in names] + [n for n in names if n not in PROBE_FIRST]
    return tuple(("probe", n, PROBE_SHOWS.get(n, ())) for n in ordered) + \
        tuple(("option", key, shows) for key, shows in OPTIONS_SHOWN)


@lru_cache(maxsize=1)
def calibration_fields() -> list[dict[str, Any]]:
    """The calibration and probe controls of the analyse view: spring constant k, sensitivity
    (InvOLS, nm/V), resonance frequency, sphere radius, the inclined cantilever's inclination theta0 and
    lengths L0, L1, L2 (every :class:`~afmforce.analysis.options.ProbeCalibration` field, ``via: probe``),
    the indentation model, tip radius, half angle and Poisson ratio (options of the ``indentation`` step,
    ``via: option``). ``shows``: result keys of the values the analysis used."""
    from ..analysis.options import ProbeCalibration

    probe = {f.name: f for f in dataclasses.fields(ProbeCalibration)}
    simulated = {f["name"]: f for f in simulation_fields()}
    out = []
    for via, key, shows in _calibration_rows():
        if via == "probe":
            f = probe[key]
            d = field_json(key, f.metadata["spec"], None)
            same = simulated.get(key)       # shown in the unit of the simulation's control (the beam in um)
            if same is not None and same["unit"] == d["unit"]:
                d.update(shown=same["shown"], factor=same["factor"])
        else:
            step, name = key.split(".")
            d = dict(next(o for o in analysis_options()[step] if o["name"] == name))
        d.update(via=via, key=key, shows=list(shows))
        out.append(d)
    return out


def analysis_settings() -> list[dict[str, Any]]:
    """The analysis's word settings (:data:`afmforce._fields.ANALYSIS_CHOICES`: the position channel ...),
    each a choice control sent as its own form field (``channel``), as ``afmforce analyze --channel``."""
    from .._fields import ANALYSIS_CHOICES

    return [dict(field_json(name, None, c.default, choices=c.choices, help=c.help), via="field")
            for name, c in ANALYSIS_CHOICES.items()]


def fit_parameters() -> list[dict[str, Any]]:
    """The fit's global parameters (``free`` choices)."""
    from ..fit import PARAMETERS

    return [{"name": n, "unit": p.unit, "lower": _num(p.lower), "upper": _num(p.upper)}
            for n, p in PARAMETERS.items()]


def fit_defaults() -> dict[str, Any]:
    """The fit's defaults, read off :func:`afmforce.fit.fit_dynamic`'s signature (as ``afmforce fit``
    runs it): ``free`` parameters, ``starts``, ``profile`` (intervals by profile likelihood) and
    ``compare`` (the friction verdict). The form's controls and the request's defaults take them."""
    import inspect

    from ..fit import fit_dynamic

    p = inspect.signature(fit_dynamic).parameters
    return {"free": list(p["free"].default), "starts": int(p["starts"].default),
            "profile": p["profile"].default != (), "compare": bool(p["compare"].default)}


def examples() -> list[dict[str, str]]:
    """The sample files shipped with afmforce (``afmforce analyze --example``)."""
    from ..datasets import DATASETS

    return [{"name": n, "description": d.description} for n, d in DATASETS.items()]


def schema() -> dict[str, Any]:
    """Everything the page builds its controls from."""
    from ..instrument.presets import PRESETS

    return {"simulation": simulation_fields(), "analysis": analysis_options(), "steps": analysis_steps(),
            "calibration": calibration_fields(), "analysis_settings": analysis_settings(),
            "fit": fit_parameters(), "fit_defaults": fit_defaults(), "examples": examples(),
            "instrument_presets": list(PRESETS)}
