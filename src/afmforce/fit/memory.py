"""The fit guards its own memory (issue 34): an estimate from the sample count, checked
against what the machine can give before anything large is allocated.

Everything the fit holds grows linearly in the fitted samples ``n`` (the noise model is
not dense in them: :mod:`afmforce.fit.noise`): the Jacobian (``n`` x parameters), the
cached model predictions (up to :data:`CACHE_PER_CURVE` per curve), the batched
simulations and the whitened designs. :func:`fit_bytes` is that estimate with a margin;
``benchmarks/bench_fit_memory.py`` measures the peak at several sizes (it must stay below
the estimate).
"""

from __future__ import annotations

import math

from ..errors import MemoryLimitError

__all__ = ["fit_bytes", "available_memory", "check_fit_memory", "BYTES_PER_SAMPLE", "BASE_BYTES"]

#: Bytes the fit holds per fitted sample and per free parameter (Jacobian columns, the
#: batched predictions of a Jacobian), measured with margin (benchmarks/bench_fit_memory.py).
BYTES_PER_SAMPLE_PARAMETER = 8 * 8
#: Bytes per sample independent of the parameters (the trajectories of a batch of runs before
#: they are reduced to the sampled deflection, the prediction cache of 64 runs per curve, the
#: curve's arrays, whitened designs), with margin: the fit's own peak grew by 2.9 kB per added
#: sample on the issue's liquid set (tracemalloc, benchmarks/bench_fit_memory.py).
BYTES_PER_SAMPLE = 3000
#: The interpreter, numpy, scipy, numba and the compiled models [bytes].
BASE_BYTES = 400e6


def fit_bytes(n_samples: int, n_free: int, n_curves: int = 1) -> float:
    """Estimated peak memory of a fit of ``n_samples`` samples with ``n_free`` global
    parameters and ``n_curves`` curves [bytes]."""
    per = BYTES_PER_SAMPLE + BYTES_PER_SAMPLE_PARAMETER * (n_free + n_curves + 4)
    return BASE_BYTES + per * float(n_samples)


def _read(path: str) -> str | None:
    try:
        with open(path) as fh:
            return fh.read()
    except OSError:
        return None


def _cgroup_headroom() -> float:
    """The container's (cgroup) limit less its current use [bytes]; inf without one."""
    for lim, cur in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                     ("/sys/fs/cgroup/memory/memory.limit_in_bytes",
                      "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        a, b = _read(lim), _read(cur)
        if a is None or not a.strip().isdigit() or int(a) >= 1 << 60:
            continue
        used = int(b) if b is not None and b.strip().isdigit() else 0
        return float(int(a) - used)
    return math.inf


def _status_bytes(key: str) -> float:
    """A ``VmSize``-like field of /proc/self/status [bytes] (0 when unknown)."""
    text = _read("/proc/self/status") or ""
    for line in text.splitlines():
        if line.startswith(key + ":"):
            return float(line.split()[1]) * 1024
    return 0.0


def available_memory() -> float:
    """Memory this process can still take [bytes]: the least of the machine's available memory,
    the headroom under the process's address-space and data limits (the limit less what it
    already uses) and under the container's (cgroup) limit; inf where none is known."""
    heads = [_cgroup_headroom()]
    info = _read("/proc/meminfo")
    if info:
        for line in info.splitlines():
            if line.startswith("MemAvailable:"):
                heads.append(float(line.split()[1]) * 1024)
    try:
        import resource

        for lim, key in ((resource.RLIMIT_AS, "VmSize"), (resource.RLIMIT_DATA, "VmData")):
            soft = resource.getrlimit(lim)[0]
            if soft != resource.RLIM_INFINITY and soft > 0:
                heads.append(float(soft) - _status_bytes(key))
    except (ImportError, ValueError, OSError):
        pass
    return max(min(heads), 0.0)


def check_fit_memory(n_samples: int, n_free: int, n_curves: int) -> float:
    """Raise :class:`~afmforce.errors.MemoryLimitError` when the memory the fit will add (its
    estimate less the interpreter's share, already in use) exceeds what is available; returns
    the estimate [bytes]."""
    need = fit_bytes(n_samples, n_free, n_curves) - BASE_BYTES
    have = available_memory()
    if need > have:
        raise MemoryLimitError(
            f"the fit of {n_samples} samples in {n_curves} curves with {n_free} free parameters "
            f"needs about {need / 1e9:.3g} GB more but {have / 1e9:.3g} GB are available: fit "
            "fewer or shorter curves (the approach's free part far from the surface carries "
            "little), decimate the samples (a lower sample_rate), or free fewer parameters")
    return need
