"""The virtual AFM's files record the lever body's drag in a liquid as they record its Q: the
metadata key ``lever_drag`` [N s/m] (``lever_height`` [m] too when the drag is not constant), in its
declared unit, read back by the text and HDF5 readers. Before, a liquid lever's drag was in the
simulation only: a file could not say what its lever's drag was."""

from __future__ import annotations

import pytest

pytest.importorskip("afmforce.dynamics")

from afmforce._fields import QUANTITIES  # noqa: E402
from afmforce.dynamics import simulate  # noqa: E402
from afmforce.errors import FileFormatError  # noqa: E402
from afmforce.instrument import get_preset  # noqa: E402
from afmforce.io import load  # noqa: E402
from afmforce.io.native.rawfile import parse_text, write_raw  # noqa: E402

LIQUID = dict(model="spring", mass=1e-11, geometry="sphere-flat", radius=5e-6, viscosity=1e-3,
              velocity=1e-5, start=-300e-9, turn=60e-9, end=-300e-9, quality_factor=3.0)


def test_a_constant_drag_round_trips_with_q(tmp_path):
    tr = simulate(lever_drag=2e-5, **LIQUID)
    curve = get_preset("ideal").record(tr, seed=1)
    assert curve.metadata["lever_drag"] == 2e-5 and curve.metadata["quality_factor"] == 3.0
    assert "lever_height" not in curve.metadata              # constant drag: no height recorded
    text = write_raw(curve, tmp_path / "l.txt")
    assert f"# lever_drag: 2e-05 {QUANTITIES['lever_drag'].unit}" in text.read_text().splitlines()
    for path in (text, write_raw(curve, tmp_path / "l.h5")):
        back = load(path)[0].metadata
        assert back["lever_drag"] == 2e-5 and back["quality_factor"] == 3.0


def test_a_height_dependent_drag_records_its_height_and_air_records_none(tmp_path):
    tr = simulate(lever_drag=2e-5, lever_height=4e-6, **LIQUID)
    back = load(write_raw(get_preset("ideal").record(tr, seed=1), tmp_path / "h.txt"))[0].metadata
    assert back["lever_drag"] == 2e-5 and back["lever_height"] == 4e-6
    air = get_preset("ideal").record(simulate(model="spring", velocity=1e-6), seed=1).metadata
    assert "lever_drag" not in air and "lever_height" not in air


def test_a_written_drag_in_other_units_reads_as_si_and_a_negative_one_is_refused(tmp_path):
    head = ('# format: "afmforce-raw"\n# version: 1\n{extra}'
            "time [s]\tpiezo_nominal [m]\tdeflection_signal [m]\tsegment [1]\n0\t0\t0\t0\n1\t1e-9\t0\t1\n")
    assert parse_text(head.format(extra="# lever_drag: 20 ug/s\n")).metadata["lever_drag"] == pytest.approx(2e-8)
    bad = tmp_path / "neg.txt"
    bad.write_text(head.format(extra="# lever_drag: -1 kg/s\n"))
    with pytest.raises(FileFormatError, match=r"metadata lever_drag \[kg/s\] must be a finite number >= 0, got -1"):
        load(bad)
