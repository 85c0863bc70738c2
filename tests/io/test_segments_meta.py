"""Segments taken by their type, and the user's metadata reaching every reader (issues 13.5, 13.6, 14).

Expected values come from the files themselves (segment headers read with zipfile, CSV
columns read with numpy), from shared/data/real/README.md, or from afmformats (an
independent reader), never from our own output.
"""

from __future__ import annotations

import itertools
import json
import zipfile
from pathlib import Path

import numpy as np
import pytest

from afmforce.errors import MissingMetadataError, ParameterError
from afmforce.io import is_supported, load, require_metadata
from afmforce.io._meta import segment_code
from afmforce.io.jpk_zip import parse_properties
from realdata import SHARED, real_file  # noqa: E402  (tests/ is on sys.path: tests/conftest.py)

DATA = Path(__file__).resolve().parents[1] / "data"
OVERRIDES = json.loads((DATA / "meta_override.json").read_text())


def _runs(segment: np.ndarray) -> list[tuple[int, int]]:
    return [(int(k), len(list(g))) for k, g in itertools.groupby(segment)]


def _real(name: str) -> Path:
    return real_file(name)


@pytest.mark.parametrize("style,code", [("extend", 0), ("Retract", 1), ("pause", 2), ("dwell", 2),
                                        ("modulation", 2), ("approach", 0)])
def test_segment_words(style, code):
    assert segment_code(style) == code


def test_stress_relaxation_segments_by_type():
    """prep pause (256), extend (2048), dwell pause (7680), retract (1951): file order 0..3 from
    afmformats becomes dwell, approach, dwell, retract; sizes and styles from the segment headers."""
    path = DATA / "afmformats_jpk-sr_cell1-0008.jpk-force"
    with zipfile.ZipFile(path) as arc:
        heads = [parse_properties(arc.read(f"segments/{i}/segment-header.properties").decode()) for i in range(4)]
    styles = [h["force-segment-header.settings.style"] for h in heads]
    sizes = [int(h["force-segment-header.num-points"]) for h in heads]
    assert styles == ["pause", "extend", "pause", "retract"]
    c = load(path)[0]
    assert _runs(c.segment) == list(zip([2, 0, 2, 1], sizes))
    assert [st in t for st, t in zip(styles, c.metadata["segment_types"])] == [True] * 4  # e.g. "pause-spm"
    assert c.metadata["spring_constant"] == pytest.approx(1.0677)
    assert c.metadata["sensitivity"] == pytest.approx(110.28e-9)
    assert c.metadata["sample_rate"] == pytest.approx(2048.0)  # the approach's rate, not the prep's
    z = c.piezo_measured if c.piezo_measured is not None else c.piezo_nominal
    app = np.flatnonzero(c.approach)
    assert z[app[-1]] > z[app[0]]
    assert np.all(np.diff(c.time) > 0)


def test_cellhesion_pause_segments_via_jpk_zip():
    """README: k = 0.0233316 N/m, 65.363 nm/V, 6 kHz; 60000 extend, 30000 pause, 60000 retract,
    and a 2-point pause-at-start stored last, put first in time."""
    c = load(_real("jpkfile_force-save-2016.06.15-13.17.08.jpk-force"))[0]
    volts = load(_real("jpkfile_force-save-2016.06.15-13.17.08.jpk-force"), format="jpk-zip")[0]
    assert volts.metadata["reader"] == "jpk-zip" and volts.deflection_unit == "V"
    assert c.deflection_unit == "N"  # the file's own k and sensitivity
    np.testing.assert_allclose(c.deflection_signal, volts.deflection_signal * 0.0233316 * 65.363e-9, rtol=1e-4)
    assert _runs(c.segment) == [(2, 2), (0, 60000), (2, 30000), (1, 60000)]
    assert c.metadata["segment_types"][0] == "pause-at-start-cellhesion200"
    assert c.metadata["spring_constant"] == pytest.approx(0.0233316, rel=1e-5)
    assert c.metadata["sensitivity"] == pytest.approx(65.363e-9, rel=1e-4)
    assert c.metadata["sample_rate"] == pytest.approx(6000.0)
    assert np.all(np.diff(c.time) > 0)


