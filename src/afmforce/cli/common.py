"""Helpers shared by the sub-commands: unit-aware argument types, output."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any, Callable

from .._json import to_jsonable  # noqa: F401  (re-export)
from .._files import atomic_path, atomic_write_bytes, atomic_write_text  # noqa: F401  (re-export)
from ..errors import UnitError
from ..units import format_quantity, parse_quantity


def quantity(dimension: str, flag: str) -> Callable[[str], float]:
    """An argparse ``type=`` that parses ``200nm`` style values into SI floats."""

    def convert(text: str) -> float:
        try:
            return parse_quantity(text, dimension, flag)
        except UnitError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    convert.__name__ = dimension  # argparse uses it in messages
    return convert


def add_quantity(parser: argparse.ArgumentParser, flag: str, dimension: str, default, help: str,
                 unit: str = "", **kw) -> None:
    """Add a ``--flag`` taking a value with units (SI default shown in help)."""
    shown = "" if default is None else f" (default {format_quantity(default, unit) if unit else default})"
    parser.add_argument(flag, type=quantity(dimension, flag), default=default,
                        help=help + shown, metavar="VALUE", **kw)


def print_json(obj: Any) -> None:
    """Print one JSON object (SI values) on stdout."""
    print(json.dumps(to_jsonable(obj), indent=2, sort_keys=False))


def print_table(rows: list[tuple[str, Any, str]], title: str | None = None) -> None:
    """Print ``(label, SI value, unit)`` rows as an aligned table with units."""
    if title:
        print(title)
    width = max((len(r[0]) for r in rows), default=0)
    for label, value, unit in rows:
        if isinstance(value, str):
            text = value
        elif value is None:
            text = "-"
        else:
            text = format_quantity(float(value), unit)
        print(f"  {label:<{width}}  {text}")


def eprint(msg: str) -> None:
    """Print one line on stderr."""
    print(msg, file=sys.stderr)


def chunk_progress_bar(desc: str, total: int, *, min_total: int = 1, leave: bool = True):
    """A tqdm bar over chunks on a terminal and the engine callback that drives it.

    Returns ``(bar, update)``; ``update(progress)`` takes the engine's progress
    record (``chunks_total``, ``chunks_done``, ``chunks_failed``). The bar is
    disabled off a terminal or for fewer than ``min_total`` chunks.
    """
    from tqdm import tqdm

    bar = tqdm(total=total, unit="chunk", desc=desc, disable=total < min_total or not sys.stderr.isatty(),
               file=sys.stderr, dynamic_ncols=True, leave=leave)

    def update(p) -> None:
        bar.total = p.chunks_total
        bar.n = p.chunks_done
        if p.chunks_failed:
            bar.set_postfix(failed=p.chunks_failed, refresh=False)
        bar.refresh()

    return bar, update
