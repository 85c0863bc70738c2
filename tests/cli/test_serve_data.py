"""``afmforce serve --data FILE`` (a file, not a folder) is a usage error naming the flag, before the
server makes any folder: before, "error: /etc/passwd: File exists" with exit status 1 (audit)."""

from __future__ import annotations

import pytest

pytest.importorskip("fastapi")

from afmforce.cli.main import main  # noqa: E402


def test_data_that_is_a_file_is_refused(tmp_path, capsys):
    not_a_folder = tmp_path / "notes.txt"
    not_a_folder.write_text("mine")
    for data, words in ((not_a_folder, "exists and is not a folder"),
                        (not_a_folder / "serve", f"cannot be written: {not_a_folder} is not a folder")):
        assert main(["serve", "--port", "0", "--data", str(data)]) == 2
        err = capsys.readouterr().err
        assert err.startswith(f"error: --data {data}") and words in err and err.count("\n") == 1, err
    assert not_a_folder.read_text() == "mine"
