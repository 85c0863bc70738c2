"""Bad input to the dynamic fit: one clear message each (library and CLI)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from afmforce.cli.main import main
from afmforce.errors import AnalysisError, FileFormatError, ParameterError
from afmforce.fit import IdentifiabilityError, fit_dynamic
from afmforce.io.native.rawfile import write_raw

from fit_virtual import make_curves, write_curves


@pytest.fixture(scope="module")
def two():
    return make_curves(0.005, seed=3, speeds=(1e-6, 4e-6), spacing=0.5e-9)


@pytest.fixture(scope="module")
def one_speed(two):
    """Two measurements at the first speed, different noise (a curve given twice is refused before:
    tests/fit/test_fit_duplicate_curves.py)."""
    return [two[0], make_curves(0.005, seed=4, speeds=(1e-6,), spacing=0.5e-9)[0]]


def test_one_speed_not_identifiable(one_speed):
    same = one_speed
    with pytest.raises(IdentifiabilityError, match="one driving speed"):
        fit_dynamic(same, "beam", free=("hamaker", "xi"))


def test_inconsistent_calibrations(two):
    other = dataclasses.replace(two[1], metadata={**two[1].metadata, "spring_constant": 0.3})
    with pytest.raises(ParameterError, match="inconsistent calibrations: spring_constant"):
        fit_dynamic([two[0], other], "beam", free=("hamaker", "xi"))


def test_no_contact():
    far = make_curves(0.005, seed=4, speeds=(1e-6, 4e-6), spacing=0.5e-9, start=-60e-9,
                      turn=-10e-9, end=-70e-9)
    with pytest.raises(AnalysisError, match="no contact"):
        fit_dynamic(far, "beam", free=("hamaker", "xi"))


def test_volts_without_sensitivity_calibrated_as_the_analysis(two):
    """Volts without a sensitivity: the analysis's calibration (the approach's compliance slope),
    the same number `afmforce analyze` reports, with a warning naming it (issue 23 item 4)."""
    from afmforce.analysis.pipeline import analyze
    from afmforce.fit import prepare_curves

    meta = {k: v for k, v in two[0].metadata.items() if k != "sensitivity"}
    volts = dataclasses.replace(two[0], deflection_signal=np.asarray(two[0].deflection_signal) / 50e-9,
                                deflection_unit="V", metadata=meta)
    fc = prepare_curves([volts])[0]
    ana = analyze(volts, steps=["calibration"])
    assert ana.calibration_source == "fit"
    assert fc.metadata["calibration"]["sensitivity"] == pytest.approx(ana.sensitivity_fit, rel=1e-12)
    assert fc.metadata["calibration"]["source"] == "compliance"
    assert fc.metadata["calibration"]["sensitivity"] == pytest.approx(50e-9, rel=0.02)   # the truth
    note = fc.metadata["preparation_notes"][0]
    assert f"{ana.sensitivity_fit * 1e9:.4g} nm/V" in note and "(`sensitivity`)" in note


def test_free_parameter_checks(two):
    with pytest.raises(ParameterError, match="no effect in the spring model"):
        fit_dynamic(two, "spring", free=("xi",))
    with pytest.raises(ParameterError, match="unknown free parameter"):
        fit_dynamic(two, "beam", free=("friction",))


def test_cli_one_line_exit_2(one_speed, tmp_path, capsys):
    paths = write_curves(one_speed, tmp_path)
    rc = main(["fit", *map(str, paths), "--free", "hamaker,xi", "--json"])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.startswith("error: ") and err.count("\n") == 1 and "one driving speed" in err
    # the input files are untouched
    assert paths[0].read_text().count("# end") == 1


def test_force_and_volts_calibrated_with_the_files_own_constants(two):
    """A force [N] is divided by the file's spring constant, volts multiplied by its sensitivity."""
    from afmforce.fit import prepare_curves

    c = two[0]
    k, s = c.metadata["spring_constant"], c.metadata["sensitivity"]
    as_n = dataclasses.replace(c, deflection_signal=np.asarray(c.deflection_signal) * k,
                               deflection_unit="N")
    as_v = dataclasses.replace(c, deflection_signal=np.asarray(c.deflection_signal) / s,
                               deflection_unit="V")
    ref, fn, fv = prepare_curves([c, as_n, as_v])
    np.testing.assert_allclose(fn.deflection, ref.deflection, rtol=1e-12)
    np.testing.assert_allclose(fv.deflection, ref.deflection, rtol=1e-12)


