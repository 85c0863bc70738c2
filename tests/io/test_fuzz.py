"""Damaged files: every reader either reads a curve or raises an AfmforceError, never crashes.

Hypothesis mutates the bytes of each data file (truncation, flipped bytes,
inserted garbage); example counts are kept small so the suite stays fast.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from afmforce.errors import AfmforceError
from afmforce.io import load
from afmforce.raw import RawCurve

DATA = Path(__file__).resolve().parents[1] / "data"
FILES = ["asylum-mfp3d_SiN-tip_air.ibw", "jpk_calibration-curve_raw-volts.jpk-force",
         "jpk_cellhesion_spot3.jpk-force", "afm-workshop_single.csv", "ntmdt_gel-in-water.txt",
         "bruker-nanoscope_synthetic.txt"]
META = {"spring_constant": 0.05, "sensitivity": 61e-9}


@st.composite
def mutations(draw, size: int):
    kind = draw(st.sampled_from(["truncate", "flip", "insert", "zero"]))
    pos = draw(st.integers(0, size - 1))
    if kind == "truncate":
        return ("truncate", pos, b"")
    n = draw(st.integers(1, 64))
    return (kind, pos, draw(st.binary(min_size=n, max_size=n)))


def _mutate(data: bytes, m) -> bytes:
    kind, pos, blob = m
    if kind == "truncate":
        return data[:pos]
    if kind == "flip":
        return data[:pos] + bytes(b ^ 0xFF for b in data[pos:pos + len(blob)]) + data[pos + len(blob):]
    if kind == "zero":
        return data[:pos] + b"\0" * len(blob) + data[pos + len(blob):]
    return data[:pos] + blob + data[pos:]


@pytest.mark.parametrize("name", FILES)
def test_mutated_file_never_crashes(name, tmp_path_factory):
    src = DATA / name
    data = src.read_bytes()
    workdir = tmp_path_factory.mktemp("fuzz")

    @settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(m=mutations(len(data)))
    def check(m):
        target = workdir / name
        target.write_bytes(_mutate(data, m))
        try:
            curves = load(target, meta_override=META if "ntmdt" in name else None)
        except AfmforceError as exc:
            assert str(exc)  # a message saying what is wrong
            return
        assert curves and all(isinstance(c, RawCurve) for c in curves)

    check()
    shutil.rmtree(workdir, ignore_errors=True)
