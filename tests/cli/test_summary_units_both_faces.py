"""``summary.csv`` names its columns with their units on both faces of a batch (``afmforce analyze FOLDER --out``
and ``--fast-map``): the same quantity, the same column name. Before (findings 2026-11-29) the full path wrote
``youngs_modulus [Pa]`` and the fast map ``youngs_modulus``, its Parquet without the units; both now take the
name from :func:`afmforce.sweep.summary.column_label`, each unit declared once (:func:`column_unit`)."""

from __future__ import annotations

import csv
import json

import pyarrow.parquet as pq
import pytest

from afmforce.cli.main import main
from afmforce.instrument.soft_map import SoftMapConfig, write_soft_map
from afmforce.sweep.map_fast import PIXEL_COLUMNS
from afmforce.sweep.summary import SUMMARY_UNITS, read_summary_csv


@pytest.fixture(scope="module")
def both(tmp_path_factory):
    folder = tmp_path_factory.mktemp("faces")
    path = write_soft_map(SoftMapConfig(nx=2, ny=1, seed=4), folder / "soft.jpk-qi-data", format="jpk-qi")
    flags = ["--serial", "--radius", "5um"]
    assert main(["analyze", str(path), "--fast-map", "--out", str(folder / "fast"), *flags]) == 0
    assert main(["analyze", str(path), "--no-plot", "--out", str(folder / "full"), *flags]) == 0
    return {face: next((folder / face).rglob("summary.csv")) for face in ("fast", "full")}


def _header(path) -> list[str]:
    with path.open(newline="") as fh:
        return next(csv.reader(fh))


def test_the_same_quantity_has_the_same_column_name_on_both_faces(both):
    fast, full = _header(both["fast"]), _header(both["full"])
    bare = lambda labels: {label.partition(" [")[0]: label for label in labels}  # noqa: E731
    fast_names, full_names = bare(fast), bare(full)
    shared = set(fast_names) & set(full_names)
    assert {"youngs_modulus", "adhesion_force", "work_of_adhesion", "position_x", "map_width"} <= shared
    assert {n: fast_names[n] for n in shared} == {n: full_names[n] for n in shared}
    # every number of the fast map's pixel rows names its unit, the full path's units where it has the column
    for name, unit in PIXEL_COLUMNS.items():
        assert fast_names[name] == f"{name} [{unit}]"
        if name in SUMMARY_UNITS:
            assert SUMMARY_UNITS[name] == unit
    assert full_names["youngs_modulus"] == "youngs_modulus [Pa]" == fast_names["youngs_modulus"]


def test_both_faces_tables_read_back_with_their_units(both):
    for face, path in both.items():
        frame = read_summary_csv(path)
        assert frame.attrs["units"]["youngs_modulus"] == "Pa" and frame.attrs["units"]["adhesion_force"] == "N"
        assert len(frame) == 2 and (frame["youngs_modulus"] > 0).all(), face
        units = json.loads(pq.read_schema(path.with_name("summary.parquet")).metadata[b"afmforce.units"])
        assert units["youngs_modulus"] == "Pa" and units["work_of_adhesion"] == "J/m^2", face