def test_jpk_map_grid_positions():
    """The 2x2 extract of a 10x10 JPK map: grid indices (0,0), (9,0), (9,9), (0,9), k and sensitivity
    from README (0.015482 N/m, 64.26 nm/V)."""
    path = _real("afmformats_jpk-fd_map2x2_extracted.jpk-force-map")
    curves = load(path)
    with zipfile.ZipFile(path) as arc:
        sizes = [[int(parse_properties(arc.read(f"index/{i}/segments/{j}/segment-header.properties").decode())
                      ["force-segment-header.num-points"]) for j in (0, 1)] for i in range(4)]
    assert [(c.metadata["map_x"], c.metadata["map_y"]) for c in curves] == [(0, 0), (9, 0), (9, 9), (0, 9)]
    assert {(c.metadata["map_nx"], c.metadata["map_ny"]) for c in curves} == {(10, 10)}
    for c, (n_ext, n_ret) in zip(curves, sizes):
        assert c.metadata["spring_constant"] == pytest.approx(0.015482, rel=1e-4)
        assert c.metadata["sensitivity"] == pytest.approx(64.26e-9, rel=1e-4)
        assert _runs(c.segment) == [(0, n_ext), (1, n_ret)]


def test_jpk_without_spring_constant_uses_the_flag():
    """afmformats with meta_override k = 12 N/m gives force[0] = -5.2617e-7 N (README); so must we.
    Without k the curve is read in volts and asking for k names `spring_constant` (the CLI: --spring-constant)."""
    path = _real("afmformats_jpk-fd_single-modified_2023.jpk-force")
    volts = load(path)[0]
    assert volts.deflection_unit == "V" and "spring_constant" not in volts.metadata
    assert volts.metadata["sensitivity"] == pytest.approx(89.32e-9, rel=1e-4)
    with pytest.raises(MissingMetadataError, match="give `spring_constant`") as err:
        load(path, require=("spring_constant", "sensitivity"))
    assert str(path) in str(err.value) and "sensitivity`" not in str(err.value)
    assert err.value.keys == ("spring_constant",)
    c = load(path, meta_override={"spring_constant": 12.0})[0]
    assert c.deflection_unit == "N" and c.metadata["spring_constant"] == 12.0
    assert c.deflection_signal[0] == pytest.approx(-5.2617e-7, rel=1e-4)
    # independent: the volts times the file's sensitivity times the user's k
    np.testing.assert_allclose(c.deflection_signal, volts.deflection_signal * volts.metadata["sensitivity"] * 12,
                               rtol=1e-9)


def test_workshop_volts_csv_needs_both_flags_and_then_loads():
    path = DATA / "afmformats_afm-workshop-fd_single_2018-08-01.csv"
    with pytest.raises(MissingMetadataError, match="give `spring_constant` and `sensitivity`") as err:
        load(path)
    assert str(path) in str(err.value) and "\n" not in str(err.value)
    c = load(path, meta_override=OVERRIDES[path.name])[0]
    rows = np.array([[float(v) for v in ln.split(",")] for ln in path.read_text().splitlines()
                     if ln[:1].isdigit()])
    assert c.deflection_unit == "V"
    np.testing.assert_allclose(c.deflection_signal[c.approach], rows[:, 1], rtol=1e-9)  # Extend T-B(V)
    z = c.piezo_nominal[c.approach]  # Z-sense [nm], oriented to increase on the approach
    np.testing.assert_allclose(np.abs(z), rows[:, 0] * 1e-9, rtol=1e-9)
    assert z[-1] > z[0]
    assert c.metadata["spring_constant"] == 0.1 and c.metadata["sensitivity"] == 50e-9


