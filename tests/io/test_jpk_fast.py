"""afmformats' JPK reader with afmforce's properties parser (:mod:`afmforce.io._jpk_fast`) gives
exactly afmformats' records: the parser returns jprops' dicts, the records afmformats.load_data's
columns and metadata, on every JPK file in tests/data and shared/data/real."""

from __future__ import annotations

import io
import logging
import zipfile
from pathlib import Path

import numpy as np
import pytest

from afmforce.io import load
from afmforce.io._jpk_fast import load_jpk_data, load_properties

DATA = Path(__file__).resolve().parents[1] / "data"
REAL = Path(__file__).resolve().parents[3] / "shared" / "data" / "real"
FILES = sorted(DATA.glob("*.jpk*")) + (sorted(REAL.glob("*.jpk*")) if REAL.is_dir() else [])


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_properties_as_jprops(path):
    import jprops

    with zipfile.ZipFile(path) as arc:
        for name in arc.namelist():
            if name.endswith(".properties"):
                raw = arc.read(name)
                assert list(load_properties(raw).items()) == list(jprops.load_properties(io.BytesIO(raw)).items())


@pytest.mark.parametrize("raw", [
    b"a b=c\nk : v\n  x\t=  y z \n!c\n#d\\\ne=f\n",          # whitespace terminators, a continued comment
    b"key\\ with\\:esc=va\\u0041l\\n\nq=1\\\n  2\n",           # escapes, a continued value
    b"only\n\n  \r\nx=\xe9\r\n", b"a=b\\\\\nc=d", b"  \x1c k=v\n\xa0m=n\n\x85z=1",
])
def test_properties_edge_cases_as_jprops(raw):
    import jprops

    assert list(load_properties(raw).items()) == list(jprops.load_properties(io.BytesIO(raw)).items())


def _items(md):
    return [(k, md[k]) for k in md]  # evaluates afmformats' lazy values (z range)


@pytest.mark.parametrize("override", [{}, {"spring constant": 0.05, "sensitivity": 5e-8}])
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.name)
def test_records_as_afmformats(path, override):
    import afmformats

    logging.getLogger("afmformats").disabled = True
    try:
        try:
            ref = afmformats.load_data(path, meta_override=dict(override))
            for rec in ref:  # afmformats reads the columns lazily: a refusal may come only now
                [rec[col] for col in rec.columns]
        except BaseException as exc:  # afmformats refuses it: so does the fast path (the caller falls back)
            if isinstance(exc, KeyboardInterrupt):
                raise
            # the fast path refuses it too, or reads what afmformats cannot (float-data channels
            # without an encoder, issue 32): then every column it gives is finite
            try:
                got = load_jpk_data(path, override)
                cols = [np.asarray(r[c]) for r in got for c in r.columns]
            except BaseException as exc2:  # afmformats' errors derive from BaseException
                if isinstance(exc2, KeyboardInterrupt):
                    raise
                return
            assert got and all(np.all(np.isfinite(c)) for c in cols if c.dtype.kind == "f")
            return
        new = load_jpk_data(path, override)
    finally:
        logging.getLogger("afmformats").disabled = False
    assert len(new) == len(ref)
    for a, b in zip(ref, new):
        assert type(a) is type(b) and a.columns == b.columns
        for col in a.columns:
            x, y = a[col], b[col]
            assert x.dtype == y.dtype and np.array_equal(x, y), col
        assert _items(a.metadata) == _items(b.metadata)


@pytest.mark.parametrize("path", [p for p in FILES if p.suffix == ".jpk-force-map"] or
                         [pytest.param(None, marks=pytest.mark.skip("no JPK map at hand"))])
def test_map_curves_identical_to_the_afmformats_route(path, monkeypatch):
    fast = load(path)
    monkeypatch.setattr("afmforce.io._afmformats.load_jpk_data", lambda *a, **k: 1 / 0)  # force the fallback
    slow = load(path)
    assert len(fast) == len(slow)
    for f, s in zip(fast, slow):
        for name in ("time", "piezo_nominal", "piezo_measured", "deflection_signal", "segment"):
            a, b = getattr(f, name), getattr(s, name)
            assert a.dtype == b.dtype and np.array_equal(a, b), name
        assert list(f.metadata.items()) == list(s.metadata.items())
