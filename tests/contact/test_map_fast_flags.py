"""``afmforce analyze MAP --fast-map`` takes the facts the full analysis takes, or refuses them: the position
channel (``--channel``) is the one asked for, the tip geometry is the indentation step's (one function,
``indentation.tip_geometry``), and options of steps the fast path does not run are refused, not dropped.

Was: ``--fast-map --channel nominal`` fitted the measured position, and ``--fast-map --calibration fit``
used the file's calibration, both silently."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from afmforce.analysis.options import IndentationOptions, ProbeCalibration
from afmforce.cli.main import main
from afmforce.instrument.soft_map import SoftMapConfig, soft_map_curves, write_soft_map
from afmforce.sweep.map_fast import PixelAnalysis

CFG = SoftMapConfig(nx=2, ny=1, seed=4)
PROBE = ProbeCalibration(radius=CFG.radius)


def test_the_fast_path_reads_the_channel_asked_for():
    c = next(iter(soft_map_curves(CFG)))
    nominal_only = dataclasses.replace(c, piezo_measured=None)
    # a position sensor that reads 3 % more than the piezo's nominal travel, 50 nm further out
    both = dataclasses.replace(c, piezo_measured=np.asarray(c.piezo_nominal) * 1.03 + 50e-9)
    ref = PixelAnalysis(probe=PROBE).row(nominal_only)
    nominal = PixelAnalysis(probe=PROBE, channel="nominal").row(both)
    measured = PixelAnalysis(probe=PROBE).row(both)      # auto: the measured position where recorded
    for key in ("youngs_modulus", "contact_point", "adhesion_force", "max_indentation"):
        assert nominal[key] == pytest.approx(ref[key], rel=1e-12), key
    assert measured["contact_point"] == pytest.approx(ref["contact_point"] * 1.03 + 50e-9, rel=0.02)
    with pytest.raises(Exception, match="measured"):
        PixelAnalysis(probe=PROBE, channel="measured").row(nominal_only)


def test_the_fast_path_takes_the_tip_geometry_as_the_indentation_step_does():
    from afmforce.analysis.indentation import tip_geometry

    c = next(iter(soft_map_curves(CFG)))
    o = IndentationOptions()
    assert tip_geometry(o, PROBE, c.metadata)[0] == CFG.radius
    assert tip_geometry(IndentationOptions(tip_radius=2e-6), PROBE, c.metadata)[0] == 2e-6
    by_option = PixelAnalysis(IndentationOptions(tip_radius=CFG.radius)).row(c)
    by_probe = PixelAnalysis(probe=PROBE).row(c)
    assert by_option["youngs_modulus"] == by_probe["youngs_modulus"] and by_probe["tip_radius"] == CFG.radius


@pytest.mark.parametrize("flags", [["--calibration", "fit"], ["--option", "vdw.max_separation=20nm"]])
def test_options_of_steps_the_fast_path_does_not_run_are_refused(tmp_path, flags, capsys):
    path = write_soft_map(CFG, tmp_path / "soft.jpk-qi-data", format="jpk-qi")
    assert main(["analyze", str(path), "--fast-map", "--serial", "--radius", "5um", *flags]) == 2
    err = capsys.readouterr().err
    assert "--fast-map runs the indentation fit only" in err and "Traceback" not in err


def test_the_fast_path_reads_the_metadata_typed_as_the_files(tmp_path):
    """``--meta poisson=0.3`` reaches the readers as on every other face (was: --fast-map read the maps without
    it, so the fit took the default 0.5): E scales by (1 - 0.3^2) / (1 - 0.5^2) against the default."""
    import csv

    path = write_soft_map(CFG, tmp_path / "soft.jpk-qi-data", format="jpk-qi")
    rows = {}
    for meta in ("0.3", None):
        out = tmp_path / f"out{meta}"
        assert main(["analyze", str(path), "--fast-map", "--serial", "--radius", "5um", "--out", str(out)]
                    + (["--meta", f"poisson={meta}"] if meta else [])) == 0
        (summary,) = out.rglob("summary.csv")
        rows[meta] = {r["name"]: float(r["youngs_modulus [Pa]"]) for r in csv.DictReader(summary.open())}
    for name, e in rows[None].items():
        assert rows["0.3"][name] == pytest.approx(e * (1 - 0.3 ** 2) / (1 - 0.5 ** 2), rel=1e-9)
