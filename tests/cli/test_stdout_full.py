"""A standard output that cannot be written (a full disk, ``> /dev/full``) is one error line, never a
traceback: with ``--json`` the error object itself could not be printed and raised again (audit)."""

from __future__ import annotations

import errno
import io
import sys

from afmforce.cli.main import main


class FullStream(io.StringIO):
    def write(self, text):
        raise OSError(errno.ENOSPC, "No space left on device")

    def flush(self):
        raise OSError(errno.ENOSPC, "No space left on device")


def test_json_to_a_full_stdout_is_one_error_line(monkeypatch, capsys):
    err = io.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    monkeypatch.setattr(sys, "stdout", FullStream())
    code = main(["formats", "--json"])
    assert code == 1
    assert err.getvalue() == "error: No space left on device\n"
    print("still writable")             # the rest of stdout goes nowhere, without a second error
