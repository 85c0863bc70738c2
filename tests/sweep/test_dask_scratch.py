"""A local Dask cluster leaves nothing in the temporary folder (branch mapcap): its workers wrote
``<tmp>/dask-scratch-space`` (their lock files and spill folders), outside the user's ``--out`` and the
web's ``--data``, and it outlived every sweep. Now the scratch is a folder of its own, removed on close.
The temporary folder is this test's (``TMPDIR``, inherited by the worker processes), not the real /tmp."""

from __future__ import annotations

import math
import os
import tempfile

import pytest

from afmforce.sweep.executors import DaskExecutor


def test_a_local_cluster_leaves_no_scratch(tmp_path, monkeypatch):
    pytest.importorskip("distributed")
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setenv("TMPDIR", str(scratch))
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    seen = []
    with DaskExecutor(workers=1) as ex:
        out = {o.key: o.value for o in ex.imap_unordered(math.hypot, [(k, (3.0 * k, 4.0 * k)) for k in range(3)])}
        seen = os.listdir(scratch)
    assert out == {0: 0.0, 1: 5.0, 2: 10.0}
    assert seen and all(name.startswith("afmforce-dask-") for name in seen), seen   # the workers wrote here
    assert os.listdir(scratch) == []                                                # and nothing is left
