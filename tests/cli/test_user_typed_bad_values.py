"""Every command as a user types it on a real file, with obviously bad values: one readable line on stderr,
exit status 2, no traceback, nothing written (faces sweep, 2026-11-29).

Was: ``analyze FILE --velocity 0`` answered ``unrecognized arguments`` without saying that analyze takes a
file's speed as ``--meta velocity=VALUE``; ``analyze MAP --fast-map`` on a real JPK map without a tip radius
printed one ``failed:`` line per pixel (16 for a 4 x 4 map, 16,384 for a QI map), the key written
`` `tip_radius` `` instead of the flag."""

from __future__ import annotations

import pytest

from afmforce.cli.main import main
from realdata import real_file

CURVE = "asylum-mfp3d_SiN-tip_air.ibw"
MAP = "jpk-force-map_HeLa_4x4.jpk-force-map"

BAD = [
    # (argv with {f} for the real curve, what the one line must say)
    (["analyze", "{f}", "--spring-constant", "-1"], "--spring-constant -1 is out of range"),
    (["analyze", "{f}", "--tip-radius", "1e9m"], "--tip-radius 1e9m is out of range"),
    (["analyze", "{f}", "--velocity", "0"], "takes file metadata as --meta velocity=VALUE"),
    (["analyze", "{f}", "--meta", "velocity=0"], "velocity 0 is out of range"),
    (["analyze", "{f}", "--tip-raduis", "5nm"], "did you mean --tip-radius?"),
    (["fit", "{f}", "--spring-constant", "-1"], "--spring-constant -1 is out of range"),
    (["fit", "{f}", "--velocity", "0"], "takes file metadata as --meta velocity=VALUE"),
    (["fit", "{f}", "--tip-radius", "1e9m"], "did you mean --radius?"),
    (["diagnose", "--spring-constant", "-1"], "--spring-constant -1 is out of range"),
    (["diagnose", "--velocity", "0"], "--velocity 0 is out of range"),
    (["simulate", "--spring-constant", "-1"], "--spring-constant -1 is out of range"),
    (["simulate", "--velocity", "0"], "--velocity 0 is out of range"),
    (["statics", "--velocity", "0"], "--velocity 0 is out of range"),
    (["plan", "--velocity", "0"], "unrecognized arguments"),
    (["calibrate", "invols", "{f}", "--spring-constant", "-1"], "an option of another method of this command"),
    (["calibrate", "thermal", "{f}", "--temperature", "-1K"], "--temperature -1K is out of range"),
]


@pytest.mark.parametrize("argv,words", BAD, ids=[" ".join(a).replace("{f}", "FILE") for a, _ in BAD])
def test_a_bad_value_is_one_line_and_writes_nothing(capsys, tmp_path, monkeypatch, argv, words):
    f = str(real_file(CURVE))
    monkeypatch.chdir(tmp_path)
    try:
        code = main([a.format(f=f) for a in argv])
    except SystemExit as exc:        # argparse's usage errors: exit status 2
        code = exc.code
    captured = capsys.readouterr()
    err = [e for e in captured.err.strip().splitlines() if not e.startswith("afmforce: first run")]
    assert code == 2 and len(err) == 1 and not captured.out, (code, err, captured.out[:200])
    assert err[0].startswith("error: ") and words in err[0] and "Traceback" not in err[0], err[0]
    assert not list(tmp_path.iterdir())


def test_a_fast_map_whose_pixels_all_fail_alike_says_it_once(capsys, tmp_path, monkeypatch):
    path = real_file(MAP)
    monkeypatch.chdir(tmp_path)
    assert main(["analyze", str(path), "--fast-map", "--serial"]) == 1
    err = [e for e in capsys.readouterr().err.strip().splitlines() if not e.startswith("afmforce: first run")]
    failed = [e for e in err if e.startswith("failed:")]
    assert len(failed) == 1, err
    assert f"{path} (16 curves)" in failed[0] and "--tip-radius" in failed[0] and "`" not in failed[0]
    assert err[-1] == "16 of 16 curves failed"


def test_an_unknown_flag_with_a_negative_value_is_echoed_as_typed(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["statics", "--spring-constant", "-1"])
    err = capsys.readouterr().err.strip()
    assert exc.value.code == 2 and err.startswith("error: unrecognized arguments: --spring-constant -1"), err
