"""Command-line options of the virtual AFM, for commands that produce trajectories.

A command adds the options with :func:`add_instrument_arguments` and, after
simulating, calls :func:`record_from_args`::

    afmforce simulate ... --instrument paper --seed 1 --raw out.txt
    afmforce simulate ... --instrument typical --photodiode-sensitivity 30nm/V --raw out.h5
    afmforce simulate ... --config instrument.toml --raw out.txt --force

Options: ``--instrument ideal|typical|paper|liquid``, ``--seed N``, ``--raw FILE``
(afmforce raw text, or HDF5 for ``.h5``/``.hdf5``), ``--instrument-config
FILE.toml`` (also ``--config`` when the command has no ``--config`` of its
own), ``--force`` (overwrite ``--raw``; shared with the command's own
``--force`` if it has one) and one flag per component parameter,
``--<component>-<parameter> VALUE`` with units (see
:data:`afmforce.instrument.config.PARAMETERS`).
"""

from __future__ import annotations

import argparse
from typing import Any

from .._files import check_writable
from ..errors import AfmforceError, ParameterError
from ..instrument.config import PARAMETERS, Parameter, build_instrument, load_config, parse_parameter
from ..instrument.presets import PRESETS
from ..io.curve import RawCurve
from ..io.native.rawfile import write_raw

__all__ = ["add_instrument_arguments", "record_from_args", "check_raw_output", "instrument_requested"]

_PREFIX = "instrument_param__"


def _param_type(p: Parameter):
    def convert(text: str):
        try:
            return parse_parameter(p.key, text, p.flag)
        except AfmforceError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = p.dimension
    return convert


def _seed_type(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--seed expects a whole number >= 0, got {text}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"--seed expects a whole number >= 0, got {text}")
    return value


def _taken(parser: argparse.ArgumentParser, flag: str) -> bool:
    return flag in parser._option_string_actions


def add_instrument_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the virtual-AFM options to ``parser`` (see the module docstring).

    ``--seed``, ``--force`` and ``--config`` are only added when the parser
    does not define them already; :func:`record_from_args` then uses the
    command's own (``--instrument-config`` is always available).
    """
    g = parser.add_argument_group("virtual instrument", "record the trajectory as an AFM would "
                                  "(afmforce.instrument; see docs/instrument.md)")
    g.add_argument("--instrument", choices=list(PRESETS), default=None,
                   help="instrument preset: " + "; ".join(f"{p.name}: {p.description}" for p in PRESETS.values()))
    if not _taken(parser, "--seed"):
        g.add_argument("--seed", type=_seed_type, default=None, metavar="N",
                       help="seed of the instrument's noise and drift (default: random, written to the file)")
    g.add_argument("--raw", metavar="FILE", default=None,
                   help="write the raw curve: afmforce raw text, or HDF5 for .h5/.hdf5")
    config_flags = ["--instrument-config"] + ([] if _taken(parser, "--config") else ["--config"])
    g.add_argument(*config_flags, dest="instrument_config", metavar="FILE.toml", default=None,
                   help="instrument TOML file: preset and [component] tables of parameters")
    if not _taken(parser, "--force"):
        g.add_argument("--force", action="store_true", help="overwrite existing output files")
    pg = parser.add_argument_group("instrument parameters",
                                   "override one parameter of the chosen preset (values with units)")
    for p in PARAMETERS.values():
        unit = f" [{p.unit}]" if p.unit else ""
        extra = " (comma-separated list)" if p.is_list else ""
        extra += " ('none' to unset)" if p.optional else ""
        pg.add_argument(p.flag, dest=_PREFIX + p.key.replace(".", "__"), type=_param_type(p),
                        default=argparse.SUPPRESS, metavar="VALUE", help=f"{p.help}{unit}{extra}")


def _overrides(args: argparse.Namespace) -> dict[str, Any]:
    out = {}
    for p in PARAMETERS.values():
        dest = _PREFIX + p.key.replace(".", "__")
        if hasattr(args, dest):
            out[p.key] = getattr(args, dest)
    return out


def instrument_requested(args: argparse.Namespace) -> bool:
    """True when any virtual-AFM option was given."""
    return bool(getattr(args, "instrument", None) or getattr(args, "raw", None)
                or getattr(args, "instrument_config", None) or _overrides(args))


def check_raw_output(args: argparse.Namespace) -> None:
    """Fail early (before a long simulation) if ``--raw`` exists and ``--force`` is not given.

    Raises
    ------
    OutputExistsError
    """
    raw = getattr(args, "raw", None)
    if raw:
        check_writable(raw, force=bool(getattr(args, "force", False)))


def check_instrument_args(args: argparse.Namespace) -> None:
    """Read the instrument's TOML file and build the instrument before any simulation (a file that is
    no text, or a parameter out of range, is refused before minutes of work, and before a compile).

    Raises
    ------
    AfmforceError
        As :func:`record_from_args`.
    """
    if not instrument_requested(args):
        return
    check_raw_output(args)
    config = load_config(args.instrument_config) if getattr(args, "instrument_config", None) else None
    preset = getattr(args, "instrument", None)
    try:
        build_instrument(preset, config, _overrides(args))
    except ParameterError as exc:
        raise ParameterError(f"{_culprit(args, preset, config, str(exc))}{exc}") from None


def _culprit(args: argparse.Namespace, preset: str | None, config: dict | None, message: str) -> str:
    """Where the value an instrument component refused was written: ``<file>: [noise] white = inf: `` for a
    key of the instrument TOML file, ``--noise-white -1.0: `` for a flag; "" when no single one is. The key the
    component's ``message`` names (``piezo creep_times must be ...``) first, else the one refused alone."""
    from_file = ((config or {}).get("parameters") or {}).items()
    typed = _overrides(args).items()

    def label(key, value, flag: bool) -> str:
        table, name = key.split(".", 1)
        return (f"{PARAMETERS[key].flag} {value!r}: " if flag else
                f"`instrument_config` {args.instrument_config}: [{table}] {name} = {value!r}: ")

    for flag, items in ((True, typed), (False, from_file)):      # a flag wins over the file's value
        for key, value in items:
            if message.startswith(key.replace(".", " ") + " "):
                return label(key, value, flag)
    for flag, items in ((False, from_file), (True, typed)):
        for key, value in items:
            try:
                build_instrument(preset, None if flag else {"parameters": {key: value}}, {key: value} if flag else None)
            except ParameterError:
                return label(key, value, flag)
    return ""


def record_from_args(args: argparse.Namespace, trajectory) -> RawCurve | None:
    """Build the instrument from the options, record ``trajectory``, write ``--raw``.

    Returns ``None`` when no virtual-AFM option was given. Without
    ``--instrument`` the preset comes from the TOML file, else ``ideal``.

    Raises
    ------
    AfmforceError
        Bad parameters (ParameterError), unreadable config (FileFormatError),
        an existing ``--raw`` without ``--force`` (OutputExistsError).
    """
    if not instrument_requested(args):
        return None
    check_raw_output(args)
    config = load_config(args.instrument_config) if getattr(args, "instrument_config", None) else None
    instrument = build_instrument(getattr(args, "instrument", None), config, _overrides(args))
    seed = getattr(args, "seed", None)
    if seed is None and config is not None:
        seed = config.get("seed")
    curve = instrument.record(trajectory, seed=seed)
    if getattr(args, "raw", None):
        write_raw(curve, args.raw, force=bool(getattr(args, "force", False)))
    return curve
