"""Every ``afmforce ...`` line of the README's bash blocks runs as written (issue 24), and every
command the docs show (docs/*.md: bash blocks and inline `afmforce ...` spans) names a real command
and only flags it has, and parses as written (a renamed flag fails here, not in a user's shell).

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
        # a README example that warns (a simulation still in contact at its end: no pull-off) is one to fix
        assert "warning:" not in err, (argv, err)
        assert out.strip(), argv


DOC_PAGES = [README, *sorted((README.parent / "docs").glob("*.md"))]


def doc_command_lines() -> list[tuple[str, str, bool]]:
    """``(page, line, whole)`` of every ``afmforce`` command the docs show: each line of a ```bash
    block, continuation lines joined (``whole``: a command to type as it stands, unless it holds a
    placeholder, ``...`` or ``[--optional]``), and each inline `afmforce ...` span (a fragment)."""
    out = []
    for page in DOC_PAGES:
        text = page.read_text(encoding="utf-8")
        for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
            for ln in block.replace("\\\n", " ").splitlines():
                if ln.strip().startswith("afmforce "):
                    out.append((page.name, ln.strip(), True))
        for span in re.findall(r"`(afmforce [^`]*)`", text):
            out.append((page.name, span, False))
    return out


def _options(command: str) -> tuple[set[str], dict[str, set[str]]]:
    """The option strings of ``command`` and of each of its sub-commands (``calibrate thermal``)."""
    import argparse

    parser = build_parser(command)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    own, subs = set(), {}
    for action in sub._actions:
        own |= set(action.option_strings)
        if isinstance(action, argparse._SubParsersAction):
            subs = {name: {o for a in p._actions for o in a.option_strings} for name, p in action.choices.items()}
    return own, subs


def test_every_documented_command_names_a_command_and_its_flags():
    from afmforce.cli.main import COMMANDS

    lines = doc_command_lines()
    assert len(lines) > 150 and {page for page, _, _ in lines} >= {"README.md", "analysis.md", "fit.md"}
    options = {}
    bad = []
    for page, line, _ in lines:
        argv = shlex.split(line.replace("\\|", "|"), comments=True)[1:]
        if not argv or argv[0].startswith("-"):              # `afmforce --debug COMMAND`, `--version`
            continue
        for command in argv[0].rstrip(":").split("/"):       # `afmforce simulate/fit/plan --medium water`
            if command not in COMMANDS:
                bad.append(f"{page}: `{line}`: no command {command!r}")
                continue
            own, subs = options.setdefault(command, _options(command))
            allowed = own.union(*(subs[a] for a in argv[1:] if a in subs))
            bad += [f"{page}: `{line}`: {command} has no {a.split('=')[0]}" for a in argv[1:]
                    if a.startswith("--") and a.split("=")[0] not in allowed]
    assert not bad, "\n".join(bad)


def test_every_documented_command_line_parses_as_written(capsys):
    from afmforce.cli.main import _join_negative_values

    bad = []
    for page, line, whole in doc_command_lines():
        if not whole or "..." in line or " [" in line:
            continue
        argv = _join_negative_values(shlex.split(line, comments=True)[1:])
        try:
            build_parser(argv[0]).parse_args(argv)
        except SystemExit as stop:
            if stop.code:                                    # `--help` exits 0
                bad.append(f"{page}: `{line}`: {capsys.readouterr().err.strip()}")
    capsys.readouterr()
    assert not bad, "\n".join(bad)


#: Documented commands that warn on purpose: the page explains the warning (page: the command's start).
WARN_ON_PURPOSE = {
    # the Fig 1 spring's pull-off hangs on damping the model lacks (docs/dynamics.md, "Damping the model lacks")
    ("dynamics.md", "afmforce simulate --model spring --mass 10ug --spring-constant 0.21N/m"),
}


#: A user's file a documented command reads, as the shipped file that stands for it.
STAND_INS = {"spectrum.tnd": ("thermal", "jpk-water")}


def _self_contained(line: str) -> bool:
    """A documented command that reads no user file but STAND_INS: the simulation, statics, diagnosis,
    the calibration of shipped or virtual spectra (and the files earlier lines of its page wrote:
    `calibrate thermal spectrum.tnd --out calib.json`, then `--probe-calibration calib.json`)."""
    argv = shlex.split(line, comments=True)[1:]
    if argv[0] in ("simulate", "statics", "diagnose"):
        return not {"--config", "--instrument-config"} & set(argv)
    if argv[0] == "calibrate":
        return (argv[1] in ("sader", "virtual") or "--example" in argv
                or argv[1:3] in (["thermal", "beam.psd"], ["thermal", "spectrum.tnd"]))
    return argv[:2] == ["sweep", "--list-parameters"]


@pytest.mark.slow
def test_documented_commands_that_read_no_user_file_run_as_written_without_a_warning(tmp_path, monkeypatch, capsys):
    """Each page's self-contained commands, in order in one empty folder, as a user types them: exit 0,
    no error and no warning on stderr (a documented simulation that ends still in contact, 'no pull-off;
    lower end', is an example to fix), unless the page explains the warning (WARN_ON_PURPOSE)."""
    monkeypatch.chdir(tmp_path)
    ran, bad = [], []
    for page, line, whole in doc_command_lines():
        if page == "README.md" or not whole or "..." in line or " [" in line or not _self_contained(line):
            continue
        if "--help" in line.split():
            continue
        folder = tmp_path / page
        if not folder.is_dir():
            from afmforce import datasets

            folder.mkdir()
            for name, (kind, what) in STAND_INS.items():
                (folder / name).symlink_to(datasets.thermal_example(what) if kind == "thermal" else what)
        monkeypatch.chdir(folder)
        code = main(shlex.split(line, comments=True)[1:])
        err = capsys.readouterr().err
        ran.append(line)
        on_purpose = any(page == p and line.startswith(s) for p, s in WARN_ON_PURPOSE)
        if code != 0 or "error:" in err or ("warning:" in err and not on_purpose):
            bad.append(f"{page}: `{line}` -> exit {code}: {err.strip()[-300:]}")
    assert len(ran) >= 10, ran
    assert not bad, "\n".join(bad)


def test_documented_synopses_show_the_parsers_defaults():
    """A synopsis (`afmforce serve [--port 8765] [--session-ttl 24h] ...`, docs/web.md) shows each option's
    default: the one its parser declares (or, for a default computed at run time, the one its --help
    states from the declaration: afmforce.limits' storage bounds)."""
    import argparse

    checked = 0
    for page in DOC_PAGES:
        for block in re.findall(r"```bash\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S):
            synopsis = re.match(r"afmforce (\w+) \[", block)
            if not synopsis:
                continue
            command = synopsis.group(1)
            parser = build_parser(command)
            sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
            actions = {o: a for a in sub._actions for o in a.option_strings}
            for flag, shown in re.findall(r"\[(--[\w-]+) ([^\]\s]+)", block):
                if re.fullmatch(r"[A-Z_]+", shown):      # a placeholder: DIR, T
                    continue
                action = actions[flag]
                if isinstance(action, argparse._AppendAction):   # repeatable: the value is an example
                    continue
                default = action.default
                if default is None:
                    stated = re.search(r"\(default ([^;)\s]+)", action.help % {"default": None})
                    default = stated.group(1) if stated else None
                same = (str(default) == shown or (isinstance(default, (int, float))
                                                  and float(shown) == pytest.approx(default)))
                assert same, f"{page.name}: {flag} {shown} shown, the parser's default is {default!r}"
                checked += 1
    assert checked >= 7


@pytest.mark.slow
def test_fit_md_states_what_its_example_fit_gives(tmp_path, monkeypatch, capsys):
    """docs/fit.md's first command, `afmforce fit --example speeds --free hamaker,xi`, gives the xi its
    comment states (it said 0.011 +- 0.0005 kg/s; the fit gives 0.0104 +- 0.0006) and no warning (it
    warned that 1 of 2717 trial runs of the search had failed: nothing a user could act on)."""
    import json

    monkeypatch.chdir(tmp_path)
    line = next(ln for page, ln, whole in doc_command_lines()
                if page == "fit.md" and whole and ln.startswith("afmforce fit --example speeds"))
    value, se = map(float, re.search(r"xi = ([\d.]+) \+- ([\d.]+) kg/s", line).groups())
    assert main([*shlex.split(line, comments=True)[1:], "--no-profile", "--json"]) == 0   # the same fit
    cap = capsys.readouterr()
    xi = json.loads(cap.out)["parameters"]["xi"]
    assert abs(xi["value"] - value) <= 1e-4 and abs(xi["stderr"] - se) <= 1e-4, xi
    assert "warning:" not in cap.err, cap.err


def test_documented_console_sessions_print_what_they_show(tmp_path, monkeypatch, capsys):
    """A ``$ afmforce ...`` line of a docs block and the lines after it (docs/ranges.md's refused radius)
    are the command and its output, as typed in an empty folder (values are checked before any file is read)."""
    monkeypatch.chdir(tmp_path)
    sessions = []
    for page in DOC_PAGES:
        for block in re.findall(r"```[a-z]*\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S):
            for cmd, shown in re.findall(r"^\$ (afmforce [^\n]*)\n((?:(?!\$ )[^\n]*\n)*)", block, flags=re.M):
                sessions.append((page.name, cmd, shown.strip()))
    assert sessions
    for page, cmd, shown in sessions:
        try:
            main(shlex.split(cmd)[1:])
        except SystemExit:                                   # a usage error, as the shell sees it
            pass
        cap = capsys.readouterr()
        assert (cap.out + cap.err).strip() == shown, (page, cmd)


@pytest.mark.slow
def test_docs_liquid_chain_measures_the_double_layer_it_simulated(tmp_path, monkeypatch, capsys):
    """docs/liquid.md's chain, its first `simulate` recorded `--instrument liquid --raw l1.txt` then its
    `analyze l1.txt --steps liquid ...`, gives the simulated double layer. Before, the run (z0 0.35 nm:
    a 68 nN pull-off) never left the surface at its end, then, retracted further, clipped the photodiode
    (+-285 nm) over the whole retract: the step said "not applicable"; the README's water run, once it
    pulled off at 225 nm of deflection, gave psi -84 mV and 1/kappa 66 nm for -30 mV and 9.6 nm."""
    import json

    monkeypatch.chdir(tmp_path)
    lines = [ln for page, ln, whole in doc_command_lines() if page == "liquid.md" and whole]
    simulate = next(ln for ln in lines if ln.startswith("afmforce simulate --model spring"))
    analyze = next(ln for ln in lines if ln.startswith("afmforce analyze l1.txt --steps liquid"))
    argv = shlex.split(simulate, comments=True)[1:] + ["--instrument", "liquid", "--seed", "1", "--raw", "l1.txt"]
    assert main(argv) == 0 and "warning:" not in capsys.readouterr().err
    assert main(shlex.split(analyze, comments=True)[1:]) == 0
    res = json.loads(capsys.readouterr().out)["results"]["l1.txt"]
    assert not res.get("not_applicable"), res.get("not_applicable")
    assert res["debye_length"] == pytest.approx(10e-9, rel=0.05)              # the run's --debye-length
    assert res["dlvo_hamaker"] == pytest.approx(1e-20, rel=0.25)              # its --hamaker
    assert res["lever_drag"] == pytest.approx(1e-5, rel=0.1)                  # its --lever-drag
    # psi: the fit's known systematic (docs/liquid.md: "treat psi's and A's as lower bounds"), -24 mV here
    assert -0.030 * 1.05 < res["surface_potential"] < -0.030 * 0.7
