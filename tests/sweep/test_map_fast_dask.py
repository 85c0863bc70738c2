"""The fast map analysis on a multi-worker Dask cluster (issue 35, item 1): the same rows as in
this process, every pixel analysed by the workers reading the map file themselves, curve by curve:
afmforce's map format, JPK QI data and a Bruker NanoScope force volume."""

from __future__ import annotations

import numpy as np

from afmforce.sweep.map_fast import PixelAnalysis, analyze_map
from afmforce.analysis.options import IndentationOptions
from afmforce.instrument.soft_map import SoftMapConfig, write_soft_map
from afmforce.sweep.executors import DaskExecutor

import pytest

CFG = SoftMapConfig(nx=4, ny=3, seed=7)


@pytest.mark.parametrize("fmt, name", [("afmforce-map", "soft.h5"), ("jpk-qi", "soft.jpk-qi-data"),
                                       ("bruker-fv", "soft.spm")])
def test_dask_workers_give_the_serial_rows(dask_client, tmp_path, fmt, name):
    path = write_soft_map(CFG, tmp_path / name, format=fmt)
    analysis = PixelAnalysis(IndentationOptions(tip_radius=CFG.radius, poisson=CFG.poisson))
    serial = analyze_map([path], analysis, executor="serial").table()
    result = analyze_map([path], analysis, executor=DaskExecutor(client=dask_client), chunk_size=3,
                         store=tmp_path / "store")
    assert "Dask" in result.executor and result.chunks_run == 4
    table = result.table()
    assert table["error"].isna().all() and len(table) == CFG.nx * CFG.ny
    key = ["map_y", "map_x"]
    a = serial.sort_values(key).reset_index(drop=True)
    b = table.sort_values(key).reset_index(drop=True)
    for col in ("youngs_modulus", "youngs_modulus_se", "contact_point", "adhesion_force", "work_of_adhesion"):
        assert np.array_equal(a[col].to_numpy(float), b[col].to_numpy(float)), col
