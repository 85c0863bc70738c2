"""``afmforce analyze``: a folder of files, outputs written atomically, bad files listed."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import pytest

from afmforce.cli.main import main

DATA = Path(__file__).resolve().parents[1] / "data"
FILES = ["asylum-mfp3d_SiN-tip_air.ibw", "jpk_calibration-curve_raw-volts.jpk-force",
         "bruker-nanoscope_synthetic.txt"]


@pytest.fixture()
def folder(tmp_path):
    d = tmp_path / "curves"
    d.mkdir()
    for name in FILES:
        shutil.copy(DATA / name, d / name)
    return d


def _digests(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir()}


def test_folder_analysis_writes_outputs_and_keeps_inputs(folder, tmp_path, capsys):
    before = _digests(folder)
    out = tmp_path / "out"
    assert main(["analyze", str(folder), "--out", str(out), "--no-plot"]) == 0
    assert _digests(folder) == before  # inputs untouched
    text = capsys.readouterr().out
    assert "pull-off F [nN]" in text and "asylum-mfp3d_SiN-tip_air.ibw" in text
    for name in FILES:
        result = json.loads((out / f"{name}.afmforce.json").read_text())
        assert result["units"]["jump_in_force"] == "N"
        assert (out / f"{name}.afmforce.csv").read_text().splitlines()[1].startswith("segment,time [s]")
    assert not list(out.glob(".*"))  # no temporary files left behind
    # finding 8: a rerun resumes (nothing recomputed, same tables), --force recomputes
    (table,) = out.glob("batch-*/summary.csv")
    first = table.read_text()
    stamps = {p.name: p.stat().st_mtime_ns for p in out.glob("*.afmforce.*")}
    assert main(["analyze", str(folder), "--out", str(out), "--no-plot"]) == 0
    assert table.read_text() == first and "failed" not in capsys.readouterr().err
    assert {p.name: p.stat().st_mtime_ns for p in out.glob("*.afmforce.*")} == stamps  # skipped
    assert main(["analyze", str(folder), "--out", str(out), "--no-plot", "--force"]) == 0
    assert all(p.stat().st_mtime_ns > stamps[p.name] for p in out.glob("*.afmforce.*"))  # recomputed
    assert table.read_text() == first


def test_a_missing_input_creates_no_output_folder(tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["analyze", str(tmp_path / "typo.ibw"), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert not out.exists() and "no such file" in err and len(err.strip().splitlines()) == 1


def test_json_is_one_object_when_the_first_file_fails(tmp_path, capsys):
    bad = tmp_path / "aaa.ibw"  # sorted first: its chunk has no rows
    bad.write_bytes(b"not an igor wave")
    code = main(["analyze", str(bad), str(DATA / "asylum-mfp3d_SiN-tip_air.ibw"), "--json"])
    payload = json.loads(capsys.readouterr().out)
    assert code == 1 and list(payload["results"]) == ["asylum-mfp3d_SiN-tip_air.ibw"]
    assert payload["failed"][0]["file"] == str(bad)
    res = payload["results"]["asylum-mfp3d_SiN-tip_air.ibw"]
    assert res["contact_kind"] == "hard" and res["adhesion_force"] < 0 and res["units"]["sensitivity"] == "m/V"


def test_shipped_examples_run(capsys):
    assert main(["analyze", "--example", "list"]) == 0
    assert "jpk-cell" in capsys.readouterr().out
    assert main(["analyze", "--example", "jpk-cell", "--json"]) == 0
    (res,) = json.loads(capsys.readouterr().out)["results"].values()
    assert res["contact_kind"] == "soft" and res["adhesion_force"] < 0
    assert main(["analyze", "--example", "nope"]) == 2


def test_figure_is_written(folder, tmp_path):
    out = tmp_path / "fig"
    assert main(["analyze", str(folder / FILES[0]), "--out", str(out)]) == 0
    assert (out / f"{FILES[0]}.afmforce.png").read_bytes()[:4] == b"\x89PNG"


def test_bad_files_are_listed_and_the_rest_analysed(folder, tmp_path, capsys):
    (folder / "broken.ibw").write_bytes(b"not an igor wave")
    (folder / "gel.txt").write_bytes((DATA / "ntmdt_gel-in-water.txt").read_bytes())  # needs k, s
    code = main(["analyze", str(folder), "--json"])
    captured = capsys.readouterr()
    assert code == 1
    payload = json.loads(captured.out)
    assert set(payload["results"]) == set(FILES)
    failed = {Path(f["file"]).name for f in payload["failed"]}
    assert failed == {"broken.ibw", "gel.txt"}
    assert "broken.ibw" in captured.err and "2 of 5" in captured.err


def test_user_metadata_flags(capsys):
    code = main(["analyze", str(DATA / "ntmdt_gel-in-water.txt"), "--spring-constant", "0.05N/m",
                 "--sensitivity", "61nm/V", "--json"])
    assert code == 0
    res = json.loads(capsys.readouterr().out)["results"]["ntmdt_gel-in-water.txt"]
    assert res["spring_constant"] == pytest.approx(0.05) and res["sensitivity"] == pytest.approx(61e-9)


def test_tilt_correction_flag(capsys):
    code = main(["analyze", str(DATA / FILES[0]), "--theta0", "-15deg", "--calibration", "metadata", "--json"])
    assert code == 0
    res = json.loads(capsys.readouterr().out)["results"][FILES[0]]
    assert res["spring_constant"] == pytest.approx(1.1841 * 1.0718, rel=1e-3)  # eq 14


@pytest.mark.parametrize("argv", [["analyze"], ["analyze", "x.ibw", "--steps", "nope"],
                                  ["analyze", "x.ibw", "--spring-constant", "3 nm"]])
def test_usage_errors_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        code = main(argv)
        raise SystemExit(code)
    assert exc.value.code == 2


@pytest.mark.parametrize("option, words", [
    ("vdw.max_separation=-5nm", ["--option vdw.max_separation", "out of range", "um"]),
    ("vdw.max_separation=5nN", ["--option vdw.max_separation", "length"]),
    ("jumps.nsigmaa=4", ["unknown option", "nsigma"]),
    ("vwd.z0=1nm", ["unknown step", "vdw"]),
    ("fringes.apply=sometimes", ["fringes.apply", "auto, always, never"]),
    ("smooth.window=4", ["smooth.window", "odd"]),
])
def test_bad_step_options_exit_2_with_one_line_before_any_work(option, words, tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["analyze", str(DATA / FILES[0]), "--out", str(out), "--option", option])
    assert code == 2 and not out.exists()
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    for w in words:
        assert w in err


def test_option_flag_matches_the_library_records(capsys):
    """``--option`` (units parsed) gives the numbers of the records in Python; the short forms agree."""
    from afmforce.analysis.options import ProbeCalibration, VdwOptions, ZeroOptions
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load

    assert main(["analyze", str(DATA / FILES[0]), "--json", "--radius", "20nm", "--option", "vdw.max_separation=20nm",
                 "--option", "zero.contact_separation=0nm"]) == 0
    cli = json.loads(capsys.readouterr().out)["results"][FILES[0]]
    lib = analyze(load(DATA / FILES[0])[0], options=[VdwOptions(max_separation=20e-9),
                                                      ZeroOptions(contact_separation=0.0)],
                  probe=ProbeCalibration(radius=20e-9))
    assert cli["hamaker_radius"] == lib.hamaker_radius and cli["hamaker"] == lib.hamaker
    assert cli["contact_separation"] == 0.0
    assert cli["details"]["vdw"]["separation_max"] <= 20e-9
    assert main(["analyze", str(DATA / FILES[0]), "--contact-separation", "0nm", "--option",
                 "zero.contact_separation=0nm"]) == 2  # one option, two flags: refused
    assert "set the same option" in capsys.readouterr().err


def test_table_sensitivity_is_the_one_used_and_agrees_with_json_and_figure(tmp_path, capsys):
    """The table showed the file's sensitivity where the fitted one was used (Asylum SiN: 44.99 nm/V in the
    table, forces with 96.4): the column is the sensitivity used, tagged fit/file/user, equal to the JSON's
    ``sensitivity_used`` and to the calibration factor the forces were computed with, and the figure's.
    By default the Asylum curve uses its wave note's InvOLS (read with igor2); `--calibration fit` the
    compliance slope's (the "sens. fit" column, reported either way)."""
    import re

    from afmforce.analysis.options import CalibrationOptions
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load
    from afmforce.plotting import plot_summary
    from realdata import wave_note

    files = [str(DATA / "asylum-mfp3d_SiN-tip_air.ibw"), str(DATA / "bruker-nanoscope_synthetic.txt")]
    invols = float(wave_note(files[0])["InvOLS"])
    for extra, tag_asylum in (((), "file"), (("--calibration", "fit"), "fit")):
        assert main(["analyze", *files, *extra]) == 0
        lines = capsys.readouterr().out.splitlines()
        head = re.split(r"\s{2,}", lines[0].strip())
        col, col_fit = head.index("sens. used [nm/V]"), head.index("sens. fit [nm/V]")
        rows = {re.split(r"\s{2,}", line.strip())[0]: re.split(r"\s{2,}", line.strip()) for line in lines[1:3]}
        assert main(["analyze", *files, *extra, "--json"]) == 0
        payload = json.loads(capsys.readouterr().out)["results"]
        tags = (("asylum-mfp3d_SiN-tip_air.ibw", tag_asylum),
                ("bruker-nanoscope_synthetic.txt", "fit" if extra else "file"))
        for name, tag in tags:
            res = payload[name]
            used = res["sensitivity_fit"] if tag == "fit" else res["sensitivity"]
            assert res["calibration_source"] == ("fit" if tag == "fit" else "metadata")
            assert res["sensitivity_used"] == pytest.approx(used) and res["units"]["sensitivity_used"] == "m/V"
            assert rows[name][col] == f"{used * 1e9:.4g} ({tag})"
            assert rows[name][col_fit] == f"{res['sensitivity_fit'] * 1e9:.4g}"
        asylum = payload["asylum-mfp3d_SiN-tip_air.ibw"]
        if tag_asylum == "file":
            assert asylum["sensitivity_used"] == pytest.approx(invols, rel=1e-12)   # the wave note's
        else:
            assert asylum["sensitivity_used"] > 2 * invols                         # the slope's, asked for
    curve = load(DATA / "asylum-mfp3d_SiN-tip_air.ibw")[0]
    for source, tag in (("auto", "the file's"), ("fit", "fit")):
        res = analyze(curve, options=[CalibrationOptions(source=source)])
        cal = res.details["calibration"]  # the signal is in newtons: the forces' factor scales as the sensitivity
        assert cal.factor / cal.factor_given == pytest.approx(res.sensitivity_used / res.sensitivity)
        title = plot_summary(res, curve).axes[0].get_title()
        assert f"{res.sensitivity_used * 1e9:.4g} nm/V" in title and tag in title
    assert main(["analyze", files[1], "--sensitivity", "50nm/V"]) == 0
    assert "50 (user)" in capsys.readouterr().out
