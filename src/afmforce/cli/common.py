"""Helpers shared by the sub-commands: unit-aware argument types, output."""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from typing import Any, Callable

from .._json import to_jsonable  # noqa: F401  (re-export)
from .._files import atomic_path, atomic_write_bytes, atomic_write_text  # noqa: F401  (re-export)
from ..errors import UnitError
from ..units import format_quantity, parse_quantity


def quantity(dimension: str, flag: str, positive: bool = False) -> Callable[[str], float]:
    """An argparse ``type=`` that parses ``200nm`` style values into SI floats (``positive``: > 0)."""

    def convert(text: str) -> float:
        try:
            value = parse_quantity(text, dimension, flag)
        except UnitError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        if positive and not value > 0:
            raise argparse.ArgumentTypeError(f"{flag} must be positive, got {text}")
        return value

    convert.__name__ = dimension  # argparse uses it in messages
    return convert


def add_quantity(parser: argparse.ArgumentParser, flag: str, dimension: str, default, help: str,
                 unit: str = "", positive: bool = False, **kw) -> None:
    """Add a ``--flag`` taking a value with units (SI default shown in help; ``positive``: > 0)."""
    shown = "" if default is None else f" (default {format_quantity(default, unit) if unit else default})"
    parser.add_argument(flag, type=quantity(dimension, flag, positive), default=default,
                        help=help + shown, metavar="VALUE", **kw)


def print_json(obj: Any) -> None:
    """Print one JSON object (SI values) on stdout."""
    print(json.dumps(to_jsonable(obj), indent=2, sort_keys=False))


def print_table(rows: list[tuple[str, Any, str]], title: str | None = None) -> None:
    """Print ``(label, SI value, unit)`` rows as an aligned table with units. A value that is not a
    number (None, NaN, infinite: a quantity the run does not define) is printed as ``-``, never as
    ``nan`` beside a unit; a row that says why gives its reason as a text instead."""
    import math

    if title:
        print(title)
    width = max((len(r[0]) for r in rows), default=0)
    for label, value, unit in rows:
        if isinstance(value, str):
            text = value
        elif value is None or not math.isfinite(float(value)):
            text = "-"
        else:
            text = format_quantity(float(value), unit)
        print(f"  {label:<{width}}  {text}")


_WORDS = (("pull off", "pull-off"), ("jump in", "jump-in"), ("max ", "maximum "), (" jkr", " (JKR)"),
          (" dmt", " (DMT)"))


def readable(key: str) -> str:
    """A table label from a field name: ``pull_off_force_jkr`` -> ``pull-off force (JKR)``."""
    text = key.replace("_", " ")
    for old, new in _WORDS:
        text = text.replace(old, new)
    return text


def eprint(msg: str) -> None:
    """Print one line on stderr."""
    print(msg, file=sys.stderr)


def progress_bar(desc: str, total: float | None = None, *, unit: str = "", min_total: float = 0,
                 leave: bool = True, enabled: bool = True, counted: bool | None = None):
    """A tqdm bar on a terminal driven by :class:`afmforce.progress.Progress` records.

    Returns ``(bar, update)``; pass ``update`` as the ``progress`` callback of
    ``simulate``, ``load``, ``run_sweep``/``run_batch`` or ``reproduce``. Chunks
    and figures count as they are (any unit with ``counted=True``: ``bar.update()``
    per item); other units (simulated seconds, a fraction of a file) are shown in per mille. Disabled off a terminal, when
    ``enabled`` is false or for a known ``total`` below ``min_total``.
    """
    from tqdm import tqdm

    counted = unit in ("chunk", "figure", "file list") if counted is None else counted
    disable = (not enabled or not sys.stderr.isatty()
               or (total is not None and total < min_total))
    bar = tqdm(total=total if counted else 1000, unit=unit if counted else "‰", desc=desc,
               disable=disable, file=sys.stderr, dynamic_ncols=True, leave=leave)

    def update(p) -> None:
        if counted:
            bar.total = p.total
            bar.n = int(p.done)
        else:
            bar.n = int(1000 * (p.fraction or 0.0))
        if p.failed:
            bar.set_postfix(failed=p.failed, refresh=False)
        if p.what:
            bar.set_description(f"{desc} {p.what}", refresh=False)
        bar.refresh()

    return bar, update


def chunk_progress_bar(desc: str, total: int, *, min_total: int = 1, leave: bool = True):
    """:func:`progress_bar` over a sweep's or batch's chunks."""
    return progress_bar(desc, total, unit="chunk", min_total=min_total, leave=leave)


@contextlib.contextmanager
def busy(desc: str, *, after: float = 2.0):
    """On a terminal, a line with the elapsed time once the work inside has taken ``after`` [s]
    (for work that reports no progress of its own: a fit, a plan); nothing off a terminal."""
    import threading

    from tqdm import tqdm

    if not sys.stderr.isatty():
        yield
        return
    bar = tqdm(total=None, desc=desc, delay=after, file=sys.stderr, leave=False,
               bar_format="{desc}: working, {elapsed} elapsed")
    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(0.5):
            bar.refresh()

    thread = threading.Thread(target=tick, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        bar.close()


def refuse_missing(paths: list[str]) -> None:
    """Refuse input paths that do not exist, before any work: one line naming each, a dangling
    symbolic link or a link loop said as such (``Path.exists`` is False for both, and "no such file"
    for a name the user sees listed is wrong).

    Raises
    ------
    ParameterError
        When any of ``paths`` does not lead to a file or folder.
    """
    import os

    from ..errors import ParameterError

    missing = [p for p in paths if not os.path.exists(p)]
    if not missing:
        return
    links = [p for p in missing if os.path.islink(p)]
    plain = [p for p in missing if p not in links]
    parts = []
    if plain:
        parts.append(f"no such file or folder: {', '.join(plain)}")
    if links:
        parts.append(f"a symbolic link that leads to no file (dangling, or a loop of links): {', '.join(links)}")
    raise ParameterError("; ".join(parts))