def test_ibw_override_rescales_the_force():
    """afmformats' Igor reader ignores meta_override: we rescale (force = k x volts x InvOLS)."""
    path = DATA / "asylum-mfp3d_SiN-tip_air.ibw"
    a = load(path)[0]
    b = load(path, meta_override={"spring_constant": 2.0, "sensitivity": 50e-9})[0]
    np.testing.assert_allclose(b.deflection_signal, a.deflection_signal * (2.0 / 1.1841) * (50 / 44.99), rtol=1e-9)
    assert b.metadata["spring_constant"] == 2.0 and b.metadata["sensitivity"] == 50e-9


def test_jpk_override_recomputes_the_force():
    """afmformats recomputes a JPK force from volts with the user's k and sensitivity."""
    path = DATA / "jpk_cellhesion_spot3.jpk-force"
    volts = load(path, format="jpk-zip")[0]
    c = load(path, meta_override={"spring_constant": 0.1, "sensitivity": 80e-9})[0]
    np.testing.assert_allclose(c.deflection_signal, volts.deflection_signal * 0.1 * 80e-9, rtol=1e-9)


@pytest.mark.parametrize("name", ["bruker-nanoscope_synthetic.txt", "jpk_calibration-curve_raw-volts.jpk-force"])
def test_override_reaches_our_own_readers(name):
    c = load(DATA / name, meta_override={"spring_constant": 3.0, "sensitivity": 7e-9})[0]
    assert c.metadata["spring_constant"] == 3.0 and c.metadata["sensitivity"] == 7e-9


def test_require_metadata_rules(tmp_path):
    c = load(DATA / "jpk_calibration-curve_raw-volts.jpk-force")[0]  # volts, neither k nor sensitivity
    with pytest.raises(MissingMetadataError) as err:
        require_metadata(c)
    assert err.value.keys == ("spring_constant", "sensitivity") and "--" not in str(err.value)   # keys, no flags
    with pytest.raises(ParameterError, match="unknown metadata"):
        require_metadata(c, ("colour",))
    forces = load(DATA / "afm-workshop_single.csv")[0]  # force in N: needs neither
    require_metadata(forces)


def test_cli_names_the_flag_and_exits_2(capsys):
    from afmforce.cli.main import main

    code = main(["analyze", str(DATA / "afmformats_afm-workshop-fd_single_2018-08-01.csv"), "--json"])
    out = capsys.readouterr()
    assert "--spring-constant" in out.out + out.err
    assert "Traceback" not in out.err
    assert code != 0


@pytest.mark.parametrize("fmt", ["hdf5", "tab"])
def test_afmformats_exports_load(tmp_path, fmt):
    """afmformats' own HDF5 and tab exports of a JPK curve read back to the same force and segments."""
    import afmformats

    src = DATA / "jpk_cellhesion_spot3.jpk-force"
    dd = afmformats.load_data(src)[0]
    out = tmp_path / f"export.{'h5' if fmt == 'hdf5' else 'tab'}"
    dd.export_data(out, fmt=fmt)
    c = load(out)[0]
    ref = load(src)[0]
    assert c.metadata["reader"] == f"afmformats-{fmt}"  # the registry identifier
    np.testing.assert_allclose(c.deflection_signal, ref.deflection_signal, rtol=1e-6)
    np.testing.assert_array_equal(c.segment, ref.segment)
    assert c.metadata["spring_constant"] == pytest.approx(ref.metadata["spring_constant"])