def test_retract_missing_or_after_a_pause(two):
    def cut(c, keep):
        return dataclasses.replace(c, **{f: np.asarray(getattr(c, f))[keep] for f in
                                        ("time", "piezo_nominal", "deflection_signal", "segment")},
                                   piezo_measured=None, truth=None)
    approach_only = [cut(c, np.asarray(c.segment) == 0) for c in two]
    with pytest.raises(AnalysisError, match="no retract run directly after the approach"):
        fit_dynamic(approach_only, "beam", free=("hamaker", "xi"), retract=True)
    # a pause at the turn: the retract starts 50 ms after the drive lines meet
    paused = []
    for c in two:
        t = np.asarray(c.time, float).copy()
        t[np.asarray(c.segment) == 1] += 0.05
        paused.append(dataclasses.replace(c, time=t))
    with pytest.raises(AnalysisError, match="pause at the turn is not supported"):
        fit_dynamic(paused, "beam", free=("hamaker", "xi"), retract=True)


def test_speed_and_rate_read_off_the_ramp_when_missing(two):
    """A file without velocity/sample_rate: both come from the approach, with a note."""
    from afmforce.fit.data import prepare_curves

    bare = [dataclasses.replace(c, metadata={k: v for k, v in c.metadata.items()
                                             if k not in ("velocity", "sample_rate")}) for c in two]
    fc = prepare_curves(bare)
    for c, f in zip(two, fc):
        assert f.velocity == pytest.approx(c.metadata["velocity"], rel=1e-9)
        assert f.sample_rate == pytest.approx(c.metadata["sample_rate"], rel=1e-9)
        assert "read off the approach ramp" in f.metadata["velocity_from_ramp"]
    # a ramp that is not straight (a sine) is not taken: the user is asked
    c = bare[0]
    t = np.asarray(c.time, float)
    wave = 5e-9 * np.sin(40 * t / t[-1])
    bent = dataclasses.replace(c, piezo_nominal=np.asarray(c.piezo_nominal) + wave,
                               piezo_measured=np.asarray(c.piezo_measured) + wave)
    with pytest.raises(FileFormatError, match="`velocities`"):       # the key; the CLI renders --velocities
        prepare_curves([bent])


def test_cli_meta_calibrates_volts(two, tmp_path, capsys):
    """Curves recorded in volts without a sensitivity fit with the compliance slope's calibration
    and a warning naming --meta; with --meta sensitivity they fit with the given one."""
    volts = [dataclasses.replace(c, deflection_signal=np.asarray(c.deflection_signal) / 50e-9,
                                 deflection_unit="V",
                                 metadata={k: v for k, v in c.metadata.items() if k != "sensitivity"})
             for c in two]
    paths = write_curves(volts, tmp_path)
    argv = ["fit", *map(str, paths), "--free", "hamaker", "--no-profile", "--no-compare", "--json"]
    import json

    for extra in ([], ["--meta", "sensitivity=50nm/V"]):
        assert main(argv + extra) == 0
        out = capsys.readouterr()
        res = json.loads(out.out)
        assert res["parameters"]["hamaker"]["value"] == pytest.approx(5e-19, rel=0.05)
        # without --meta: calibrated from the compliance slope, said with the flag that overrides it
        assert ("--meta sensitivity=" in out.err) == (not extra)
