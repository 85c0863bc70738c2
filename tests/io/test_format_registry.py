"""Issue 31 item 7: a new file format is one module that calls :func:`afmforce.io.register_format`.

A toy format (a text file: a ``toy-afm`` first line, then position [nm] and deflection [nN] rows,
approach then retract, a 1.5-power rise) is written as ONE module in ``tmp_path`` and imported; nothing else is
edited. It must then be detected by :func:`~afmforce.io.load`, listed by ``afmforce formats``
(text and JSON) and the docs' Markdown table, accepted as ``--format``, claimed by
:func:`~afmforce.io.is_supported`, and analysed by ``afmforce analyze FILE --json`` with the
numbers of its file (checked against the rows written here, not against the reader).
"""

from __future__ import annotations

import importlib.util
import json
import sys
import textwrap

import numpy as np
import pytest

from afmforce import io
from afmforce.cli.main import main
from afmforce.errors import ParameterError

MODULE = '''
"""A toy reader: one module, registered on import."""
import numpy as np

from afmforce.io import ReaderFormat, register_format
from afmforce.io.curve import RawCurve


def detect(path):
    with open(path, encoding="utf-8") as fh:
        return fh.readline().strip() == "toy-afm"


def load(path, *, meta_override=None, callback=None, **_):
    rows = np.loadtxt(path, skiprows=1)
    z, f, seg = rows[:, 0] * 1e-9, rows[:, 1] * 1e-9, rows[:, 2].astype(int)
    md = {"spring_constant": 0.1, "sample_rate": 1000.0, "reader": "toy-afm"}
    md.update(meta_override or {})
    return [RawCurve(time=np.arange(z.size) / 1000.0, piezo_nominal=z, piezo_measured=None,
                     deflection_signal=f, segment=seg, deflection_unit="N", metadata=md)]


TOY = register_format(ReaderFormat("toy-afm", "Toy AFM text", (".toyf",), detect, load, via="afmforce",
                                   deflection="N", signature="first line toy-afm",
                                   supplies=("spring_constant", "sample_rate")))
'''


def _curve_rows() -> np.ndarray:
    """A Hertz-like approach and its retract: z [nm] growing towards the sample, force [nN]."""
    za = np.linspace(0.0, 200.0, 400)
    contact = 150.0
    fa = 0.02 * np.clip(za - contact, 0.0, None) ** 1.5 + 0.001 * np.sin(za)
    zr, fr = za[::-1], fa[::-1]
    return np.vstack([np.column_stack((za, fa, np.zeros_like(za))), np.column_stack((zr, fr, np.ones_like(zr)))])


@pytest.fixture
def toy(tmp_path):
    mod = tmp_path / "toy_reader.py"
    mod.write_text(textwrap.dedent(MODULE), encoding="utf-8")
    spec = importlib.util.spec_from_file_location("toy_reader", mod)
    module = importlib.util.module_from_spec(spec)
    sys.modules["toy_reader"] = module
    spec.loader.exec_module(module)
    data = tmp_path / "curve.toyf"
    rows = _curve_rows()
    data.write_text("toy-afm\n" + "\n".join(f"{float(z)!r} {float(f)!r} {int(s)}" for z, f, s in rows) + "\n", encoding="utf-8")
    try:
        yield data, rows
    finally:
        io.unregister_format("toy-afm")
        sys.modules.pop("toy_reader", None)


def test_a_format_in_one_module_reaches_every_face(toy, capsys):
    path, rows = toy
    before = path.read_bytes()
    assert io.is_supported(path) and ".toyf" in io.supported_suffixes()
    assert io.find_format(path).identifier == "toy-afm"
    (curve,) = io.load(path)
    assert np.array_equal(curve.piezo_nominal, rows[:, 0] * 1e-9)
    assert np.array_equal(curve.deflection_signal, rows[:, 1] * 1e-9)
    assert "| `toy-afm` | Toy AFM text | .toyf |" in io.formats_markdown()
    assert main(["formats"]) == 0
    assert "toy-afm" in capsys.readouterr().out
    assert main(["formats", "--json"]) == 0
    assert any(r["identifier"] == "toy-afm" for r in json.loads(capsys.readouterr().out)["formats"])
    code = main(["analyze", str(path), "--format", "toy-afm", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0, out
    (res,) = out["results"].values()
    # the file's own k (the reader's metadata), its unit, and its shape: a Hertz-like rise is soft contact
    assert res["deflection_unit"] == "N" and res["spring_constant"] == 0.1
    assert res["contact_kind"] == "soft" and res["position_channel"] == "nominal"
    assert path.read_bytes() == before            # the input is never modified


def test_register_format_refuses_what_it_cannot_hold(toy):
    fmt = io.FORMATS["toy-afm"]
    with pytest.raises(ParameterError, match="registered already"):
        io.register_format(fmt)
    import dataclasses

    with pytest.raises(ParameterError, match="claims no file name"):
        io.register_format(dataclasses.replace(fmt, identifier="toy-2", suffixes=()))
    with pytest.raises(ParameterError, match="lower case"):
        io.register_format(dataclasses.replace(fmt, identifier="toy-3", suffixes=(".TOY",)))
    with pytest.raises(ParameterError, match="is not registered"):
        io.register_format(dataclasses.replace(fmt, identifier="toy-4"), before="no-such-format")
    first = io.register_format(dataclasses.replace(fmt, identifier="toy-5"), before="afmforce-raw")
    try:
        assert next(iter(io.FORMATS)) == "toy-5" and first.identifier == "toy-5"
    finally:
        io.unregister_format("toy-5")
    assert "toy-5" not in io.FORMATS
