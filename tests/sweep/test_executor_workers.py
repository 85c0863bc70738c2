"""A local cluster's worker count is bounded (afmforce.sweep.executors.check_workers): ``afmforce sweep
--workers 1000`` on a 2-core machine started 1000 worker processes (the audit: "622 leaked semaphore
objects" at exit). More than WORKERS_PER_CORE per available core is refused before any work, on the
command line and in Python."""

from __future__ import annotations

import pytest

from afmforce.cli.main import main
from afmforce.errors import ParameterError
from afmforce.sweep import executors


@pytest.fixture()
def two_cores(monkeypatch):
    monkeypatch.setattr(executors, "available_cores", lambda: 2)


def test_library_refuses_more_workers_than_the_cap(two_cores):
    most = executors.WORKERS_PER_CORE * 2
    assert executors.DaskExecutor(workers=most).workers == most      # no cluster is started by the record
    with pytest.raises(ParameterError, match=rf"`workers` = {most + 1} is more than {most}"):
        executors.DaskExecutor(workers=most + 1)
    with pytest.raises(ParameterError, match="at least 1"):
        executors.DaskExecutor(workers=0)
    with pytest.raises(ParameterError, match="whole number"):
        executors.DaskExecutor(workers=2.5)


@pytest.mark.parametrize("command", [["sweep", "--grid", "xi=0.1,0.2"], ["analyze", "--example", "asylum-air"]])
def test_cli_refuses_before_any_work(two_cores, capsys, tmp_path, command):
    code = main([*command, "--workers", "1000", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("error: --workers = 1000 is more than 8"), err
    assert not (tmp_path / "o").exists()
