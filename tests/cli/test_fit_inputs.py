"""`afmforce fit` reads folders as `afmforce analyze` does (audit: `afmforce fit FOLDER` answered
"no such file: FOLDER" for a folder that exists, the way users keep one speed per file)."""

from __future__ import annotations

import json
import shutil

from afmforce import datasets
from afmforce.cli.main import main


def test_fit_reads_every_curve_file_of_a_folder(tmp_path, capsys):
    speeds = tmp_path / "speeds"
    speeds.mkdir()
    files = datasets.fit_example("speeds")[:2]
    for f in files:
        shutil.copy(f, speeds / f.name)
    (speeds / "notes.md").write_text("not a curve\n")   # other files in the folder are not inputs
    code = main(["fit", str(speeds), "--free", "hamaker", "--no-profile", "--no-compare", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert sorted(out["calibration"]) == sorted(f.name for f in files)


def test_fit_on_a_folder_without_curves_says_so(tmp_path, capsys):
    (tmp_path / "notes.md").write_text("not a curve\n")
    assert main(["fit", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "no force-curve files" in err and "Traceback" not in err


def test_fit_on_a_missing_path_names_it(tmp_path, capsys):
    assert main(["fit", str(tmp_path / "typo")]) == 2
    assert "no such file or folder" in capsys.readouterr().err
