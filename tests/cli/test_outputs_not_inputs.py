"""An output named as one of the command's input files is refused before any work, even with
--force: ``afmforce calibrate thermal t.tnd --out t.tnd --force`` replaced the spectrum by its own
calibration JSON (audit), ``--plot t.tnd`` by a PNG; ``--out`` and ``--plot`` naming one file wrote
the one over the other."""

from __future__ import annotations

import hashlib
import shutil

import pytest

from afmforce import datasets
from afmforce.cli.main import main


def digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture()
def spectrum(tmp_path):
    path = tmp_path / "t.tnd"
    shutil.copy(datasets.thermal_example("jpk-water"), path)
    return path


def refused(capsys, argv, words):
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: ") and err.count("\n") == 1 and words in err, err


@pytest.mark.parametrize("flag", ["--out", "--plot"])
def test_calibrate_never_writes_over_its_spectrum(capsys, spectrum, flag):
    before = digest(spectrum)
    refused(capsys, ["calibrate", "thermal", str(spectrum), flag, str(spectrum), "--force"],
            f"{flag} {spectrum} is a file this command reads")
    assert digest(spectrum) == before


def test_calibrate_out_and_plot_name_one_file(capsys, spectrum, tmp_path):
    out = tmp_path / "c.json"
    refused(capsys, ["calibrate", "thermal", str(spectrum), "--out", str(out), "--plot", str(out)],
            "--out and --plot name the same file")
    assert not out.exists()


def test_fit_and_simulate_never_write_over_their_inputs(capsys, tmp_path):
    curves = [tmp_path / p.name for p in datasets.fit_example("speeds")[:2]]
    for p, src in zip(curves, datasets.fit_example("speeds")):
        shutil.copy(src, p)
    before = digest(curves[1])
    refused(capsys, ["fit", *map(str, curves), "--report", str(curves[1]), "--force"], "is a file this command reads")
    assert digest(curves[1]) == before
    cal = tmp_path / "c.json"
    assert main(["calibrate", "invols", "--example", "--out", str(cal)]) == 0
    capsys.readouterr()
    before = digest(cal)
    refused(capsys, ["simulate", "--probe-calibration", str(cal), "--raw", str(cal), "--force"],
            f"--raw {cal} is a file this command reads")
    assert digest(cal) == before
