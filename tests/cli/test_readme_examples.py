"""Every ``afmforce ...`` line of the README's bash blocks runs as written (issue 24).

The lines run in order in one empty folder (a later line may read what an earlier one wrote:
``simulate --raw run.txt`` then ``analyze run.txt``), in this process. Commands that take
tens of seconds (fit, plan, sweep, reproduce, demo, warmup: 10-120 s each on the 2-core
machine) are parsed and their input files checked here; ``AFMFORCE_README_FULL=1`` runs them
too (``AFMFORCE_README_FULL=1 pytest tests/cli/test_readme_examples.py``, a few minutes).
The Python blocks of the README are not run here (tests/test_docs_tables.py reads its raw text
example).
"""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path

import pytest

from afmforce.cli.main import build_parser, main

README = Path(__file__).resolve().parents[2] / "README.md"
SLOW = ("fit", "plan", "sweep", "reproduce", "demo", "warmup")
#: Commands that run until stopped (a server): parsed only, even with AFMFORCE_README_FULL=1.
SERVERS = ("serve",)
FULL = os.environ.get("AFMFORCE_README_FULL") == "1"


def readme_commands() -> list[list[str]]:
    """argv of every ``afmforce`` line of the README's ```bash blocks (comments dropped)."""
    blocks = re.findall(r"```bash\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    lines = [ln.strip() for block in blocks for ln in block.splitlines()]
    return [shlex.split(ln, comments=True)[1:] for ln in lines if ln.startswith("afmforce ")]


def test_the_readme_shows_every_command_with_runnable_examples():
    commands = readme_commands()
    names = {argv[0] for argv in commands}
    assert {"analyze", "fit", "sweep", "simulate", "statics", "diagnose", "reproduce",
            "formats", "plan"} <= names
    assert all("..." not in argv for argv in commands)
    assert len(README.read_text().splitlines()) < 200  # short: the details live in docs/


def test_every_readme_command_runs_as_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    for argv in readme_commands():
        if argv[0] in SERVERS:
            build_parser(argv[0]).parse_args(argv)  # a usage error would raise SystemExit
            continue
        if argv[0] in SLOW and not FULL:
            args = build_parser(argv[0]).parse_args(argv)  # a usage error would raise SystemExit
            files = [Path(f) for f in args.curves] if argv[0] == "fit" else []
            if getattr(args, "example", None):
                from afmforce import datasets

                files += datasets.fit_example(args.example) if argv[0] == "fit" else [datasets.SWEEP_EXAMPLE]
            assert all(f.is_file() for f in files), argv
            continue
        code = main(argv)
        out, err = capsys.readouterr()
        assert code == 0, (argv, err)
        assert "Traceback" not in err and "error:" not in err, (argv, err)
        assert out.strip(), argv
