"""How many CPU cores this process may use: the thread pool of ``simulate_many``, the workers
of a local Dask cluster and the compile helper of a first ``simulate()`` size themselves by it.

The CPUs the process may run on (its affinity), capped by a CPU quota of its control group
(containers and batch schedulers: ``cpu.max`` of cgroup v2, ``cpu.cfs_quota_us`` of v1), which
the affinity does not show: a container limited to one CPU on a 16-core host sees 16 CPUs.
A quota of 1.5 CPUs counts as 2 (rounded to the nearest whole CPU, at least 1).
"""

from __future__ import annotations

import functools
import math
import os
from pathlib import Path

__all__ = ["available_cores", "cgroup_cpu_limit"]


def _read(path: Path) -> str | None:
    try:
        return path.read_text()
    except (OSError, UnicodeDecodeError):
        return None


def _ancestors(root: Path, rel: str) -> list[Path]:
    parts = [p for p in rel.strip().split("/") if p and p != ".."]
    return [root.joinpath(*parts[:i]) for i in range(len(parts), -1, -1)]


def cgroup_cpu_limit(root: str | Path = "/sys/fs/cgroup",
                     proc_cgroup: str | Path = "/proc/self/cgroup") -> float | None:
    """CPUs allowed by the control group's CPU quota (the smallest along the group's path
    and its parents), or None where there is no quota or it cannot be read."""
    root = Path(root)
    limits = []
    for line in (_read(Path(proc_cgroup)) or "0::/\n").splitlines():
        hier, _, rest = line.partition(":")
        controllers, _, rel = rest.partition(":")
        if hier == "0" and controllers == "":                     # cgroup v2
            for d in _ancestors(root, rel):
                text = (_read(d / "cpu.max") or "").split()
                if len(text) == 2 and text[0] != "max":
                    try:
                        limits.append(int(text[0]) / int(text[1]))
                    except (ValueError, ZeroDivisionError):
                        pass
        elif "cpu" in controllers.split(","):                    # cgroup v1
            base = root / controllers
            if not base.exists():
                base = root / "cpu"
            for d in _ancestors(base, rel):
                try:
                    q = int((_read(d / "cpu.cfs_quota_us") or "").strip())
                    p = int((_read(d / "cpu.cfs_period_us") or "").strip())
                except ValueError:
                    continue
                if q > 0 and p > 0:
                    limits.append(q / p)
    return min(limits) if limits else None


@functools.cache
def _process_limit() -> float | None:
    # read once per process (~0.2 ms of file reads; simulate_many asks on every call)
    return cgroup_cpu_limit()


def available_cores() -> int:
    """CPU cores this process may use (affinity, capped by the cgroup CPU quota, which is
    read once per process) [-]."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:                                    # pragma: no cover - not Linux
        n = os.cpu_count() or 1
    limit = _process_limit()
    if limit is not None and math.isfinite(limit):
        n = min(n, int(limit + 0.5))
    return max(1, n)
