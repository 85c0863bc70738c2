"""Command-line flags derived from field metadata, and the checks made before any work.

- :func:`add_field` adds ``--flag VALUE`` for a quantity of
  :data:`afmforce._fields.QUANTITIES` (or any :class:`~afmforce._fields.FieldSpec`):
  the value takes units, is checked against the valid range while parsing
  (exit 2, one line), and the help shows the range and the default in the
  user's units. A default that only a heavy module knows (``SimulationConfig``)
  is given as ``default_from=callable`` and computed when help is printed,
  never when the parser is built.
- :func:`check_output` fails before the work if an output cannot be written.
- :func:`refuse_ignored` refuses options that the chosen model ignores.
- :func:`confirm_size` refuses very large runs without ``--yes``.

Nothing here imports numpy, numba, dask or matplotlib.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterable

from .._fields import QUANTITIES, FieldSpec
from ..errors import OutputExistsError, ParameterError, UnitError

__all__ = ["HelpFormatter", "add_field", "field_type", "check_output", "refuse_ignored", "confirm_size",
           "lazy_help", "given"]


class HelpFormatter(argparse.HelpFormatter):
    """Help formatter that appends lazily computed text (defaults, choices) at print time."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        extra = getattr(action, "lazy_help", None)
        return text if extra is None else text + extra().replace("%", "%%")


def lazy_help(action: argparse.Action, text: Callable[[], str]) -> argparse.Action:
    """Append ``text()`` to ``action``'s help when the help is printed."""
    action.lazy_help = text
    return action


def field_type(spec: FieldSpec, name: str, flag: str) -> Callable[[str], Any]:
    """An argparse ``type=``: value with units -> SI, checked against ``spec``'s range."""

    def convert(text: str):
        from ..units import DIMENSIONS, parse_quantity

        try:
            if spec.dimension == "integer":
                try:
                    value = float(text)
                except ValueError:
                    raise ParameterError(f"{flag} expects a whole number, got {text}") from None
                if not value.is_integer():
                    raise ParameterError(f"{flag} expects a whole number, got {text}")
                value = int(value)
            elif spec.dimension in DIMENSIONS:
                value = parse_quantity(text, spec.dimension, flag)
            else:  # pragma: no cover - every CLI quantity has a parseable dimension
                value = float(text)
            return spec.check(value, name, flag, typed=text)
        except (ParameterError, UnitError) as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = spec.dimension  # argparse names it in some messages
    return convert


def add_field(group, name: str, *, flag: str | None = None, dest: str | None = None,
              default: Any = None, default_from: Callable[[], Any] | None = None,
              help: str | None = None, spec: FieldSpec | None = None, **kw) -> argparse.Action:
    """Add ``--flag VALUE`` for quantity ``name`` (a key of :data:`QUANTITIES`, or give ``spec``).

    Parameters
    ----------
    flag : str
        Default ``--<name>`` with ``_`` -> ``-``.
    dest : str
        Namespace attribute; default ``name``.
    default : any
        Parsed default [SI], shown in the help in the field's display unit.
    default_from : callable
        Returns the default to *show* (the value itself stays ``default``),
        called only when the help is printed.
    help : str
        Help text; default the spec's.
    """
    spec = spec or QUANTITIES[name]
    flag = flag or "--" + name.replace("_", "-")
    text = (help or spec.help) + (f" [{spec.unit}]" if spec.unit and spec.unit not in (help or "") else "")

    def tail() -> str:
        parts = []
        if spec.bounded:
            parts.append(f"range {spec.range_text()}")
        shown = default if default_from is None else default_from()
        if shown is not None:
            parts.append(f"default {spec.show(shown)}")
        return f" ({'; '.join(parts)})" if parts else ""

    action = group.add_argument(flag, dest=dest or name, type=field_type(spec, dest or name, flag),
                                default=default, metavar="VALUE", help=text, **kw)
    return lazy_help(action, tail)


