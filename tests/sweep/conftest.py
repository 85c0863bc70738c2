"""Fixtures of the sweep tests: one small local Dask cluster for the whole session."""

from __future__ import annotations

import logging
import sys
from pathlib import Path

import pytest

# sweep_funcs must be importable here and in Dask worker processes (which inherit sys.path),
# whatever pytest's import mode
if str(Path(__file__).parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture(scope="session")
def dask_client():
    """A Client of a LocalCluster: 2 single-threaded worker processes on 127.0.0.1."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1",
                                  dashboard_address=None, silence_logs=logging.ERROR) as cluster:
        with distributed.Client(cluster) as client:
            yield client
