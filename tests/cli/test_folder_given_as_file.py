"""A folder given where one file is read (``afmforce calibrate invols DIR``, ``load(DIR)``) is named
as a folder; before, the message said "DIR: no such file" of a folder that exists."""

from __future__ import annotations

import pytest

from afmforce.cli.main import main
from afmforce.errors import FileFormatError
from afmforce.io import load


@pytest.mark.parametrize("fmt", [None, "afmforce-raw"])
def test_load_of_a_folder_says_it_is_a_folder(tmp_path, fmt):
    with pytest.raises(FileFormatError, match=r"is a folder, not a force-curve file: give the files in it"):
        load(tmp_path, format=fmt)
    with pytest.raises(FileFormatError, match=r"missing.txt: no such file$"):
        load(tmp_path / "missing.txt", format=fmt)


def test_calibrate_invols_on_a_folder(tmp_path, capsys):
    assert main(["calibrate", "invols", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err == f"error: {tmp_path} is a folder, not a force-curve file: give the files in it (or the folder to a batch)\n"
