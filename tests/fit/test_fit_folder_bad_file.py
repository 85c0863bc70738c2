"""``afmforce fit FOLDER`` goes on past a file of the folder no reader can read, as ``afmforce
analyze`` does with a batch: the file is named in a warning, left out of the fit, listed in the
JSON's ``skipped_files``, and the status is 1. Before, one unreadable file in the folder stopped
the whole fit (``error: mixdir/garbage.txt: content not recognised ...``). A file named on the
command line is still the command's error, and a folder of nothing readable too."""

from __future__ import annotations

import shutil

import pytest

from afmforce.cli.main import main
from afmforce.datasets import fit_example


class _Fitted(Exception):
    pass


@pytest.fixture
def folder(tmp_path):
    d = tmp_path / "speeds"
    d.mkdir()
    for p in fit_example("speeds")[:2]:
        shutil.copy(p, d / p.name)
    (d / "garbage.txt").write_bytes(bytes(range(256)) * 8)
    return d


def test_a_bad_file_in_a_folder_is_skipped_and_named(folder, monkeypatch, capsys):
    import afmforce.fit as fit

    seen = {}

    def fake(curves, *a, names=None, **kw):     # the fit itself is tested elsewhere: what reaches it
        seen["names"] = list(names)
        seen["n"] = len(curves)
        raise _Fitted

    monkeypatch.setattr(fit, "fit_dynamic", fake)
    before = (folder / "garbage.txt").read_bytes()
    code = main(["fit", str(folder), "--free", "hamaker", "--no-profile"])
    err = capsys.readouterr().err
    assert code == 1 and "unexpected _Fitted" in err     # the CLI's contract caught the fake fit's stop
    good = sorted(p.name for p in fit_example("speeds")[:2])
    assert seen == {"names": good, "n": 2}
    line = next(x for x in err.splitlines() if x.startswith("warning: skipped "))
    assert f"{folder / 'garbage.txt'}: content not recognised" in line and "--format" in line
    assert (folder / "garbage.txt").read_bytes() == before


def test_a_bad_file_named_is_the_commands_error(folder, capsys):
    code = main(["fit", str(folder / "garbage.txt"), *(str(p) for p in sorted(folder.glob("fit-*")))])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and err.startswith(f"error: {folder / 'garbage.txt'}: content not")


def test_a_folder_of_nothing_readable_is_an_error(tmp_path, capsys):
    d = tmp_path / "bad"
    d.mkdir()
    for i in range(2):
        (d / f"g{i}.txt").write_bytes(b"\x00\xff" * 500)
    code = main(["fit", str(d)])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("error: no file could be read: ") and "(and 1 more)" in err
    assert err.count("\n") == 1 + err.count("warning: skipped")
