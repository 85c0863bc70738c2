"""afmforce raw text and HDF5: bit-exact round trips, user files with units, malformed files."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from afmforce.errors import FileFormatError, OutputExistsError
from afmforce.instrument import get_preset
from afmforce.io.curve import RawCurve
from afmforce.io.native.rawfile import read_raw, write_raw

from afm_trajectories import ramp_trajectory


def assert_identical(a: RawCurve, b: RawCurve):
    for name in ("time", "piezo_nominal", "deflection_signal", "segment"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.tobytes() == y.tobytes(), name
    assert (a.piezo_measured is None) == (b.piezo_measured is None)
    if a.piezo_measured is not None:
        assert a.piezo_measured.tobytes() == b.piezo_measured.tobytes()
    assert a.deflection_unit == b.deflection_unit
    assert dict(a.metadata) == dict(b.metadata)
    assert (a.truth is None) == (b.truth is None)
    if a.truth is not None:
        assert set(a.truth) == set(b.truth)
        for key, value in a.truth.items():
            if isinstance(value, np.ndarray):
                assert value.tobytes() == b.truth[key].tobytes(), key
            else:
                assert value == b.truth[key], key


@pytest.fixture(scope="module")
def paper_curve():
    tr = ramp_trajectory([-0.4e-6, 0.2e-6, -0.5e-6], 5e-6, 4e3, contact=0.0)
    return get_preset("paper").record(tr, seed=42)


@pytest.mark.parametrize("suffix", [".txt", ".h5"])
def test_round_trip_is_bit_exact(tmp_path, paper_curve, suffix):
    path = tmp_path / f"curve{suffix}"
    write_raw(paper_curve, path)
    assert_identical(paper_curve, read_raw(path))


@pytest.mark.parametrize("suffix", [".tsv", ".hdf5"])
def test_round_trip_of_a_measured_curve(tmp_path, suffix):
    rng = np.random.default_rng(0)
    curve = RawCurve(time=np.arange(50) * 1e-3, piezo_nominal=rng.normal(size=50) * 1e-7,
                     deflection_signal=np.r_[rng.normal(size=49), -0.0], segment=np.r_[np.zeros(25), np.ones(25)].astype(np.int8),
                     metadata={"spring_constant": 0.1, "instrument": "Park Autoprobe", "note": [1, "a"]},
                     deflection_unit="N")
    path = tmp_path / f"m{suffix}"
    write_raw(curve, path)
    assert_identical(curve, read_raw(path))


def test_refuses_to_overwrite_without_force(tmp_path, paper_curve):
    path = tmp_path / "c.txt"
    write_raw(paper_curve, path)
    before = path.read_bytes()
    with pytest.raises(OutputExistsError):
        write_raw(paper_curve, path)
    assert path.read_bytes() == before
    write_raw(paper_curve, path, force=True)



@pytest.mark.parametrize("suffix", [".txt", ".h5"])
@pytest.mark.parametrize("bad", [np.zeros(49), np.zeros((50, 2))])
def test_a_truth_array_that_is_not_a_column_is_refused(tmp_path, suffix, bad):
    """Both halves of the format store a truth array as a column: one value per sample; another shape
    is refused by name, and nothing is written."""
    from afmforce.errors import ParameterError

    curve = RawCurve(time=np.arange(50) * 1e-3, piezo_nominal=np.linspace(0, 1e-6, 50),
                     deflection_signal=np.zeros(50), segment=np.r_[np.zeros(25), np.ones(25)].astype(np.int8),
                     truth={"separation": bad})
    path = tmp_path / f"t{suffix}"
    with pytest.raises(ParameterError, match=r"truth array 'separation' has shape .*curve's length \(50\)"):
        write_raw(curve, path)
    assert not path.exists()

USER_FILE = """# format: afmforce-raw
# version: 1
# exported by hand: from a spreadsheet
# spring_constant: 0.21 N/m
# velocity: 1um/s
# instrument: Park Autoprobe
time [ms]\tpiezo_nominal [nm]\tdeflection_signal [mV]\tsegment
0\t-100\t5\t0
1\t-99\t4\t0
2\t-100\t6\t1
"""


def test_user_text_file_with_units(tmp_path):
    path = tmp_path / "user.txt"
    path.write_text(USER_FILE)
    c = read_raw(path)
    assert np.allclose(c.time, [0, 1e-3, 2e-3], rtol=1e-15)
    assert np.allclose(c.piezo_nominal, [-100e-9, -99e-9, -100e-9], rtol=1e-15)
    assert np.allclose(c.deflection_signal, [5e-3, 4e-3, 6e-3], rtol=1e-15)
    assert c.deflection_unit == "V" and c.piezo_measured is None and c.truth is None
    assert c.metadata == {"spring_constant": 0.21, "velocity": pytest.approx(1e-6), "instrument": "Park Autoprobe"}
    assert list(c.segment) == [0, 0, 1]


def test_deflection_in_nanometres_becomes_metres(tmp_path):
    path = tmp_path / "nm.txt"
    path.write_text(USER_FILE.replace("[mV]", "[nm]"))
    c = read_raw(path)
    assert c.deflection_unit == "m" and c.deflection_signal[0] == pytest.approx(5e-9)


@pytest.mark.parametrize("text, match", [
    ("time [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n0\t0\t0\t0\n", "not an afmforce raw file"),
    ("# format: afmforce-raw\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n", "version"),
    ("# format: afmforce-raw\n# version: 2\n", "version 2"),
    ("# format: afmforce-raw\n# version: 1\n", "column header row"),
    ("# format: afmforce-raw\n# version: 1\ntime [s]\tpiezo_nominal [m]\tsegment\n0\t0\t0\n1\t0\t0\n", "deflection_signal"),
    ("# format: afmforce-raw\n# version: 1\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n", "no data"),
    ("# format: afmforce-raw\n# version: 1\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n"
     "0\t0\t0\t0\n1\t0\t0\n", "malformed data"),
    ("# format: afmforce-raw\n# version: 1\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n"
     "0\t0\t0\t0\n1\t0\tx\t0\n", "malformed data"),
    ("# format: afmforce-raw\n# version: 1\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n"
     "0\t0\t0\t0\n", "at least two samples"),
    ("# format: afmforce-raw\n# version: 1\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\tzz [m]\n"
     "0\t0\t0\t0\t0\n1\t0\t0\t0\t0\n", "unknown column"),
    ("# format: afmforce-raw\n# version: 1\ntime [N]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n"
     "0\t0\t0\t0\n1\t0\t0\t0\n", "unit 'N'"),
    ("# format: afmforce-raw\n# version: 1\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n"
     "0\t0\t0\t0\n1\t0\t0\t7\n", "segment"),
    ("# format: afmforce-raw\n# version: 1\n# velocity: fast\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n"
     "0\t0\t0\t0\n1\t0\t0\t0\n", "velocity"),
    ("# format: afmforce-raw\n# version: 1\n# velocity: 3 N\ntime [s]\tpiezo_nominal [m]\tdeflection_signal [V]\tsegment\n"
     "0\t0\t0\t0\n1\t0\t0\t0\n", "velocity"),
])
def test_malformed_text_files(tmp_path, text, match):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=match):
        read_raw(path)


def test_truncated_write_of_our_own_file_is_detected(tmp_path, paper_curve):
    path = tmp_path / "c.txt"
    write_raw(paper_curve, path)
    data = path.read_text()
    cut = tmp_path / "cut.txt"
    cut.write_text(data[: len(data) - 40])  # partial last row
    with pytest.raises(FileFormatError):
        read_raw(cut)


def test_binary_and_missing_files(tmp_path):
    path = tmp_path / "bin.txt"
    path.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(FileFormatError, match="UTF-8"):
        read_raw(path)
    with pytest.raises(FileFormatError, match="cannot read"):
        read_raw(tmp_path / "missing.txt")
    fake = tmp_path / "fake.h5"
    fake.write_text("not hdf5")
    with pytest.raises(FileFormatError, match="HDF5"):
        read_raw(fake)


def test_hdf5_missing_dataset(tmp_path, paper_curve):
    import h5py

    path = tmp_path / "c.h5"
    write_raw(paper_curve, path)
    with h5py.File(path, "a") as f:
        del f["segment"]
    with pytest.raises(FileFormatError, match="segment"):
        read_raw(path)
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = [1, 2]
    with pytest.raises(FileFormatError, match="not an afmforce raw HDF5"):
        read_raw(other)


@pytest.mark.parametrize("cut", [2, 8, 40, 2000])
def test_truncation_inside_a_number_is_detected(tmp_path, paper_curve, cut):
    path = tmp_path / "c.txt"
    write_raw(paper_curve, path)
    data = path.read_text()
    bad = tmp_path / "cut.txt"
    bad.write_text(data[: len(data) - cut])
    with pytest.raises(FileFormatError, match="truncated"):
        read_raw(bad)


SMALL = (USER_FILE + "# end\n").replace("# version: 1\n", "# version: 1\n# rows: 3\n").encode()


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.integers(0, len(SMALL) - 1), st.integers(0, 255)), min_size=1, max_size=6))
def test_mutated_files_raise_only_file_format_errors(tmp_path, edits):
    data = bytearray(SMALL)
    for pos, byte in edits:
        data[pos] = byte
    path = tmp_path / "fuzz.txt"
    path.write_bytes(bytes(data))
    try:
        curve = read_raw(path)
    except FileFormatError:
        return
    assert isinstance(curve, RawCurve)
