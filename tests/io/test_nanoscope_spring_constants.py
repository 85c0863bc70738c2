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

from afmforce.analysis.options import IndentationOptions, ProbeCalibration
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


def _nanite_modulus(nu: float) -> float:
    """nanite 4.2.3's Hertz paraboloid E on the curve read by hand from the header's scales (V/LSB
    0.000375, DeflSens 21.9 nm/V, Zsens 8.1 nm/V x ramp 6.17284 V = 50 nm), R = 100 nm, k = 10 N/m."""
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
    p["nu"].set(value=nu)
    idnt.fit_model(model_key="hertz_para", params_initial=p, weight_cp=0, range_x=(0, 0), range_type="absolute",
                   segment="approach")
    return float(idnt.fit_properties["params_fitted"]["E"].value)


def _header_poisson() -> float:
    """``\\Sample Poisson's Ratio`` of the header, read by hand."""
    head = FILE.read_bytes()[:40960].decode("latin-1")
    return float(re.search(r"^\\Sample Poisson's Ratio:\s*(\S+)", head, re.M).group(1))


def test_modulus_agrees_with_nanite_and_scales_with_k():
    """1.90 GPa (Hertz paraboloid, R = 100 nm from the header, nu = 0.5 given, k = 10 N/m); nanite on the
    curve read by hand gives 1.935 GPa. Sub-nanometre indentation (0.78 nm at 23 nN) of a stiff sample: a
    polymer's modulus. With the other list's k (13.8772 N/m) the modulus scales as k (the deflection, and
    so the indentation, does not depend on k): 2.64 GPa."""
    e_nanite = _nanite_modulus(0.5)
    assert e_nanite == pytest.approx(1.935e9, rel=0.01)
    curve = load(FILE)[0]
    half = IndentationOptions(poisson=0.5)
    res = analyze(curve, options=[half])
    assert res.indentation_model == "hertz_paraboloid"
    assert res.details["indentation"].tip_radius == pytest.approx(100e-9, rel=1e-12)     # the header's
    assert res.youngs_modulus == pytest.approx(e_nanite, rel=0.05)
    other = analyze(curve, probe=ProbeCalibration(spring_constant=13.8772), options=[half])
    assert other.youngs_modulus / res.youngs_modulus == pytest.approx(1.38772, rel=0.03)


def test_the_files_poisson_ratio_is_the_default():
    """The header's ``\\Sample Poisson's Ratio: 0.3`` is read (metadata ``poisson``) and used when the user
    gives none: E scales as 1 - nu^2 (the fit is of E / (1 - nu^2)), so E(0.3) / E(0.5) = 0.91 / 0.75 to
    rounding; nanite 4.2.3 with poisson 0.3 on the curve read by hand gives 2.35 GPa (afmforce 2.30). The
    user's value wins, and the result says which ratio it used and where from."""
    nu = _header_poisson()
    assert nu == 0.3
    curve = load(FILE)[0]
    assert curve.metadata["poisson"] == nu
    res = analyze(curve)                                       # no ratio given: the file's
    d = res.details["indentation"]
    assert (d.poisson, d.poisson_source) == (nu, "file")
    assert any("Poisson ratio 0.3 is the file's" in w for w in res.warnings)     # said, as the CLI shows it
    half = analyze(curve, options=[IndentationOptions(poisson=0.5)])
    assert (half.details["indentation"].poisson, half.details["indentation"].poisson_source) == (0.5, "user")
    assert not any("Poisson" in w for w in half.warnings)
    assert res.youngs_modulus / half.youngs_modulus == pytest.approx((1 - nu ** 2) / (1 - 0.5 ** 2), rel=1e-9)
    assert res.youngs_modulus == pytest.approx(_nanite_modulus(nu), rel=0.04)


def test_without_a_ratio_in_the_file_the_default_is_said():
    """A curve whose file states no ratio (or the user's override of the file's) uses 0.5 and says so."""
    curve = load(FILE, meta_override={"poisson": 0.45})[0]
    assert curve.metadata["poisson"] == 0.45                   # the user's metadata wins over the header's
    md = {k: v for k, v in curve.metadata.items() if k != "poisson"}
    o = IndentationOptions()
    assert o.sample_poisson(md) == (0.5, "default")
    assert o.sample_poisson(curve.metadata) == (0.45, "file")
    assert IndentationOptions(poisson=0.2).sample_poisson(curve.metadata) == (0.2, "user")
