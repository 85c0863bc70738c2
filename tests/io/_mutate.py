"""Mutations of a file's bytes for the fuzz test (truncation, bit flips, garbage, header edits, NaN)."""

from __future__ import annotations

import re

import numpy as np

KINDS = ("truncate", "flip", "garbage", "header", "nan", "empty", "zero")
_NUM = re.compile(rb"[-+]?\d+(?:[.,]\d+)?(?:[eE][-+]?\d+)?")
_REPLACEMENTS = (b"-1", b"0", b"nan", b"inf", b"1e308", b"", b"-5e-08", b"{}", b"abc")


def mutate(data: bytes, rng: np.random.Generator) -> tuple[str, bytes]:
    """One random mutation of ``data``: (kind, new bytes)."""
    kind = KINDS[int(rng.integers(len(KINDS)))]
    n = len(data)
    if kind == "empty" or n == 0:
        return "empty", b""
    if kind == "truncate":
        return kind, data[: int(rng.integers(0, n))]
    if kind == "flip":
        b = bytearray(data)
        for _ in range(int(rng.integers(1, 9))):
            i = int(rng.integers(n))
            b[i] ^= 1 << int(rng.integers(8))
        return kind, bytes(b)
    if kind == "garbage":
        i, k = int(rng.integers(n)), int(rng.integers(1, 65))
        return kind, data[:i] + rng.integers(0, 256, k, dtype=np.uint8).tobytes() + data[i + k:]
    if kind == "zero":
        i, k = int(rng.integers(n)), int(rng.integers(1, 257))
        return kind, data[:i] + b"\0" * k + data[i + k:]
    # header edits (numbers near the start) and NaN (numbers anywhere) in text parts of the file
    region = data[:4096] if kind == "header" else data
    matches = list(_NUM.finditer(region))
    if not matches:
        return "flip", mutate(data, rng)[1]
    m = matches[int(rng.integers(len(matches)))]
    new = _REPLACEMENTS[int(rng.integers(len(_REPLACEMENTS)))] if kind == "header" else (b"nan", b"inf")[
        int(rng.integers(2))]
    return kind, data[: m.start()] + new + data[m.end():]
