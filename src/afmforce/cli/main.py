"""Entry point of the ``afmforce`` command.

Each sub-command lives in its own module of this package with a
``register(subparsers)`` function that adds its parser and sets ``func``
(a callable ``func(args) -> int``). :data:`COMMANDS` lists them; only the
module of the command being run is imported, so ``afmforce --help`` and
``afmforce --version`` answer without loading numpy, numba or dask. Every
outcome follows one contract (:mod:`afmforce.cli._outcome`): an error is one
line on stderr, exit status 2 for usage errors and 1 for failures, no traceback
unless ``--debug``; ``--json`` (every command has it) prints exactly one JSON
object on stdout, errors included; every file written is named.

Adding a command: write ``cli/<name>.py`` with ``register(sub)`` and
``run(args)``, and add one line ``"<name>": ("<module>", "<one-line help>")``
to :data:`COMMANDS`.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import re
import sys

from .. import __version__
from . import _firstrun, _outcome
from ._validate import HelpFormatter, check_common, refuse_empty_values

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
    "formats": ("formats", "list the force-curve file formats afmforce reads"),
    "fit": ("fit", "fit the dynamic model to curves at several driving speeds (friction, A*R)"),
    "plan": ("plan", "design a multi-speed measurement: speeds and sample rates that fix xi best"),
    "calibrate": ("calibrate", "calibrate the probe: thermal noise spectrum, Sader method, InvOLS"),
    "serve": ("serve", "a local web application: analyse, simulate, fit and sweep in the browser"),
    "warmup": ("warmup", "compile the kernels the commands use, once, ahead of their first run"),
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
        if message.startswith("unrecognized arguments: "):
            tokens = message[len("unrecognized arguments: "):].split()
            message = "unrecognized arguments: " + " ".join(_JOINED.get(t, t) for t in tokens)   # as typed
            message += _unrecognized_hint(tokens)
        self.exit(_outcome.fail("UsageError", _outcome.one_line(message), EXIT_USAGE))


def _unrecognized_hint(tokens: list[str]) -> str:
    """What a flag the command lacks is called there: a file's metadata (``analyze --velocity 0``: the
    command takes ``--meta velocity=VALUE``), or the command's nearest flag (``--tip-raduis``)."""
    import difflib

    options = sorted(o for o in (_outcome.RunState.options or ()) if o.startswith("--"))
    for tok in tokens:
        if not tok.startswith("--"):
            continue
        flag = tok.split("=", 1)[0]
        key = flag[2:].replace("-", "_")
        if "--meta" in options:
            from ..io import METADATA

            if key in METADATA:
                return f" (this command takes file metadata as --meta {key}=VALUE)"
        if flag in options:      # a flag of another method (calibrate thermal's, not calibrate invols')
            return f" ({flag} is an option of another method of this command: each method's --help lists its own)"
        near = difflib.get_close_matches(flag, options, n=1, cutoff=0.75)
        if near:
            return f" (did you mean {near[0]}?)"
    return ""


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
            _add_json(sub.choices[name])
        else:
            sub.add_parser(name, help=help_, add_help=False)
    return parser


def _add_json(parser: argparse.ArgumentParser) -> None:
    """Give a command without a JSON result of its own ``--json``: its outcome as one JSON object."""
    if "--json" not in parser._option_string_actions:
        parser.add_argument("--json", action="store_true",
                            help="print one JSON object on stdout: exit status, the text output and the "
                                 "files written (errors: {\"error\": {...}})")
        parser.set_defaults(_generic_json=True)


def _subparser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[command]


def _option_strings(parser: argparse.ArgumentParser) -> frozenset:
    """Every option string of ``parser`` and of its sub-commands (``calibrate thermal``)."""
    out: set[str] = set()
    for action in parser._actions:
        out.update(action.option_strings)
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                out |= _option_strings(sub)
    return frozenset(out)


def _command_of(argv: list[str]) -> str:
    """The sub-command named in ``argv`` ("" when none: top-level help, version, a typo)."""
    for tok in argv:
        if not tok.startswith("-"):
            return tok if tok in COMMANDS else ""
    return ""


