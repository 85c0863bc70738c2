"""Liquid flags of ``afmforce simulate`` (issue 25): units, media, the same run as the library."""

import json
import warnings

import pytest

from afmforce.cli.main import main
from afmforce.cli.simulate import config_from_args
from afmforce.constants import MEDIA
from afmforce.dynamics import simulate

FLAGS = ["--model", "spring", "--spring-constant", "0.1N/m", "--mass", "10ng", "--radius", "2um",
         "--geometry", "sphere-flat", "--medium", "water", "--hamaker", "1e-20J",
         "--double-layer", "weak_overlap", "--surface-potential=-40mV", "--debye-length", "10nm",
         "--slip-length", "5nm", "--lever-drag", "5e-5", "--velocity", "10um/s",
         "--start=-300nm", "--turn", "30nm", "--end=-300nm", "--sample-rate", "10kHz"]


def test_liquid_flags_build_the_library_config(capsys):
    import argparse
    from afmforce.cli import simulate as S

    p = argparse.ArgumentParser()
    for add in S.ARGUMENT_GROUPS:
        add(p)
    cfg = config_from_args(p.parse_args(FLAGS))
    assert cfg.viscosity == MEDIA["water"]["viscosity"] and cfg.permittivity == MEDIA["water"]["permittivity"]
    assert (cfg.geometry, cfg.double_layer) == ("sphere-flat", "weak_overlap")
    assert cfg.surface_potential == pytest.approx(-0.04) and cfg.debye_length == pytest.approx(10e-9)
    assert cfg.slip_length == pytest.approx(5e-9) and cfg.lever_drag == 5e-5
    # an explicit flag wins over the medium; a salt concentration sets the Debye length
    no_debye = [f for i, f in enumerate(FLAGS) if f != "--debye-length" and FLAGS[i - 1] != "--debye-length"]
    cfg2 = config_from_args(p.parse_args(no_debye + ["--viscosity", "2mPa*s", "--salt-concentration", "1mM"]))
    assert cfg2.viscosity == pytest.approx(2e-3) and cfg2.debye_length == pytest.approx(9.6e-9, rel=5e-3)
    assert main(["simulate", "--json", *FLAGS]) == 0
    s = json.loads(capsys.readouterr().out)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = simulate(cfg)
    assert s["jump_in"]["piezo_position"] == pytest.approx(ref.events.jump_in_position, rel=1e-9)


@pytest.mark.parametrize("argv, match", [
    (["--double-layer", "dlvo"], "double-layer"),
    (["--surface-potential", "3V"], "surface-potential"),
    (["--slip-length", "-1nm"], "slip-length"),
    (["--medium", "honey"], "medium"),
    (["--debye-length", "10nm", "--salt-concentration", "1mM"], "salt_concentration"),
])
def test_bad_liquid_flags_are_one_line(capsys, argv, match):
    try:
        code = main(["simulate", *argv])       # errors found after parsing return 2
    except SystemExit as e:                     # errors found while parsing exit 2
        code = e.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0] and "Traceback" not in err[0]


def test_fit_from_volts_with_a_quadratic_compliance(tmp_path, capsys):
    """Raw files in volts from the ``liquid`` virtual AFM (curved photodiode, drift, 1/f noise),
    the file's spring constant 8 % off: ``afmforce fit --quadratic-compliance`` finds b and k."""
    import dataclasses

    from afmforce.instrument import get_preset
    from afmforce.io.native.rawfile import write_raw

    paths = []
    for i, v in enumerate((10e-6, 40e-6)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tr = simulate(model="spring", mass=1e-11, spring_constant=0.1, radius=5e-6,
                          geometry="sphere-flat", hamaker=5e-21, viscosity=0.89e-3, slip_length=3e-9,
                          lever_drag=1e-5, z0=1e-9, velocity=v, sample_rate=v / 1e-9,
                          start=-200e-9, turn=60e-9, end=-200e-9, sampling="average")
        raw = get_preset("liquid").record(tr, seed=i)
        raw = dataclasses.replace(raw, metadata={**raw.metadata, "spring_constant": 0.108})
        paths.append(str(write_raw(raw, tmp_path / f"v{i}.txt")))
    argv = ["fit", *paths, "--quadratic-compliance", "--model", "spring", "--mass", "10ng",
            "--geometry", "sphere-flat", "--medium", "water", "--radius", "5um", "--hamaker", "5e-21J",
            "--z0", "1nm", "--lever-drag", "1e-5", "--free", "slip_length,spring_constant",
            "--jump-window", "0.3ms", "--no-profile", "--no-compare", "--json"]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["parameters"]["slip_length"]["value"] == pytest.approx(3e-9, abs=0.5e-9)
    assert d["parameters"]["spring_constant"]["value"] == pytest.approx(0.1, rel=0.02)
    assert d["slip_detected"] is None          # no comparison asked for