def given(args: argparse.Namespace, dest: str) -> bool:
    """Whether option ``dest`` has a value (was given, or has a non-None default)."""
    return getattr(args, dest, None) is not None


def refuse_ignored(args: argparse.Namespace, rules: Iterable[tuple[str, str, bool, str]]) -> None:
    """Refuse options that the chosen model ignores.

    ``rules``: ``(dest, flag, applies, why)``; an option with a value whose
    ``applies`` is false raises ``ParameterError("{flag} is ignored {why}")``.
    """
    for dest, flag, applies, why in rules:
        if not applies and given(args, dest):
            raise ParameterError(f"{flag} is ignored {why}; drop it")


def _nearest_existing(path: Path) -> Path:
    p = path
    while not p.exists():
        if p.parent == p:
            break
        p = p.parent
    return p


def _can_create_in(folder: Path) -> bool:
    """Really try: create and remove a temporary file (os.access lies for root and read-only mounts)."""
    try:
        fd, tmp = tempfile.mkstemp(prefix=".afmforce-write-test-", dir=folder)
    except OSError:
        return False
    os.close(fd)
    os.unlink(tmp)
    return True


def check_output(path, *, flag: str = "--out", force: bool = True, folder: bool = False) -> Path:
    """Fail before any work if ``path`` cannot be written (exit 2 via the error).

    Parameters
    ----------
    folder : bool
        ``path`` is an output folder (created if missing) rather than a file.
    force : bool
        For a file: overwriting an existing one is allowed.

    Raises
    ------
    OutputExistsError
        A file exists and ``force`` is false.
    ParameterError
        The path, or the folder it would be created in, cannot be written.
    """
    path = Path(path)
    if folder:
        if path.exists() and not path.is_dir():
            raise ParameterError(f"{flag} {path} exists and is not a folder")
    elif path.is_dir():
        raise ParameterError(f"{flag} {path} is a folder; give a file name")
    elif path.exists() and not force:
        raise OutputExistsError(f"{path} exists; choose another name or pass --force to overwrite")
    base = path if folder and path.is_dir() else _nearest_existing(path.parent if not folder else path)
    if not base.is_dir():
        raise ParameterError(f"{flag} {path} cannot be written: {base} is not a folder")
    if not _can_create_in(base):
        raise ParameterError(f"{flag} {path} cannot be written: no permission to write in {base}")
    return path


def confirm_size(n: int, limit: int, *, yes: bool, what: str) -> None:
    """Refuse ``n`` > ``limit`` units of work unless ``yes``."""
    if n > limit and not yes:
        raise ParameterError(f"{what}: {n:,} runs is more than {limit:,}; check the numbers, "
                             "then pass --yes to run them")


def check_beam(L0: float, L1: float, L2: float, *, k0: float | None = None, B: float | None = None,
               prefix: str = "--") -> None:
    """Refuse an inclined cantilever that is not one: rigid parts longer than the beam, or a
    rigidity that makes the intrinsic spring constant ``k0 = 3 B / L0^3`` leave its range.
    """
    for name, value in (("L1", L1), ("L2", L2)):
        if value is not None and L0 is not None and value > L0:
            raise ParameterError(
                f"{prefix}{name} {QUANTITIES[name].show(value)} is longer than the flexible beam "
                f"{prefix}L0 {QUANTITIES['L0'].show(L0)}; the base and the probe are short rigid parts "
                "of the cantilever (Fig 2)")
    if B is not None and L0 is not None and k0 is None:
        k = 3.0 * B / L0**3
        spec = QUANTITIES["k0"]
        if not spec.contains(k):
            raise ParameterError(
                f"{prefix}B {QUANTITIES['B'].show(B)} with {prefix}L0 {QUANTITIES['L0'].show(L0)} gives "
                f"k0 = 3B/L0^3 = {spec.show(k)}, out of range: k0 must lie in {spec.range_text()}")
