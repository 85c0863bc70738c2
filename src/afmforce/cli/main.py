"""Entry point of the ``afmforce`` command.

Each sub-command lives in its own module of this package with a
``register(subparsers)`` function that adds its parser and sets ``func``
(a callable ``func(args) -> int``). Errors raised on purpose
(:class:`~afmforce.errors.AfmforceError`) become one line on stderr and exit
status 2 (bad input) unless the command says otherwise; ``--debug`` shows the
traceback.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys

from ..errors import AfmforceError

#: Sub-command modules, in the order ``afmforce --help`` lists them.
COMMANDS = ("demo", "statics", "diagnose", "simulate", "analyze", "formats", "sweep", "reproduce", "explore",
            "fit", "plan")

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line: ``error: <what is wrong>``."""

    def error(self, message: str):  # noqa: D401
        if message.startswith("argument ") and ": " in message:
            head, rest = message.split(": ", 1)
            if " expects " in rest:
                message = rest
            else:
                message = f"{head[len('argument '):]}: {rest}"
        self.exit(EXIT_USAGE, f"error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    """Build the full argument parser with every available sub-command."""
    parser = _Parser(
        prog="afmforce",
        description="Dynamic surface force measurement with the atomic force microscope.",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMANDS:
        importlib.import_module(f"{__package__}.{name}").register(sub)
    return parser


_NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d)")


def _join_negative_values(argv: list[str]) -> list[str]:
    """Turn ``--theta0 -15deg`` into ``--theta0=-15deg``.

    argparse takes ``-15deg`` for an option because it is not a plain number.
    """
    out: list[str] = []
    i = 0
    while i < len(argv):
        tok = argv[i]
        if (tok.startswith("--") and "=" not in tok and i + 1 < len(argv)
                and _NEGATIVE_VALUE.match(argv[i + 1])):
            out.append(f"{tok}={argv[i + 1]}")
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = build_parser()
    argv = _join_negative_values(list(sys.argv[1:] if argv is None else argv))
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_USAGE
    try:
        return int(args.func(args) or 0)
    except AfmforceError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
