"""CPU cores this process may use (:mod:`afmforce._cores`): affinity capped by a cgroup quota."""

from __future__ import annotations

import os

import pytest

from afmforce import _cores


def _tree(tmp_path, files: dict, cgroup: str):
    for rel, text in files.items():
        p = tmp_path / "fs" / rel
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(text)
    proc = tmp_path / "cgroup"
    proc.write_text(cgroup)
    return tmp_path / "fs", proc


@pytest.mark.parametrize("files, cgroup, want", [
    ({"cpu.max": "max 100000\n"}, "0::/\n", None),                        # v2, no quota
    ({"cpu.max": "150000 100000\n"}, "0::/\n", 1.5),                      # v2, 1.5 CPUs
    ({"a/b/cpu.max": "max 100000\n", "a/cpu.max": "100000 100000\n"},
     "0::/a/b\n", 1.0),                                                    # a parent's quota
    ({"cpu,cpuacct/cpu.cfs_quota_us": "-1\n", "cpu,cpuacct/cpu.cfs_period_us": "100000\n"},
     "4:cpu,cpuacct:/\n0::/\n", None),                                     # v1, no quota
    ({"cpu/cpu.cfs_quota_us": "200000\n", "cpu/cpu.cfs_period_us": "100000\n"},
     "1:cpu:/\n", 2.0),                                                    # v1, 2 CPUs
    ({"cpu.max": "garbage\n"}, "0::/\n", None),                           # unreadable: none
    ({}, "", None),                                                        # no cgroup at all
])
def test_cgroup_cpu_limit_reads_v1_and_v2_quotas(tmp_path, files, cgroup, want):
    root, proc = _tree(tmp_path, files, cgroup)
    assert _cores.cgroup_cpu_limit(root, proc) == want


@pytest.mark.parametrize("limit, want", [(None, 8), (1.0, 1), (1.5, 2), (0.2, 1), (64.0, 8)])
def test_available_cores_caps_the_affinity_by_the_quota(monkeypatch, limit, want):
    """A container limited to one CPU on an 8-CPU host: 1 (its thread pools and the compile
    helper would otherwise share one CPU eight or two ways)."""
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(8)), raising=False)
    monkeypatch.setattr(_cores, "_process_limit", lambda: limit)
    assert _cores.available_cores() == want


def test_this_machine():
    """On the machine running the tests: at least 1, at most the CPUs it may run on."""
    n = _cores.available_cores()
    assert 1 <= n <= (len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                      else os.cpu_count())


def test_the_quota_is_read_once_per_process():
    """simulate_many asks on every call (a fit: hundreds): the cgroup files are read once."""
    _cores.available_cores()
    before = _cores._process_limit.cache_info()
    for _ in range(3):
        _cores.available_cores()
    after = _cores._process_limit.cache_info()
    assert after.hits == before.hits + 3 and after.misses == before.misses
