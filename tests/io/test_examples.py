"""Every registered format has a file in tests/data, and the example files written by
tests/data/make_format_examples.py hold what their sources hold.

The coverage test loads every file and collects the reader each curve records, so a
format added to ``afmforce.io.FORMATS`` without a file here fails. The example files
are checked against their sources, read independently (afmformats, the JPK archive
through the jpk-zip reader, the Chiaro file's own text), never against our own output
of the same file.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from afmforce.io import FORMATS, is_supported, load
from realdata import real_path  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

DATA = Path(__file__).resolve().parents[1] / "data"
OVERRIDES = json.loads((DATA / "meta_override.json").read_text())
FILES = sorted(p for p in DATA.iterdir() if is_supported(p))
#: the real-file corpus (tests/data/corpus, its own table and gallery test): counts for the coverage
CORPUS = json.loads((DATA / "corpus" / "corpus.json").read_text())
SHARED_MAP = real_path("afmformats_jpk-fd_map2x2_extracted.jpk-force-map")  # 0.95 MB: not copied


def test_every_registered_format_has_a_file():
    readers: dict[str, list[str]] = {}
    for path in FILES:
        for curve in load(path, meta_override=OVERRIDES.get(path.name)):
            readers.setdefault(curve.metadata["reader"], []).append(path.name)
    for name, entry in CORPUS.items():
        if entry["expect"]["read"] == "read":
            for curve in load(DATA / "corpus" / name, meta_override=entry.get("given")):
                readers.setdefault(curve.metadata["reader"], []).append(name)
    assert set(readers) <= set(FORMATS)  # every recorded reader is a registry identifier
    missing = sorted(set(FORMATS) - set(readers))
    assert not missing, (f"formats without a file in tests/data or tests/data/corpus: {missing}; add a small example "
                         "(tests/data/make_format_examples.py) and list it in tests/data/README.md")


def test_every_file_is_listed_in_the_readme():
    readme = (DATA / "README.md").read_text()
    assert [p.name for p in FILES if f"`{p.name}`" not in readme] == []


def test_afmforce_raw_text_is_the_jpk_curve_thinned():
    """Every 8th sample of jpk_cellhesion_spot3 in raw volts, bit for bit, with the file's k and InvOLS."""
    src = load(DATA / "jpk_cellhesion_spot3.jpk-force", format="jpk-zip")[0]
    c = load(DATA / "afmforce-raw_jpk-cellhesion-spot3.txt")[0]
    assert c.metadata["reader"] == "afmforce-raw" and c.deflection_unit == "V"
    for name in ("time", "piezo_nominal", "piezo_measured", "deflection_signal", "segment"):
        np.testing.assert_array_equal(getattr(c, name), getattr(src, name)[::8], err_msg=name)
    assert c.metadata["spring_constant"] == src.metadata["spring_constant"]
    assert c.metadata["sensitivity"] == src.metadata["sensitivity"]
    assert c.metadata["sample_rate"] == pytest.approx(2000.0 / 8)


def test_afmforce_hdf5_is_the_documented_virtual_afm_run():
    """`afmforce simulate --instrument typical --seed 1 --velocity 1um/s --acquisition-sample-rate 2kHz`:
    2 kHz samples, the approach commanded at 1 um/s, truth arrays sample for sample."""
    c = load(DATA / "afmforce-hdf5_virtual-afm.h5")[0]
    assert c.metadata["reader"] == "afmforce-hdf5" and c.deflection_unit == "V"
    assert (c.metadata["instrument"], c.metadata["seed"]) == ("typical+custom", 1)  # typical, own sample rate
    np.testing.assert_allclose(np.diff(c.time), 1 / 2000, rtol=1e-9)
    app = c.segment == 0
    slope = np.polyfit(c.time[app], c.truth["piezo_position"][app], 1)[0]
    assert slope == pytest.approx(1e-6, rel=1e-9)  # the commanded ramp (piezo_nominal: what the instrument reports)
    assert {"separation", "normal_force", "deflection", "piezo_position"} <= set(c.truth)
    assert all(np.shape(c.truth[k]) == (len(c),) for k in ("separation", "normal_force"))
    assert c.truth["separation"][0] > 30e-9  # starts 40 nm away (the paper's Fig 5 start)


@pytest.mark.skipif(SHARED_MAP is None, reason="shared/data/real not present (the map is too large for tests/data)")
def test_afmforce_map_holds_the_jpk_map_corners_thinned():
    src = load(SHARED_MAP)
    curves = load(DATA / "afmforce-map_jpk-map2x2.h5")
    assert [c.metadata["reader"] for c in curves] == ["afmforce-map"] * 4
    assert [(c.metadata["map_x"], c.metadata["map_y"]) for c in curves] == [(0, 0), (9, 0), (9, 9), (0, 9)]
    assert {(c.metadata["map_nx"], c.metadata["map_ny"]) for c in curves} == {(10, 10)}
    for c, s in zip(curves, src):
        step = len(s) // 300
        np.testing.assert_array_equal(c.deflection_signal, s.deflection_signal[::step])
        np.testing.assert_array_equal(c.piezo_measured, s.piezo_measured[::step])
        np.testing.assert_array_equal(c.segment, s.segment[::step])
        assert c.metadata["sample_rate"] == pytest.approx(s.metadata["sample_rate"] / step)
        assert c.metadata["spring_constant"] == s.metadata["spring_constant"]


