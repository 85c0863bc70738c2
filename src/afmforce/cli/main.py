"""Entry point of the ``afmforce`` command.

Each sub-command lives in its own module of this package with a
``register(subparsers)`` function that adds its parser and sets ``func``
(a callable ``func(args) -> int``). :data:`COMMANDS` lists them; only the
module of the command being run is imported, so ``afmforce --help`` and
``afmforce --version`` answer without loading numpy, numba or dask. Errors
raised on purpose (:class:`~afmforce.errors.AfmforceError`) become one line on
stderr and exit status 2 (bad input) unless the command says otherwise;
``--debug`` shows the traceback.

Adding a command: write ``cli/<name>.py`` with ``register(sub)`` and
``run(args)``, and add one line ``"<name>": ("<module>", "<one-line help>")``
to :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import importlib
import os
import re
import sys

from .. import __version__
from ..errors import AfmforceError
from ._validate import HelpFormatter

#: Sub-command -> (module of this package, one-line help), in the order ``afmforce --help`` lists them.
COMMANDS: dict[str, tuple[str, str]] = {
    "demo": ("demo", "reproduce the paper (fast) and analyse a virtual experiment end to end"),
    "statics": ("statics", "static spring constant, calibration factor, friction hysteresis"),
    "diagnose": ("diagnose", "inertia parameter, inertial lag, jump-in and pull-off estimates"),
    "simulate": ("simulate", "simulate a dynamic approach-retract cycle (spring or inclined beam)"),
    "analyze": ("analyze", "analyse force-curve files and force maps: force vs separation, jumps, fits, "
                           "diagnosis"),
    "sweep": ("sweep", "parameter sweeps of the simulation (grids, random/LHS samples) on Dask"),
    "reproduce": ("reproduce", "reproduce the paper's figures and numbers (report.md, PNG)"),
    "explore": ("explore", "write an interactive HTML page: speed x friction on the Fig 5-6 run"),
    "formats": ("formats", "list the force-curve file formats afmforce reads"),
    "fit": ("fit", "fit the dynamic model to curves at several driving speeds (friction, A*R)"),
    "plan": ("plan", "design a multi-speed measurement: speeds and sample rates that fix xi best"),
    "serve": ("serve", "a local web application: analyse, simulate, fit and sweep in the browser"),
}

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line: ``error: <what is wrong>``."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str):  # noqa: D401
        if message.startswith("argument ") and ": " in message:
            head, rest = message.split(": ", 1)
            flag = head[len("argument "):]
            if " expects " in rest or rest.startswith(flag.split("/")[-1]):
                message = rest
            else:
                message = f"{flag}: {rest}"
        self.exit(EXIT_USAGE, f"error: {message}\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """Build the argument parser.

    Parameters
    ----------
    command : str, optional
        Register only this sub-command fully (the others are listed by name
        and help); ``None`` registers every command (imports every module).
        ``""`` registers none.
    """
    parser = _Parser(
        prog="afmforce",
        description="Dynamic surface force measurement with the atomic force microscope.",
        epilog="afmforce COMMAND --help shows the options of a command. Values take units "
               "(200nm, 0.1um/s, -15deg) and are checked against their valid range "
               "(docs/ranges.md) before any work.",
    )
    parser.add_argument("--version", action="version", version=f"afmforce {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, (module, help_) in COMMANDS.items():
        if command is None or name == command:
            importlib.import_module(f"{__package__}.{module}").register(sub)
        else:
            sub.add_parser(name, help=help_, add_help=False)
    return parser


def _command_of(argv: list[str]) -> str:
    """The sub-command named in ``argv`` ("" when none: top-level help, version, a typo)."""
    for tok in argv:
        if not tok.startswith("-"):
            return tok if tok in COMMANDS else ""
    return ""


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


#: Commands that run the dynamic model (and compile it on the first run).
SIMULATING = ("simulate", "demo", "reproduce", "explore", "fit", "plan", "sweep")


def _compile_notice() -> None:
    """One line on stderr when the integrator is about to be compiled (first run, empty or
    stale numba cache): 7-10 s of silence otherwise looks like a hang."""
    from ..dynamics import radau
    from ..dynamics._jit import cache_missing

    if cache_missing(radau.integrate_segment):
        print("afmforce: compiling the integrator, ~10 s (first run; later runs load it from "
              "numba's cache)...", file=sys.stderr, flush=True)


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    argv = _join_negative_values(list(sys.argv[1:] if argv is None else argv))
    parser = build_parser(_command_of(argv))
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return EXIT_USAGE
    try:
        if _command_of(argv) in SIMULATING:
            _compile_notice()
        return int(args.func(args) or 0)
    except AfmforceError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # stdout closed early (afmforce ... | head): not an error of ours
        sys.stdout = open(os.devnull, "w")
        return 1
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
