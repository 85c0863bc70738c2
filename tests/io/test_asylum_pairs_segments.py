"""Asylum force-map curves saved one wave per channel whose note has four ``Indexes`` and no
``Direction`` (corpus5): BAMresearch/SOFA's ``test_data/fdc_data_*/LineNNNN/LineNNNNPointMMMM{Defl,ZSnsr}.ibw``
(GPL-3.0, not redistributed; note ``XLVDT``, ``YLVDT``, ``Indexes:0,2487,5015,5214`` only, 5 kHz from
the wave's own x scaling) sweep towards the surface, back, then dwell 200 samples away from it. The
reader took four indexes for approach, dwell at the surface, retract: the whole retract became a
"dwell" and the 200 far samples the "retract", and `afmforce analyze ... --spring-constant 0.1` refused
("no contact region found on the retract run"). The segments now follow the position's own motion
(the still segment is the dwell, wherever it lies); a dwell at the surface stays one. Waves written
here with known content (`write_ibw` of test_asylum_pairs.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import FileFormatError
from afmforce.io import load
from test_asylum_pairs import write_ibw  # noqa: E402  (tests/io is the rootdir of this module's imports)

N_APP, N_RET, N_DWELL = 400, 420, 60


def _curve(dwell_at: str):
    """ZSnsr [m] (rising towards the surface, as Asylum's) and Defl [m] of an approach, a retract and a
    dwell (at the end, away from the surface; or between the sweeps, at the surface), and the codes."""
    app = np.linspace(-1.4e-6, -0.3e-6, N_APP)
    ret = np.linspace(-0.3e-6, -1.4e-6, N_RET)
    if dwell_at == "away":
        z = np.concatenate([app, ret, np.full(N_DWELL, -1.4e-6) + np.linspace(0, -4e-9, N_DWELL)])
        codes = np.repeat([0, 1, 2], [N_APP, N_RET, N_DWELL])
    else:
        z = np.concatenate([app, np.full(N_DWELL, -0.3e-6), ret])
        codes = np.repeat([0, 2, 1], [N_APP, N_DWELL, N_RET])
    defl = np.clip(z + 0.36e-6, 0, None) * 0.7
    return z, defl, codes


@pytest.mark.parametrize("dwell_at", ["away", "surface"])
def test_four_indexes_without_direction_follow_the_positions_motion(tmp_path: Path, dwell_at):
    z, defl, codes = _curve(dwell_at)
    edges = np.flatnonzero(np.diff(codes)) + 1
    note = f"XLVDT:1.2e-06\rYLVDT:3.4e-06\rIndexes:0,{edges[0]},{edges[1]},{z.size - 1},\r"
    write_ibw(tmp_path / "Line0000Point0000Defl.ibw", defl, note, step=2e-4, name="Line0000Point0000Defl")
    write_ibw(tmp_path / "Line0000Point0000ZSnsr.ibw", z, note, step=2e-4, name="Line0000Point0000ZSnsr")
    c = load(tmp_path / "Line0000Point0000Defl.ibw", meta_override={"spring_constant": 0.1})[0]
    np.testing.assert_array_equal(c.segment, codes)
    assert c.metadata["sample_rate"] == pytest.approx(5000)  # the wave's x step, 0.2 ms
    np.testing.assert_allclose(c.deflection_signal, defl.astype("f4"), rtol=1e-6)


def test_motion_that_does_not_tell_keeps_the_old_reading(tmp_path: Path):
    """Three sweeps (no still segment): the motion does not tell, four indexes stay approach, dwell,
    retract as before."""
    z = np.concatenate([np.linspace(0, 1e-6, 100), np.linspace(1e-6, 0.5e-6, 100), np.linspace(0.5e-6, 0, 100)])
    note = "Indexes:0,100,200,299,\r"
    write_ibw(tmp_path / "P0000Defl.ibw", np.clip(z - 0.8e-6, 0, None), note)
    write_ibw(tmp_path / "P0000ZSnsr.ibw", z, note)
    c = load(tmp_path / "P0000Defl.ibw", meta_override={"spring_constant": 0.1})[0]
    np.testing.assert_array_equal(c.segment, np.repeat([0, 2, 1], 100))


@pytest.mark.parametrize("lead, trail", [(173, 0), (3, 5)])
def test_nan_padding_of_both_channels_is_dropped_and_said(tmp_path: Path, lead, trail):
    """SOFA's ``fdc_without_image`` curves (no note at all, 5024 samples, x step 0.995 ms) start with 2-173
    NaN samples in both waves: refused before ("column piezo_nominal has 173 non-finite values ...: remove
    those rows", of a binary file); the padding is dropped now, counted in ``unrecorded_samples``, and the
    time keeps each recorded sample's place (the wave's x scaling)."""
    z = np.concatenate([np.linspace(0, 1e-6, 300), np.linspace(1e-6, 0, 300)])
    defl = np.clip(z - 0.8e-6, 0, None) * 0.5
    pad = lambda a: np.concatenate([np.full(lead, np.nan), a, np.full(trail, np.nan)])  # noqa: E731
    write_ibw(tmp_path / "P0030Defl.ibw", pad(defl), "", step=1e-3)
    write_ibw(tmp_path / "P0030ZSnsr.ibw", pad(z), "", step=1e-3)
    c = load(tmp_path / "P0030Defl.ibw", meta_override={"spring_constant": 0.1})[0]
    assert len(c) == 600 and c.metadata["unrecorded_samples"] == lead + trail
    np.testing.assert_allclose(c.deflection_signal, defl.astype("f4"), rtol=1e-6)
    np.testing.assert_allclose(c.time, (lead + np.arange(600)) * 1e-3)
    assert (c.approach.sum(), c.retract.sum()) == (299, 301)  # turns at the top of z (sample 299)


def test_nan_inside_the_data_is_still_refused(tmp_path: Path):
    z = np.concatenate([np.linspace(0, 1e-6, 50), np.linspace(1e-6, 0, 50)])
    defl = z * 0.1
    defl[40] = np.nan
    write_ibw(tmp_path / "P0001Defl.ibw", defl, "")
    write_ibw(tmp_path / "P0001ZSnsr.ibw", z, "")
    with pytest.raises(FileFormatError, match="non-finite values"):
        load(tmp_path / "P0001Defl.ibw", meta_override={"spring_constant": 0.1})
