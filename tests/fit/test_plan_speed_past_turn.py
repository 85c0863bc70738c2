"""``afmforce plan --speeds 1um/s,30um/s`` as typed (the walk of 2026-11-29): at 30 um/s the model's
approach (default drive -40 nm to +20 nm; xi = 0.1 kg/s) ends before the lever reaches the surface,
and the plan answered with a measured file's words ("curve 2: no contact reached ... no contact
point, sensitivity, modulus or adhesion; the fit needs curves that reach contact"), exit 1. The
design is the user's: the speed is named and the way out (a later turn, slower speeds) given."""

from __future__ import annotations

from afmforce.cli.main import main


def test_a_speed_whose_model_curve_misses_the_surface_is_named(capsys):
    assert main(["plan", "--speeds", "1um/s,30um/s"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith("error: at 30 um/s the model's approach from -40 nm to 20 nm ends before the tip "
                          "reaches the surface")
    assert "--turn" in err and "Traceback" not in err


def test_a_later_turn_reaches_it(capsys):
    """The way out the message gives works: with the turn at +200 nm the 30 um/s curve is planned."""
    assert main(["plan", "--speeds", "1um/s,30um/s", "--turn", "200nm", "--json"]) == 0
