"""Damaged files: thousands of mutations of every test file; each loads a valid curve or raises
FileFormatError naming the file, within a few seconds of CPU (issue 14, tests).

Every readable file in tests/data (at least one per registered format, see
tests/io/test_examples.py) is mutated (truncation, bit flips, garbage, zeroed runs, header
number edits, NaN/inf, empty, the content under every other ending): a fixed number of seeded
mutations per file, the same ones on every run and every machine (a time budget per file made
the count, and the suite's time, depend on the machine's load). Each file's loop runs in a
child process with its own budget, so a hang fails the test instead of stopping the suite.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError
from afmforce.io import is_supported, load
from afmforce.io._guard import run_with_timeout

from _mutate import mutate  # noqa: E402  (tests/io is on sys.path under pytest)

DATA = Path(__file__).resolve().parents[1] / "data"
OVERRIDES = json.loads((DATA / "meta_override.json").read_text())
FILES = sorted(p.name for p in DATA.iterdir() if is_supported(p))
ENDINGS = (".txt", ".csv", ".ibw", ".jpk-force", ".spm", ".h5", ".tab", ".001")
#: Seeded mutations per file (after the file under every other ending): 24 files x (90 + 7)
#: = 2,328 loads on the 24 files of tests/data, every run the same (the seed is the file's name)
MUTATIONS = 90
SLOW = 5.0      # [s of CPU] one load may take at most this (HDF5: the budget below, then FileTimeoutError)
H5_BUDGET = 3.0
#: [s] wall-time guard of one file's whole loop (a hang fails the test, not the suite): its CPU is
#: 5-25 s; this leaves room for a machine whose other work leaves the test a tenth of a core
LOOP_BUDGET = 600.0


def _problems(curves) -> str | None:
    for c in curves:
        cols = [c.time, c.piezo_nominal, c.deflection_signal] + ([c.piezo_measured] if c.piezo_measured is not None
                                                                  else [])
        if not all(np.isfinite(np.asarray(x, float)).all() for x in cols):
            return "non-finite column"
        if not np.all(np.diff(c.time) > 0):
            return "time not increasing"
        for key in ("spring_constant", "sensitivity", "sample_rate", "velocity"):
            v = c.metadata.get(key)
            if v is not None and not (np.isfinite(v) and v > 0):
                return f"{key} = {v!r}"
    return None


def _check(target: Path, data: bytes, meta) -> tuple[str | None, float]:
    # CPU time of this process, not wall time: the verdict must not depend on the machine's load
    # (an HDF5 load runs in a forked child under its wall-time budget: a hang there is a
    # FileTimeoutError, a FileFormatError naming the file)
    target.write_bytes(data)
    t0 = time.process_time()
    try:
        curves = load(target, meta_override=meta, timeout=H5_BUDGET if target.suffix == ".h5" else None)
    except FileFormatError as exc:
        return (None if target.name in str(exc) else f"message without the file name: {exc}"), time.process_time() - t0
    except Exception as exc:  # anything else is a bug
        return f"{type(exc).__name__}: {str(exc)[:200]}", time.process_time() - t0
    return _problems(curves), time.process_time() - t0


def _fuzz(src: Path, workdir: Path, seed: int, meta) -> dict:
    rng = np.random.default_rng(seed)
    data = src.read_bytes()
    bad, slow, n = [], [], 0
    cases = [(f"ending {e}", workdir / f"wrong{e}", data) for e in ENDINGS if not src.name.endswith(e)]
    total = len(cases) + MUTATIONS
    while n < total:
        if cases:
            kind, target, new = cases.pop()
        else:
            kind, new = mutate(data, rng)
            target = workdir / src.name
        problem, dt = _check(target, new, meta)
        n += 1
        if problem:
            bad.append(f"{kind}: {problem}")
        if dt > SLOW + 1:
            slow.append(f"{kind}: {dt:.1f} s")
    return {"n": n, "bad": bad[:5], "slow": slow[:5]}


TOTAL: dict[str, int] = {}


def _fuzz_file(name: str, workdir: Path) -> dict:
    """One file's mutation loop in a child process (its count recorded in TOTAL)."""
    result = run_with_timeout(_fuzz, DATA / name, workdir, sum(map(ord, name)), OVERRIDES.get(name),
                              timeout=LOOP_BUDGET, path=name)
    TOTAL[name] = result["n"]
    return result


@pytest.mark.parametrize("name", FILES)
def test_mutated_files_load_cleanly_or_fail_with_one_named_error(name, tmp_path):
    result = _fuzz_file(name, tmp_path)
    assert not result["bad"], result["bad"]
    assert not result["slow"], result["slow"]


def test_thousands_of_mutations_in_total(tmp_path):
    # after the per-file tests (the usual order) their counts are in TOTAL; run alone, or
    # after a selection, it runs the files they did not (their problems fail those tests)
    for name in FILES:
        if name not in TOTAL:
            _fuzz_file(name, tmp_path)
    assert sum(TOTAL.values()) >= 2000, TOTAL
    print(f"{sum(TOTAL.values())} mutated files loaded: {TOTAL}")
