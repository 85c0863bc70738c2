"""The JPK QI writer's header speeds are the ones simulated (read back by afmforce and afmformats).

A reader takes a run's speed as ``|z-start - z-end| / duration``. Before, both runs carried the
approach's travel: on ``afmforce simulate``'s default drive (60 nm in, 250 nm out at 2 um/s) the
retract read back at 0.48 um/s and the approach at 1.9934 um/s (its travel over ``n`` sample
intervals, not ``n - 1``). The truth is the simulation's ``velocity`` (the raw file's header).
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.cli.main import main
from afmforce.io import load
from afmforce.io.native.rawfile import read_raw
from afmforce.io.writers import write_jpk_qi


@pytest.mark.parametrize("speeds", [("2um/s", None), ("0.5um/s", "3um/s")])
def test_jpk_qi_header_speed_is_the_simulated_one(tmp_path, speeds):
    raw = tmp_path / "c.txt"
    args = ["simulate", "--instrument", "liquid", "--seed", "1", "--velocity", speeds[0],
            "--raw", str(raw), "--no-progress"]
    if speeds[1]:
        args += ["--retract-velocity", speeds[1]]
    assert main(args) == 0
    c = read_raw(raw)
    v_app = float(c.metadata["velocity"])
    v_ret = float(c.metadata.get("retract_velocity") or v_app)
    # the simulated speeds, independently: the nominal drive's slope over each run
    seg, z, t = (np.asarray(a, float) for a in (c.segment, c.piezo_nominal, c.time))
    for run, v in ((0, v_app), (1, v_ret)):
        assert abs(np.polyfit(t[seg == run], z[seg == run], 1)[0]) == pytest.approx(v, rel=1e-9)
    qi = write_jpk_qi([c], tmp_path / "m.jpk-qi-data", shape=(1, 1), step=1e-6)
    r = load(qi)
    r = r[0] if isinstance(r, list) else r
    assert r.metadata["velocity"] == pytest.approx(v_app, rel=1e-9)
    assert r.metadata["retract_velocity"] == pytest.approx(v_ret, rel=1e-9)