def test_formats_cli_lists_every_format(capsys):
    from afmforce.cli.main import main
    from afmforce.io import FORMATS

    assert main(["formats", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["formats"]
    assert [r["identifier"] for r in rows] == list(FORMATS)
    assert main(["formats"]) == 0
    assert "bruker-nanoscope" in capsys.readouterr().out


#: the shared real files; without the shared folder, the files of tests/data (copies of most)
REAL_FILES = (sorted(p for p in SHARED.glob("*") if p.suffix != ".md") if SHARED.is_dir()
              else sorted(p for p in DATA.iterdir() if is_supported(p)))


@pytest.mark.parametrize("path", REAL_FILES, ids=lambda p: p.name)
def test_every_shared_real_file_loads_or_names_the_flag(path):
    """Every real file in shared/data/real loads, or fails with one line naming what to give."""
    try:
        curves = load(path)
    except MissingMetadataError as exc:
        assert "\n" not in str(exc) and set(exc.keys) & {"spring_constant", "sensitivity"}
        curves = load(path, meta_override={k: 1.0 if k == "spring_constant" else 50e-9 for k in exc.keys})
    for c in curves:
        assert np.isfinite(c.deflection_signal).all() and np.all(np.diff(c.time) > 0)
        assert c.approach.any() and c.retract.any()


def test_other_metadata_overrides_reach_the_readers():
    """--meta sample_rate=2kHz gives a time base to a file without one (AFM Workshop)."""
    from afmforce.io._meta import parse_meta_args

    meta = parse_meta_args(["sample_rate=2kHz", "velocity=1um/s", "instrument=AFMW"])
    assert meta == {"sample_rate": 2000.0, "velocity": pytest.approx(1e-6), "instrument": "AFMW"}
    c = load(DATA / "afm-workshop_single.csv", meta_override=meta)[0]
    assert c.time[1] - c.time[0] == pytest.approx(1 / 2000) and not c.metadata.get("time_is_sample_index")
    assert c.metadata["velocity"] == pytest.approx(1e-6)
    for bad in (["colour=red"], ["sample_rate"], ["sample_rate=2m"], ["velocity=-1um/s"]):
        with pytest.raises(ParameterError):
            parse_meta_args(bad)


def _chiaro(path: Path, micro: bytes) -> np.ndarray:
    """A SYNTHETIC Optics11 Chiaro export in the "Peak Load Poking" layout (V3.5); returns its table."""
    n = 200
    t = np.arange(2 * n) * 0.005  # s: 2000 nm per run at the header's 2 um/s
    piezo = np.concatenate([np.linspace(0, 2000, n), np.linspace(2000, 0, n)])  # nm, into the sample
    load_un = np.clip(piezo - 1500, 0, None) * 1e-3  # uN, contact after 1500 nm
    load_un[n:] -= 0.05 * np.exp(-((piezo[n:] - 1400) / 30) ** 2)  # a small adhesion dip on the retract
    cant = load_un * 1e-6 / 0.5 * 1e9  # nm, k = 0.5 N/m
    table = np.round(np.column_stack([t, load_un, piezo - cant, cant, piezo, np.zeros_like(t)]), 6)
    head = ("Date\t2024-01-01\nTime\t10:00:00\nDevice:\tChiaro\nSoftware version\t3.0\n"
            "k (N/m)\t0.5\nMax load (\u00b5N)\t0.5\nPiezo position (nm) (Measured)\t2000\n"
            "Piezo speed  (\u00b5m/s)\t2\n\n"
            "Time (s)\tLoad (uN)\tIndentation (nm)\tCantilever (nm)\tPiezo (nm)\tAuxiliary\n")
    body = "".join("\t".join(f"{v:.6f}" for v in row) + "\n" for row in table)
    path.write_bytes((head + body).encode("latin-1").replace(b"\xb5", micro))
    return table


@pytest.mark.parametrize("micro", [b"\xb5", b"\xc2\xb5", b"\xce\xbc"], ids=["latin-1", "utf-8", "greek-mu"])
def test_chiaro_any_micro_sign(tmp_path, micro):
    """The header's micro sign in ISO-8859-1 (as exported), UTF-8 or as the Greek mu: all read (afmformats
    0.18 fails on the last two with a KeyError)."""
    path = tmp_path / "indent.txt"
    table = _chiaro(path, micro)
    before = path.read_bytes()
    c = load(path)[0]
    assert path.read_bytes() == before
    assert c.metadata["reader"] == "chiaro-txt" and c.metadata["source_file"] == str(path)
    assert c.metadata["spring_constant"] == 0.5 and c.metadata["velocity"] == pytest.approx(2e-6)
    np.testing.assert_allclose(c.deflection_signal, table[:, 1] * 1e-6, atol=1e-15)  # load [uN] -> N
    np.testing.assert_allclose(np.abs(c.piezo_nominal), table[:, 4] * 1e-9, rtol=1e-9)
    assert c.piezo_measured is None
    app = c.piezo_nominal[c.approach]
    assert app[-1] > app[0]


def test_chiaro_displacement_profile_with_a_hold(tmp_path):
    """A SYNTHETIC V3.4 "Displacement" export: no 'Max load' or 'Piezo speed' line (afmformats 0.18 fails
    with a KeyError), a profile 0 -> 2000 nm in 1 s, held 0.5 s, back in 1 s. The hold is a dwell
    (not the start of the retract, where the maximum load would put it), the speeds are the profile's
    ramps, the tip radius is the header's, and a user's k recomputes the force from the Cantilever column."""
    dt = 0.001
    piezo = np.concatenate([np.linspace(0, 2000, 1000), np.full(500, 2000.0), np.linspace(2000, 0, 1000)[1:]])
    t = np.arange(piezo.size) * dt
    load_un = np.clip(piezo - 1500, 0, None) * 1e-3
    load_un[1000:1500] *= np.exp(-np.arange(500) * dt / 0.2) * 0.5 + 0.5  # relaxation in the hold: max load first
    cant = load_un * 1e-6 / 0.5 * 1e9  # nm, k = 0.5 N/m
    table = np.round(np.column_stack([t, load_un, piezo - cant, cant, piezo, np.zeros_like(t)]), 6)
    head = ("Date\t08/06/2021\tTime\t15:42:17\tStatus\tOK\nk (N/m)\t0.500\nTip radius (um)\t22.000\n"
            "Device:\tChiaro\nSoftware version: V3.4.1\n\nControl mode: Displacement\nProfile:\n"
            "D[Z1] (nm)\t0.000\tt[1] (s)\t0.000\nD[Z2] (nm)\t2000.000\tt[2] (s)\t1.000\n"
            "D[Z3] (nm)\t2000.000\tt[3] (s)\t0.500\nD[Z4] (nm)\t0.000\tt[4] (s)\t1.000\n\n"
            "Time (s)\tLoad (uN)\tIndentation (nm)\tCantilever (nm)\tPiezo (nm)\tAuxiliary\n")
    path = tmp_path / "displacement.txt"
    path.write_text(head + "".join("\t".join(f"{v:.6f}" for v in row) + "\n" for row in table))
    c = load(path)[0]
    hold = np.flatnonzero(piezo >= 2000 - 0.005 * 2000)  # the dwell rule: within 0.5 % of the travel
    np.testing.assert_array_equal(np.flatnonzero(c.segment == 2), hold)
    assert np.all(c.segment[:hold[0]] == 0) and np.all(c.segment[hold[-1] + 1:] == 1)
    assert np.argmax(load_un) < hold[-1]  # the maximum-load rule would have ended the approach in the hold
    assert c.metadata["velocity"] == pytest.approx(2e-6) and c.metadata["retract_velocity"] == pytest.approx(2e-6)
    assert c.metadata["radius"] == pytest.approx(22e-6) and c.metadata["spring_constant"] == 0.5
    np.testing.assert_allclose(c.deflection_signal, table[:, 1] * 1e-6, atol=1e-15)
    user = load(path, meta_override={"spring_constant": 0.25})[0]
    np.testing.assert_allclose(user.deflection_signal, 0.25 * table[:, 3] * 1e-9, rtol=1e-12, atol=1e-18)


def test_chiaro_truncated_row_is_named(tmp_path):
    """A Chiaro export cut inside its last row: a FileFormatError naming the row, not a numpy message."""
    from afmforce.errors import FileFormatError

    path = tmp_path / "cut.txt"
    table = _chiaro(path, b"\xb5")
    path.write_bytes(path.read_bytes()[:-20])
    with pytest.raises(FileFormatError, match="ends inside its last line"):   # io.cut_mid_line, for every text table
        load(path)
    path.write_bytes(path.read_bytes() + b"\n")     # the cut row with its line break: the reader's own check
    with pytest.raises(FileFormatError, match=f"row {table.shape[0]} of the Chiaro table has fewer"):
        load(path)
