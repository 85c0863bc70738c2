"""``afmforce.io.given``: the user's k and InvOLS over a curve read with the file's own, in closed form
(a deflection in metres is volts x InvOLS, a force in newtons volts x InvOLS x k), and the reading that
gives a reader the user's values only where the file cannot be read without them."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from afmforce.analysis.options import ProbeCalibration
from afmforce.errors import MissingMetadataError
from afmforce.instrument.soft_map import SoftMapConfig, soft_map_curves
from afmforce.io.given import FILE_SENSITIVITY, apply_given, file_sensitivity, read_own

S_F, K_F, S_U, K_U = 50e-9, 0.1, 60e-9, 0.12


def _volts():
    c = next(iter(soft_map_curves(SoftMapConfig(nx=1, ny=1, seed=2))))
    return dataclasses.replace(c, metadata={**c.metadata, "sensitivity": S_F, "spring_constant": K_F})


@pytest.mark.parametrize("unit, factor_file, factor_given", [("V", 1.0, 1.0), ("m", S_F, S_U),
                                                               ("N", S_F * K_F, S_U * K_U)])
def test_the_given_calibration_scales_as_the_instrument_computed(unit, factor_file, factor_given):
    v = _volts()
    stored = dataclasses.replace(v, deflection_signal=np.asarray(v.deflection_signal) * factor_file, deflection_unit=unit)
    out = apply_given(stored, ProbeCalibration(sensitivity=S_U, spring_constant=K_U))
    np.testing.assert_allclose(out.deflection_signal, np.asarray(v.deflection_signal) * factor_given, rtol=1e-12)
    if unit == "V":   # volts: converted with the probe's values where they are used
        assert out is stored
        return
    assert out.metadata["sensitivity"] == S_U and out.metadata[FILE_SENSITIVITY] == S_F
    assert out.metadata["spring_constant"] == (K_U if unit == "N" else K_F)
    assert file_sensitivity(out.metadata) == S_F
    assert apply_given(out, ProbeCalibration(sensitivity=S_U, spring_constant=K_U)) is out   # once only


def test_a_files_value_no_lever_has_is_not_rescaled_from():
    v = _volts()
    stored = dataclasses.replace(v, deflection_unit="N", metadata={**v.metadata, "sensitivity": 5.0})  # 5 m/V
    out = apply_given(stored, ProbeCalibration(sensitivity=S_U))
    assert out.deflection_signal is stored.deflection_signal and out.metadata["sensitivity"] == 5.0
    assert "cannot rescale" in out.metadata["given_calibration_note"]


def test_the_reader_gets_the_users_values_only_where_the_file_needs_them():
    seen = []

    def reader(meta):
        seen.append(dict(meta))
        if "spring_constant" not in meta:
            raise MissingMetadataError("no spring constant")
        return meta

    probe = ProbeCalibration(sensitivity=S_U, spring_constant=K_U)
    assert read_own(reader, {"sample_rate": 1e3, "sensitivity": S_U}, probe) == \
        {"sample_rate": 1e3, "sensitivity": S_U, "spring_constant": K_U}
    assert seen[0] == {"sample_rate": 1e3}       # first the file's own (the typed sample rate kept)
    assert read_own(lambda meta: meta, {"sensitivity": 40e-9}, probe) == {"sensitivity": 40e-9}  # typed as the file's


def test_a_given_sensitivity_that_cannot_rescale_the_stored_force_is_said():
    """A force file without its InvOLS (tests/data/chiaro-txt_AEBP1_Indentation_002_thinned.txt): the forces stay
    the file's, and the analysis says the given sensitivity was not applied (was: "yours is used", silently)."""
    from pathlib import Path

    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load
    from afmforce.io.given import GIVEN_NOTE

    c = load(Path(__file__).resolve().parents[1] / "data" / "chiaro-txt_AEBP1_Indentation_002_thinned.txt")[0]
    assert c.deflection_unit == "N" and c.metadata.get("sensitivity") is None
    out = apply_given(c, ProbeCalibration(sensitivity=S_U))
    assert out.deflection_signal is c.deflection_signal and "cannot rescale" in out.metadata[GIVEN_NOTE]
    res = analyze(c, probe=ProbeCalibration(sensitivity=S_U))
    assert res.adhesion_force == analyze(c).adhesion_force
    assert any("yours cannot rescale it" in w and "60 nm/V" in w for w in res.warnings)
    # not reported as the forces' sensitivity either (was "sens. used 60 (user)"): the file's, which it has none of
    assert math.isnan(res.sensitivity_used)
    assert not any("yours is used" in w for w in res.warnings)
    no_k = dataclasses.replace(c, metadata={k: v for k, v in c.metadata.items() if k != "spring_constant"})
    assert apply_given(no_k, ProbeCalibration(spring_constant=K_U)) is no_k   # a k turns the force into deflections
