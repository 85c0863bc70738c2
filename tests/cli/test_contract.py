"""The command-line contract of issue 24, in every command (afmforce.cli._outcome).

Every bad invocation the issue lists, and one of each kind for every command: exit status 2 for
usage errors and 1 for failures, exactly one line on stderr, no traceback, and with ``--json``
exactly one JSON object on stdout (``{"error": {"type", "message"}}``). Then: a rerun of
``analyze`` into the same ``--out`` with other options never replaces the first run's files,
every file written is named, and the automatic executor of a batch never picks a cluster on a
machine without a free core.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from afmforce.cli.main import COMMANDS, build_parser, main

DATA = Path(__file__).resolve().parents[1] / "data"
CURVE = DATA / "bruker-ascii_nm_retract-reversed.txt"


@pytest.fixture()
def odd_files(tmp_path):
    """A binary file, a UTF-16 text file and a folder, where a text file is expected."""
    (tmp_path / "binary.toml").write_bytes(bytes(range(256)) * 4)
    (tmp_path / "utf16.toml").write_bytes('[grid]\nxi = "0.1,0.2"\n'.encode("utf-16"))
    (tmp_path / "folder").mkdir()
    return tmp_path


def run(capsys, argv):
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own usage errors
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def check_error(capsys, argv, status, words=""):
    """One stderr line (``error: ...``), no traceback, the exit status; with --json one error object."""
    code, out, err = run(capsys, argv)
    assert code == status, (argv, err)
    assert err.count("\n") == 1 and err.startswith("error: ") and "Traceback" not in err, err
    assert words in err, err
    assert out == ""
    code, out, err = run(capsys, [*argv, "--json"])
    assert code == status and err.count("\n") == 1 and "Traceback" not in err, err
    obj = json.loads(out)  # exactly one JSON value, and it is an object
    assert set(obj) == {"error"} and obj["error"]["message"] in err and obj["error"]["type"]
    return obj["error"]


# the issue's list (and a few of the same kinds): argv with {tmp} for the odd_files folder
ISSUE_CASES = [
    (["sweep", "--config", "{tmp}/binary.toml", "--out", "{tmp}/o"], 2, "not a UTF-8 text file"),
    (["sweep", "--config", "{tmp}/utf16.toml", "--out", "{tmp}/o"], 2, "not a UTF-8 text file"),
    (["sweep", "--config", "{tmp}/folder", "--out", "{tmp}/o"], 2, "is a folder"),
    (["simulate", "--instrument-config", "{tmp}/binary.toml", "--raw", "{tmp}/r.txt"], 1, "not a UTF-8 text file"),
    (["simulate", "--instrument-config", "{tmp}/folder", "--raw", "{tmp}/r.txt"], 1, "is a folder"),
    (["plan", "--report", "{tmp}/folder", "--force"], 2, "is a folder"),
    (["fit", str(CURVE), str(CURVE), "--out", "{tmp}/folder", "--force"], 2, "is a folder"),
    (["plan", "--force-error", "-1"], 2, "--force-error -1 is out of range: force_error"),
    (["plan", "--noise", "0nm"], 2, "--noise 0nm is out of range: deflection_noise"),
    (["plan", "--speeds", "1um/s,1e9um/s"], 2, "must lie in [0.1 nm/s, 10 mm/s]"),
    (["plan", "--speeds", ""], 2, "--speeds: empty value"),
    (["plan", "--speeds", ","], 2, "--speeds: empty list"),
    (["fit", str(CURVE), "--velocities", "1um/s,,2um/s"], 2, "an empty value between commas"),
    (["sweep", "--range", "xi=1:0", "--n", "4", "--out", "{tmp}/o"], 2, "the low end must lie below"),
    (["sweep", "--grid", "xi=0.1,0.2", "--workers", "0", "--out", "{tmp}/o"], 2, "--workers must be at least 1"),
    (["analyze", str(CURVE), "--workers", "0"], 2, "--workers must be at least 1"),
    (["analyze", str(CURVE), "--chunk-size", "0"], 2, "--chunk-size must be at least 1"),
    (["reproduce", "--only", "", "--out", "{tmp}/o"], 2, "--only: empty value"),
    (["reproduce", "--only", ",", "--out", "{tmp}/o"], 2, "no figure named"),
    (["analyze", str(CURVE), "--out", ""], 2, "--out: empty value"),
    (["analyze", str(CURVE), "--out="], 2, "--out: empty value"),
    (["simulate", "--out", ""], 2, "--out: empty value"),
    (["sweep", "--grid", "xi=0.1", "--out", ""], 2, "--out: empty value"),
    (["fit", str(CURVE), "--out", ""], 2, "--out: empty value"),
    (["analyze", ""], 2, "an empty argument"),
    (["analyze", "{tmp}/typo.ibw"], 2, "no such file"),
    (["fit", "{tmp}/typo.txt", "{tmp}/typo2.txt"], 2, "no such file"),
    (["fit"], 2, "--example speeds"),
    (["fit", "--example", "nope"], 2, "unknown"),
    (["analyze", "--example", "nope"], 2, "unknown"),
    (["sweep", "--example", "--config", "{tmp}/utf16.toml"], 2, "not both"),
    (["simulate", "--velocity", "5nN"], 2, "--velocity expects a speed"),
    (["bogus-command"], 2, "invalid choice"),
]


@pytest.mark.parametrize("argv,status,words", ISSUE_CASES, ids=lambda v: " ".join(v) if isinstance(v, list) else None)
def test_bad_invocation_is_one_line_exit_status_and_json(odd_files, capsys, monkeypatch, argv, status, words):
    monkeypatch.chdir(odd_files)
    argv = [a.replace("{tmp}", str(odd_files)) for a in argv]
    check_error(capsys, argv, status, words)
    assert not (odd_files / "o").exists()  # refused before any work or output


#: For every command: an option it does not have (argparse) and a value out of range (our checks).
PER_COMMAND = {
    "demo": ["--out", "{tmp}/binary.toml"],
    "statics": ["--k0", "-1N/m"],
    "diagnose": ["--radius", "-5nm"],
    "simulate": ["--xi", "1e9kg/s"],
    "analyze": ["--example", "asylum-air", "--radius", "0nm"],
    "sweep": ["--grid", "xi=1e9", "--out", "{tmp}/o"],
    "reproduce": ["--only", "fig99", "--out", "{tmp}/o"],
    "formats": ["--no-such-flag"],
    "fit": ["--example", "speeds", "--level", "2"],
    "plan": ["--speeds", "1e9um/s"],
    "serve": ["--max-upload", "0MB"],
    "warmup": ["--only", "everything"],
    "calibrate": ["sader", "--length", "-5um", "--width", "1um", "--frequency", "1kHz", "--quality-factor", "2"],
}


@pytest.mark.parametrize("argv", [["serve", "--port", "70000"], ["serve", "--budget", "-1"],
                                  ["serve", "--max-upload", "lots"], ["serve", "--session-storage", "0"],
                                  ["serve", "--server-storage", "lots"]])
def test_serve_refuses_bad_values_before_listening(argv, odd_files, capsys, monkeypatch):
    monkeypatch.chdir(odd_files)
    check_error(capsys, argv, 2)


def test_every_command_is_covered():
    assert set(PER_COMMAND) == set(COMMANDS)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_json_on_error_for_every_command(command, odd_files, capsys, monkeypatch):
    monkeypatch.chdir(odd_files)
    assert "--json" in build_parser(command)._subparsers._group_actions[0].choices[command]._option_string_actions
    check_error(capsys, [command, "--no-such-option"], 2, "unrecognized arguments")
    bad = [a.replace("{tmp}", str(odd_files)) for a in PER_COMMAND[command]]
    check_error(capsys, [command, *bad], 2)


def test_unexpected_exceptions_are_one_line_exit_1_and_json(capsys, monkeypatch):
    import afmforce.cli.formats as formats

    def boom(*a, **k):
        raise KeyError("surprise")

    monkeypatch.setattr("afmforce.io.formats_table", boom)
    error = check_error(capsys, ["formats"], 1, "unexpected KeyError")
    assert error["type"] == "KeyError" and "--debug" in error["message"]
    with pytest.raises(KeyError):
        main(["--debug", "formats"])
    assert formats  # the command module was the one run


def test_commands_without_a_json_result_print_one_object(tmp_path, capsys, monkeypatch):
    """sweep/reproduce have no JSON result of their own: exit status, text and files written."""
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, ["sweep", "--grid", "velocity=1um/s", "--set", "xi=0.1kg/s", "--set", "start=-20nm",
                                  "--serial", "--out", "o", "--json"])
    assert code == 0
    obj = json.loads(out)
    assert obj["exit_status"] == 0 and obj["command"] == "sweep"
    html = [w for w in obj["wrote"] if w.endswith("results.html")] or [
        f"{w}/results.html" for w in obj["wrote"] if (tmp_path / w / "results.html").is_file()]
    assert len(html) == 1 and (tmp_path / html[0]).is_file()
    assert any("results.html" in line for line in obj["output"])


def test_json_is_one_object_for_listings(capsys):
    code, out, _ = run(capsys, ["analyze", "--example", "list", "--json"])
    assert code == 0 and "asylum-air" in json.loads(out)["examples"]
    code, out, _ = run(capsys, ["formats", "--json"])
    assert code == 0 and isinstance(json.loads(out)["formats"], list)
    code, out, _ = run(capsys, ["sweep", "--list-parameters", "--json"])
    obj = json.loads(out)
    assert code == 0 and obj["exit_status"] == 0 and any("velocity" in line for line in obj["output"])


def test_every_file_written_is_named(tmp_path, capsys):
    argv = ["simulate", "--model", "spring", "--start=-20nm", "--turn", "-5nm", "--end=-20nm", "--check", "off",
            "--out", str(tmp_path / "t.csv"), "--plot", str(tmp_path / "t.png"),
            "--instrument", "ideal", "--raw", str(tmp_path / "r.txt")]
    code, out, err = run(capsys, argv)
    assert code == 0
    for name in ("t.csv", "t.png", "r.txt"):
        assert (tmp_path / name).is_file() and f"wrote {tmp_path / name}\n" in out
    code, out, err = run(capsys, [*argv, "--force", "--json"])
    assert code == 0 and "wrote" not in out and f"wrote {tmp_path / 't.csv'}" in err  # stdout: JSON only
    json.loads(out)


def _digests(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.glob("*.afmforce.*")}


def test_analyze_rerun_with_other_options_never_replaces_the_first_runs_files(tmp_path, capsys):
    out = tmp_path / "out"
    first = ["analyze", str(CURVE), "--out", str(out), "--no-plot", "--steps", "jumps"]
    assert run(capsys, first)[0] == 0
    before = _digests(out)
    assert set(before) == {f"{CURVE.name}.afmforce.json", f"{CURVE.name}.afmforce.csv"}
    summaries = sorted(out.glob("batch-*/summary.csv"))
    other = first[:-2] + ["--option", "jumps.nsigma=6"]
    error = check_error(capsys, other, 2, "--force")
    assert "other options" in error["message"]
    assert _digests(out) == before and sorted(out.glob("batch-*/summary.csv")) == summaries
    assert run(capsys, first)[0] == 0 and _digests(out) == before  # the same options: resumes
    assert run(capsys, other + ["--force"])[0] == 0                  # asked for: replaced
    after = json.loads((out / f"{CURVE.name}.afmforce.json").read_text())
    assert after["analysis_settings"] != json.loads(before[f"{CURVE.name}.afmforce.json"])["analysis_settings"]


def test_each_failed_file_is_one_stderr_line(tmp_path, capsys):
    bad = [tmp_path / "a.txt", tmp_path / "b.txt"]
    for p in bad:
        p.write_text("not a force curve\n")
    code, _, err = run(capsys, ["analyze", str(bad[0]), str(CURVE)])
    assert code == 1 and err.count("\n") == 1 and err.startswith(f"failed: {bad[0]}:")
    code, _, err = run(capsys, ["analyze", *map(str, bad), str(CURVE)])
    lines = err.splitlines()
    assert code == 1 and len(lines) == 3 and lines[-1] == "2 of 3 file(s) failed"


def test_automatic_executor_is_serial_without_a_free_core(monkeypatch):
    """72 files at a load of 10 on 2 cores: 32 s serial, 58 s on the Dask cluster the old rule picked
    (benchmarks/bench_executor.py)."""
    from afmforce.sweep import files

    refs = files.plan_curves([CURVE] * 3)
    monkeypatch.setattr(os, "getloadavg", lambda: (10.0, 10.0, 10.0))
    plan, workers = files.choose_executor(refs, files.CurveAnalysis(steps=("jumps",)), workers=2)
    assert (plan.executor, workers, plan.seconds_per_run) == ("serial", 1, None)  # no timing needed
    assert "load 10.0" in plan.reason
    # two free cores: the measured cost decides; three cheap curves never pay for a cluster start
    monkeypatch.setattr(os, "getloadavg", lambda: (0.0, 0.0, 0.0))
    plan, workers = files.choose_executor(refs, files.CurveAnalysis(steps=("jumps",)), workers=2)
    assert workers == 2 and plan.seconds_per_run > 0
    assert plan.executor == ("serial" if plan.serial_estimate <= plan.cluster_estimate else "dask") == "serial"
    assert plan.cluster_estimate >= files.ANALYSIS_CLUSTER_START


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_help_with_json_is_one_object(command, capsys):
    """`--help --json` prints the help as one JSON object (it printed the text before)."""
    code, out, _ = run(capsys, [command, "--help", "--json"])
    obj = json.loads(out)
    assert code == 0 and obj["exit_status"] == 0 and obj["command"] == command
    assert obj["help"][0].startswith(f"usage: afmforce {command}")
    code, out, _ = run(capsys, ["--json", "-h"])
    assert code == 0 and any(command in line for line in json.loads(out)["help"])
