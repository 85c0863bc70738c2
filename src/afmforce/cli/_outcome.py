"""The command line's contract, in one place (used by :mod:`afmforce.cli.main`).

Every command, in every outcome:

* an error is one readable line on stderr (``error: ...``), never a traceback
  unless ``--debug``;
* the exit status is 0 on success, 2 for usage errors (a bad flag or value, a
  missing input, an output that exists) and 1 for failures (an unreadable file,
  a failed analysis or solve, anything unexpected);
* with ``--json`` stdout holds exactly one JSON object: the command's result,
  or ``{"error": {"type": ..., "message": ...}}``; commands without a JSON
  result of their own print ``{"command", "exit_status", "output", "wrote"}``;
* every file written (through :mod:`afmforce._files`) is named: ``wrote PATH``
  (on stdout, or stderr under ``--json``), grouped per folder when many.

Nothing here imports numpy.
"""

from __future__ import annotations

import io
import json
import sys
from pathlib import Path

from .. import _files
from ..errors import AfmforceError, MissingMetadataError, OutputExistsError, ParameterError, render_keys

EXIT_OK, EXIT_FAILURE, EXIT_USAGE = 0, 1, 2
#: Files named one per line up to this many per folder; more are one line for the folder.
_LISTED_PER_FOLDER = 4


class RunState:
    """What one run of ``afmforce`` wrote and how it reports (reset by :func:`start`)."""

    json = False              # --json on the command line
    generic_json = False      # the command has no JSON result of its own: we print one
    debug = False
    written: list[Path] = []
    reported: list[Path] = []  # files or folders the command named itself
    captured: io.StringIO | None = None
    stdout = None              # sys.stdout while captured
    flags: dict[str, str] = {}  # this command's own way to give a quantity (fit: --meta spring_constant=...)
    options: frozenset = frozenset()  # the option strings of the command being run (set by main)


#: Quantity key (the `` `key` `` of a library message) -> how the command line gives it, where that
#: is not ``--`` + the key with dashes (``spring_constant`` -> ``--spring-constant``).
FLAGS: dict[str, str] = {"n_curves": "--curves", "ranges": "--range", "sets": "--set", "store": "--out",
                         "meta_override": "--meta", "format": "--format"}


def flag_of(key: str) -> str:
    """The command-line form of quantity ``key`` in this command: its own flag, or, for a file's
    metadata key the command has no flag for, ``--meta KEY=VALUE``."""
    if key in RunState.flags or key in FLAGS:
        return RunState.flags.get(key) or FLAGS[key]
    if "." in key:                       # a step option: STEP.NAME
        return f"--option {key}"
    flag = "--" + key.replace("_", "-")
    if RunState.options and flag not in RunState.options and "--meta" in RunState.options:
        from ..io import METADATA

        if key in METADATA:
            return f"--meta {key}=VALUE"
    return flag


def render(text: str) -> str:
    """A library message as the command line shows it: each `` `key` `` as its flag."""
    return render_keys(text, flag_of)


def start(argv: list[str]) -> None:
    """Reset the state for a run of ``argv`` and listen for written files."""
    RunState.json = "--json" in argv
    RunState.debug = "--debug" in argv
    RunState.generic_json = False
    RunState.written = []
    RunState.reported = []
    RunState.captured = None
    RunState.flags = {}
    RunState.options = frozenset()
    if _note_written not in _files.LISTENERS:
        _files.LISTENERS.append(_note_written)


def _note_written(path) -> None:
    RunState.written.append(Path(path))


def reported(*paths) -> None:
    """The command named these files or folders itself: :func:`finish` does not list them again."""
    RunState.reported.extend(Path(p) for p in paths if p)


def exit_status(exc: BaseException) -> int:
    """2 for usage errors (the user can fix the command line), 1 for failures."""
    if isinstance(exc, (ParameterError, OutputExistsError, MissingMetadataError)):
        return EXIT_USAGE
    return EXIT_FAILURE


def one_line(text: str) -> str:
    return " ".join(str(text).split()) or "(no message)"


def message_of(exc: BaseException) -> tuple[str, str]:
    """``(type, readable one-line message)`` of any exception."""
    if isinstance(exc, AfmforceError):
        return type(exc).__name__, one_line(render(str(exc)))
    if isinstance(exc, UnicodeDecodeError):
        return "FileFormatError", f"not a text file in {exc.encoding} ({one_line(exc.reason)} at byte {exc.start})"
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        return type(exc).__name__, one_line(f"{where}{exc.strerror or exc}")
    if isinstance(exc, MemoryError):
        return "MemoryError", "out of memory; use fewer or smaller inputs"
    return type(exc).__name__, one_line(f"unexpected {type(exc).__name__}: {exc} (a bug: rerun with --debug "
                                        "and report the traceback)")


def fail(kind: str, message: str, status: int) -> int:
    """Report an error: one line on stderr, the error object on stdout under ``--json``."""
    release_stdout()
    RunState.written, RunState.reported = [], []
    print(f"error: {message}", file=sys.stderr, flush=True)
    if RunState.json:
        try:
            print(json.dumps({"error": {"type": kind, "message": message, "exit_status": status}}), flush=True)
        except OSError:     # stdout itself cannot be written (a full disk, /dev/full): the stderr line stands
            _drop_stdout()
    return status


def _drop_stdout() -> None:
    """Send the rest of stdout to the null device (a write that failed leaves its text buffered: the
    interpreter's flush at exit would fail again and print a traceback)."""
    import os

    try:
        sys.stdout = open(os.devnull, "w")
    except OSError:
        pass


def capture_stdout() -> None:
    """Under ``--json`` for a command without a JSON result: keep its text for the JSON object."""
    RunState.captured, RunState.stdout = io.StringIO(), sys.stdout
    sys.stdout = RunState.captured


def release_stdout() -> str:
    text = ""
    if RunState.captured is not None:
        text = RunState.captured.getvalue()
        if sys.stdout is RunState.captured:
            sys.stdout = RunState.stdout
        RunState.captured = None
    return text


def _unreported() -> list[Path]:
    done = [p.resolve() for p in RunState.reported]
    out = []
    for path in dict.fromkeys(RunState.written):
        full = path.resolve()
        if not any(full == d or d in full.parents for d in done):
            out.append(path)
    return out


def written_lines() -> list[str]:
    """``wrote PATH`` lines for the files not named by the command, grouped per folder when many."""
    by_folder: dict[Path, list[Path]] = {}
    for path in _unreported():
        by_folder.setdefault(path.parent, []).append(path)
    lines = []
    for folder, paths in by_folder.items():
        if len(paths) <= _LISTED_PER_FOLDER:
            lines += [f"wrote {p}" for p in paths]
        else:
            names = ", ".join(p.name for p in paths[:3])
            lines.append(f"wrote {len(paths)} files to {folder}/ ({names}, ...)")
    return lines


def finish(command: str, status: int) -> int:
    """After a command returned: name the files written; print the generic JSON object."""
    text = release_stdout()
    lines, written = written_lines(), [str(p) for p in dict.fromkeys(RunState.written)]
    RunState.written, RunState.reported = [], []  # a long-lived process (tests, notebooks) keeps nothing
    if RunState.generic_json and RunState.json:
        print(json.dumps({"command": command, "exit_status": status, "output": text.splitlines(),
                          "wrote": written}, indent=2))
        return status
    for line in lines:
        print(line, file=sys.stderr if RunState.json else sys.stdout)
    return status
