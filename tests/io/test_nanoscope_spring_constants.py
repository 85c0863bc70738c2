"""Bruker's own NanoScope v8.15 example (PyPI ``nanoscope`` 1.2.300, ``Force.spm``): two spring constants.

Its header holds two ``\\*Ciao force image list`` sections of the same channel (Deflection Error), whose
data blocks (byte 40960 and 45056) are byte for byte the same curve: the first, ``X Data Type: Ramp``,
says ``Spring Constant: 10``; the second, ``X Data Type: Time`` with ``Offline Planefit: Full`` (changed
offline), says 13.8772. No ``\\Spring Constant`` in the Ciao scan list. Bruker's toolbox gives a file's
spring constant as channel 0's (``files/base.py``: ``ForceSpringConstant`` of ``i_chan = 0``): 10 N/m,
the one afmforce reads; it now says that the other exists. The modulus with the file's tip radius
(``\\Tip Radius: 100`` nm) is checked against nanite 4.2.3 on the curve read here by hand.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from afmforce.analysis.options import ProbeCalibration
from afmforce.analysis.pipeline import analyze
from afmforce.io import load

FILE = Path(__file__).resolve().parents[1] / "data" / "corpus" / "bruker-nanoscope_v8.15_Bruker-example_Force.spm"


def _lists(raw: bytes) -> list[dict[str, str]]:
    """The header's force image lists, read by hand: {key: value} each."""
    head = raw[: raw.index(b"\\*File list end")].decode("latin-1")
    out = []
    for block in head.split("\\*Ciao force image list")[1:]:
        block = block.split("\\*", 1)[0]
        out.append({m.group(1).strip(): m.group(2).strip()
                    for m in re.finditer(r"^\\@?([^:\r\n]+):(.*)$", block, re.M)})
    return out


def test_the_deflection_lists_spring_constant_is_read_and_the_other_named():
    raw = FILE.read_bytes()
    lists = _lists(raw)
    ks = [float(e["Spring Constant"]) for e in lists]
    assert ks == [10.0, 13.8772]
    blocks = [raw[int(e["Data offset"]): int(e["Data offset"]) + int(e["Data length"])] for e in lists]
    assert blocks[0] == blocks[1]                  # one curve, two lists: the header alone tells them apart
    curve = load(FILE)[0]
    assert curve.metadata["spring_constant"] == ks[0]      # the first list's, as Bruker's toolbox reads it
    note = curve.metadata["spring_constant_note"]
    assert "10 N/m" in note and "13.8772 N/m" in note and "used" in note
    res = analyze(curve)
    assert res.spring_constant == ks[0]
    assert note in res.warnings                    # the analysis says which k it used, and the other
    given = analyze(curve, probe=ProbeCalibration(spring_constant=ks[1]))
    assert given.spring_constant == ks[1] and note not in given.warnings


def test_one_spring_constant_gives_no_note():
    curve = load(FILE.parent / "bruker-nanoscope_v9.2_Egel4_00025.spm")[0]
    assert "spring_constant_note" not in curve.metadata


def test_modulus_agrees_with_nanite_and_scales_with_k():
    """1.90 GPa (Hertz paraboloid, R = 100 nm from the header, nu = 0.5, k = 10 N/m); nanite on the curve read
    by hand from the header's scales (V/LSB 0.000375, DeflSens 21.9 nm/V, Zsens 8.1 nm/V x ramp 6.17284 V
    = 50 nm) gives 1.935 GPa. Sub-nanometre indentation (0.78 nm at 23 nN) of a stiff sample: a polymer's
    modulus. With the other list's k (13.8772 N/m) the modulus scales as k (the deflection, and so the
    indentation, does not depend on k): 2.64 GPa."""
    nanite = pytest.importorskip("nanite")
    raw = FILE.read_bytes()
    counts = np.frombuffer(raw[40960:40960 + 4096], "<i2").astype(float)
    defl = counts * 0.000375 * 21.9e-9
    app, ret = defl[:1024][::-1], defl[1024:]            # stored from the turning point
    ramp = 6.172840 * 8.1e-9
    k = 10.0
    data = {"force": np.r_[app, ret] * k, "height (measured)": np.r_[np.linspace(ramp, 0, 1024),
                                                                     np.linspace(0, ramp, 1024)],
            "segment": np.r_[np.zeros(1024, bool), np.ones(1024, bool)], "time": np.arange(2048) * 1e-4}
    md = {"spring constant": k, "sensitivity": 21.9e-9, "path": str(FILE), "enum": 0,
          "imaging mode": "force-distance", "duration": 0.2048, "point count": 2048}
    idnt = nanite.Indentation(data=data, metadata=md)
    idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset", "correct_tip_offset"],
                             options={"correct_tip_offset": {"method": "fit_line_polynomial"}})
    p = idnt.get_initial_fit_parameters(model_key="hertz_para")
    p["R"].set(value=100e-9)
    p["nu"].set(value=0.5)
    idnt.fit_model(model_key="hertz_para", params_initial=p, weight_cp=0, range_x=(0, 0), range_type="absolute",
                   segment="approach")
    e_nanite = float(idnt.fit_properties["params_fitted"]["E"].value)
    assert e_nanite == pytest.approx(1.935e9, rel=0.01)
    curve = load(FILE)[0]
    res = analyze(curve)
    assert res.indentation_model == "hertz_paraboloid"
    assert res.details["indentation"].tip_radius == pytest.approx(100e-9, rel=1e-12)     # the header's
    assert res.youngs_modulus == pytest.approx(e_nanite, rel=0.05)
    other = analyze(curve, probe=ProbeCalibration(spring_constant=13.8772))
    assert other.youngs_modulus / res.youngs_modulus == pytest.approx(1.38772, rel=0.03)
