"""Atomic outputs (afmforce._files): what they refuse to replace."""

from __future__ import annotations

import os

import pytest

from afmforce._files import atomic_write_text, check_writable
from afmforce.errors import ParameterError


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no named pipes on this system")
def test_a_pipe_or_device_is_never_replaced_by_a_file(tmp_path):
    """The rename of an atomic write replaces the node it lands on: with ``force`` a named pipe (or,
    run as root, ``/dev/full``: found by the audit, the device became a 6 kB file) turned into a
    plain file. Such an output is refused, and the node is left as it was."""
    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    for force in (False, True):
        with pytest.raises(ParameterError, match="not a plain file"):
            check_writable(pipe, force)
        with pytest.raises(ParameterError, match="not a plain file"):
            atomic_write_text(pipe, "x", force)
    assert not pipe.is_file() and pipe.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["pipe"]      # no temporary file left either


def test_a_plain_file_is_still_replaced_with_force(tmp_path):
    out = tmp_path / "out.txt"
    out.write_text("old")
    atomic_write_text(out, "new", force=True)
    assert out.read_text() == "new"