def _afmformats(path: Path):
    import afmformats

    return afmformats.load_data(path)[0]


def test_afmformats_hdf5_export_is_the_jpk_curve_thinned():
    """afmformats' HDF5 export stores float64: force and heights equal afmformats' reading of the
    source, every 8th sample; a user's spring constant rescales the force (afmformats refuses it)."""
    src = _afmformats(DATA / "jpk_cellhesion_spot3.jpk-force")
    path = DATA / "afmformats-hdf5_jpk-cellhesion-spot3.h5"
    c = load(path)[0]
    assert c.metadata["reader"] == "afmformats-hdf5" and c.deflection_unit == "N"
    np.testing.assert_array_equal(c.deflection_signal, np.asarray(src["force"])[::8])
    np.testing.assert_array_equal(np.abs(c.piezo_measured), np.abs(np.asarray(src["height (measured)"])[::8]))
    np.testing.assert_array_equal(c.segment, np.asarray(src["segment"])[::8])
    assert c.metadata["spring_constant"] == src.metadata["spring constant"]
    k2 = 2.5 * src.metadata["spring constant"]
    c2 = load(path, meta_override={"spring_constant": k2})[0]
    np.testing.assert_allclose(c2.deflection_signal, 2.5 * c.deflection_signal, rtol=1e-12)
    assert c2.metadata["spring_constant"] == k2


def test_afmformats_tab_export_is_split_like_the_igor_wave():
    """afmformats exports the Asylum curve with every sample in segment 0; the reader splits it at
    the turning point, where afmforce's Igor reader splits the wave (sample 1008 -> 252 of every 4th)."""
    src = _afmformats(DATA / "asylum-mfp3d_SiN-tip_air.ibw")
    ibw = load(DATA / "asylum-mfp3d_SiN-tip_air.ibw")[0]
    c = load(DATA / "afmformats-tab_asylum-sin-tip.tab")[0]
    assert c.metadata["reader"] == "afmformats-tab" and "segments_note" in c.metadata
    assert not np.any(np.asarray(src["segment"]))  # what afmformats writes
    np.testing.assert_array_equal(c.segment, ibw.segment[::4])
    np.testing.assert_allclose(c.deflection_signal, np.asarray(src["force"])[::4], rtol=6e-8)  # %.8g text
    np.testing.assert_allclose(c.piezo_measured, ibw.piezo_measured[::4], rtol=6e-8)
    assert c.metadata["sensitivity"] == pytest.approx(44.99e-9)


def test_chiaro_file_against_its_own_columns_and_header():
    """The real Chiaro export (thinned): load [uN] and piezo [nm] columns read with numpy, k and the
    piezo speed from its header; the approach ends at the maximum load (afmformats' rule)."""
    path = DATA / "chiaro-txt_AEBP1_Indentation_002_thinned.txt"
    raw = path.read_bytes()
    assert b"Max load (\xb5N)" in raw  # ISO-8859-1 as exported: no transcoding needed
    lines = raw.decode("latin-1").splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("Time (s)\tLoad (uN)"))
    table = np.array([[float(v) for v in ln.split("\t")] for ln in lines[head + 1:] if ln.strip()])
    c = load(path)[0]
    assert c.metadata["reader"] == "chiaro-txt" and "note" not in c.metadata
    np.testing.assert_allclose(c.deflection_signal, table[:, 1] * 1e-6, rtol=1e-12)
    np.testing.assert_allclose(c.time, table[:, 0], rtol=1e-12)
    np.testing.assert_allclose(np.abs(c.piezo_nominal), np.abs(table[:, 4]) * 1e-9, rtol=1e-12)
    assert np.sum(c.segment == 0) == np.argmax(table[:, 1]) + 1
    assert c.metadata["spring_constant"] == 0.019  # "k (N/m)	0.019"
    assert c.metadata["velocity"] == pytest.approx(7e-6)  # "Piezo speed  (um/s)	7.000"
    # the retract runs ~11x faster than the header's one speed: its speed comes from the columns
    ret = np.flatnonzero(c.segment == 1)
    travel = abs(table[ret[-1], 4] - table[ret[0], 4]) * 1e-9 / (table[ret[-1], 0] - table[ret[0], 0])
    assert c.metadata["retract_velocity"] == pytest.approx(travel, rel=1e-9) and travel > 70e-6
    assert "header 'Piezo speed'" in c.metadata["retract_velocity_note"]


def test_copies_of_the_shared_real_files_are_identical():
    """tests/realdata.py uses tests/data's copies where the shared folder is absent: they must
    be the same bytes (the renamed ones included)."""
    from realdata import COPIES, DATA, SHARED

    if not SHARED.is_dir():
        pytest.skip("shared/data/real not present: nothing to compare the copies with")
    pairs = [(SHARED / name, DATA / COPIES.get(name, name)) for name in sorted(
        p.name for p in SHARED.iterdir() if p.suffix != ".md") if (DATA / COPIES.get(name, name)).is_file()]
    assert len(pairs) >= 9
    for shared, copy in pairs:
        assert shared.read_bytes() == copy.read_bytes(), copy.name
