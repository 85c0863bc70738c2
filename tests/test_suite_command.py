"""The suite's own command: the README's test command is what `.ci/run` runs, on every core
(`pytest -n auto`, pytest-xdist: tests/conftest.py, benchmarks/README.md "The test suite's time")."""

import importlib.util
import os
import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _readme_test_command():
    block = re.search(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    lines = [ln for ln in block.splitlines() if ln.startswith("pip install -e '.[test]'")]
    assert len(lines) == 1, block
    return lines[0]


def test_ci_runs_the_readme_test_command_exactly():
    ci = [ln.strip() for ln in (ROOT / ".ci" / "run").read_text().splitlines()]
    commands = [ln for ln in ci if ln and not ln.startswith("#")]
    readme = _readme_test_command()
    assert commands[-1] == readme                       # the last thing CI does, character for character
    assert re.search(r"&& pytest -n auto$", readme)     # on every core


def test_the_test_extra_brings_xdist_and_a_file_stays_on_one_worker():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    extra = pyproject["project"]["optional-dependencies"]["test"]
    assert any(re.match(r"pytest-xdist\b", dep) for dep in extra)
    assert "--dist loadfile" in pyproject["tool"]["pytest"]["ini_options"]["addopts"]


@pytest.mark.parametrize("cores, workers", [(1, 0), (2, 2), (3, 3), (16, 16)])
def test_auto_is_the_usable_cores_and_no_worker_on_one(monkeypatch, cores, workers):
    spec = importlib.util.spec_from_file_location("_root_conftest", ROOT / "tests" / "conftest.py")
    conftest = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(conftest)
    monkeypatch.delenv("PYTEST_XDIST_AUTO_NUM_WORKERS", raising=False)
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(cores)))
    assert conftest.pytest_xdist_auto_num_workers(None) == workers
    monkeypatch.setenv("PYTEST_XDIST_AUTO_NUM_WORKERS", "5")
    assert conftest.pytest_xdist_auto_num_workers(None) is None   # xdist's own hook then reads it