_NEGATIVE_VALUE = re.compile(r"^-(\d|\.\d)")
#: ``--flag=-1`` (joined by :func:`_join_negative_values`) -> ``--flag -1`` as the user typed it (messages).
_JOINED: dict[str, str] = {}


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
            _JOINED[out[-1]] = f"{tok} {argv[i + 1]}"
            i += 2
            continue
        out.append(tok)
        i += 1
    return out


#: Commands that run the dynamic model (and compile it on the first run).
SIMULATING = ("simulate", "demo", "reproduce", "fit", "plan", "sweep")


def _compile_notice() -> None:
    """One line on stderr when the integrator is about to be compiled (first run, empty or
    stale numba cache): 7-10 s of silence otherwise looks like a hang. Registered with the
    dynamics, so that it is printed only when a compile really starts (never before a usage error)."""
    from ..dynamics import BEFORE_COMPILE

    def notice() -> None:
        print("afmforce: compiling the integrator, ~10 s (first run; later runs load it from "
              "numba's cache; afmforce warmup compiles ahead)...", file=sys.stderr, flush=True)

    BEFORE_COMPILE[:] = [notice]


def _text_never_fails() -> None:
    """A file name that is not UTF-8 (its bytes kept as lone surrogates) is printed with the
    undecodable bytes escaped, never as a UnicodeEncodeError in the middle of the output."""
    for stream in (sys.stdout, sys.stderr):
        if getattr(stream, "errors", None) == "strict" and hasattr(stream, "reconfigure"):
            try:
                stream.reconfigure(errors="backslashreplace")
            except (ValueError, OSError):   # pragma: no cover - a stream that cannot change
                pass


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (argparse usage errors raise SystemExit(2))."""
    command_line = argv is None         # the afmforce process itself (not main() called from Python)
    argv = _join_negative_values(list(sys.argv[1:] if argv is None else argv))
    _text_never_fails()
    _outcome.start(argv)
    command = _command_of(argv)
    try:
        parser = build_parser(command)
        if _outcome.RunState.json and not command and "--version" in argv:
            print(json.dumps({"command": "afmforce", "exit_status": 0, "version": __version__}, indent=2))
            return 0
        if _outcome.RunState.json and ("-h" in argv or "--help" in argv):
            # --json always prints one JSON object: the help text as lines, exit status 0
            text = (_subparser(parser, command) if command else parser).format_help()
            print(json.dumps({"command": command or "afmforce", "exit_status": 0,
                              "help": text.splitlines()}, indent=2))
            return 0
        if command:
            refuse_empty_values(_subparser(parser, command), argv)
            _outcome.RunState.options = _option_strings(_subparser(parser, command))
        args = parser.parse_args(argv)
    except SystemExit:
        raise
    except Exception as exc:  # an empty value, or a command's register() failing: still one line (and JSON)
        if "--debug" in argv:
            raise
        return _outcome.fail(*_outcome.message_of(exc), _outcome.exit_status(exc))
    if not getattr(args, "func", None):
        if _outcome.RunState.json:
            return _outcome.fail("UsageError", "give a command (afmforce --help lists them)", EXIT_USAGE)
        parser.print_help()
        return EXIT_USAGE
    _outcome.RunState.generic_json = bool(getattr(args, "_generic_json", False))
    try:
        check_common(args)
        if command_line:                # its first run may use uncompiled kernels (cli/_firstrun.py)
            _firstrun.prepare(command, args, lambda text: print(text, file=sys.stderr, flush=True))
        if command in SIMULATING:
            _compile_notice()
        if _outcome.RunState.generic_json and _outcome.RunState.json:
            _outcome.capture_stdout()
        status = int(args.func(args) or 0)
    except BrokenPipeError:  # stdout closed early (afmforce ... | head): not an error of ours
        sys.stdout = open(os.devnull, "w")
        return 1
    except KeyboardInterrupt:
        return _outcome.fail("KeyboardInterrupt", "interrupted", 130)
    except SystemExit:
        _outcome.release_stdout()
        raise
    except Exception as exc:
        if args.debug:
            raise
        kind, message = _outcome.message_of(exc)
        return _outcome.fail(kind, message, _outcome.exit_status(exc))
    return _outcome.finish(command, status)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
