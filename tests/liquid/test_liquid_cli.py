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
