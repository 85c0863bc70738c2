"""``afmforce analyze``: the analysis steps' options from the command line (``--option``, short forms, probe flags)."""

from __future__ import annotations

import argparse

from ..errors import ParameterError

__all__ = ["default", "option_names", "step_options", "OPTION_FLAGS"]


def default(step: str, name: str):
    """A step option's registry default (shown in the help; computed when the help is printed)."""
    from ..analysis.options import OPTIONS

    return OPTIONS[step].__dataclass_fields__[name].default


def option_names() -> str:
    """Every registered step's options (the help of ``--option``; computed when the help is printed)."""
    import dataclasses

    from ..analysis.options_text import step_options as registered

    return "; ".join(f"{s}: {', '.join(f.name for f in dataclasses.fields(c))}" for s, c in registered().items()
                     if dataclasses.fields(c))


#: Dedicated flags that set a step option: dest -> (step, option).
OPTION_FLAGS = {"contact_separation": ("zero", "contact_separation"), "calibration": ("calibration", "source"),
                 "indentation_model": ("indentation", "model"), "tip_radius": ("indentation", "tip_radius"),
                 "half_angle": ("indentation", "half_angle"), "poisson": ("indentation", "poisson"),
                 "medium": ("liquid", "medium"), "permittivity": ("liquid", "permittivity"),
                 "geometry": ("liquid", "geometry"), "double_layer": ("liquid", "double_layer")}


def step_options(args: argparse.Namespace) -> tuple:
    """The step options records (``--option`` and the dedicated flags) and the probe record.

    Raises ParameterError (exit 2) for an unknown step or option, a value out of
    its range, or an option given twice.
    """
    from ..analysis.options import OPTIONS, ProbeCalibration
    from ._validate import check_beam
    from ..analysis.options_text import parse_option
    from ..analysis.pipeline import resolve_options

    given: dict[str, dict] = {}
    for text in args.option:
        step, name, value = parse_option(text, where="--option")
        if name in given.setdefault(step, {}):
            raise ParameterError(f"--option {step}.{name} given twice")
        given[step][name] = value
    for dest, (step, name) in OPTION_FLAGS.items():
        value = getattr(args, dest)
        if value is None:
            continue
        if name in given.get(step, {}):
            raise ParameterError(f"--{dest.replace('_', '-')} and --option {step}.{name} set the same option; "
                                 "give one")
        given.setdefault(step, {})[name] = value
    records = tuple(OPTIONS[step](**values) for step, values in given.items())
    check_beam(args.L0, args.L1, args.L2)   # as the record does, naming the flags
    import dataclasses      # every field of the probe record is a flag of the same name (as the web's probe controls)
    probe = ProbeCalibration(**{f.name: getattr(args, f.name) for f in dataclasses.fields(ProbeCalibration)})
    resolve_options(records, probe)  # what only the registries know (a contact point method's name)
    return records, probe
