"""Sweep specifications: grids, samples, text and TOML forms (issue 7, part 1)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from afmforce.errors import ParameterError, UnitError
from afmforce.sweep import SweepSpec, build_spec, parse_grid, parse_range, parse_setting
from afmforce.sweep.spec import GridAxis, SampledRange, chunk_size_from_config

DIMS = {"velocity": "velocity", "xi": "damping", "radius": "length", "theta0": "angle",
        "model": None, "start": "length"}


def test_log_grid_with_units_is_geometric():
    # velocity=0.1um/s:10um/s:5:log -> 1e-7 * 10^(k/2) m/s, k = 0..4 (two decades in 4 steps)
    axis = parse_grid("velocity=0.1um/s:10um/s:5:log", DIMS)
    expected = [1e-7 * 10 ** (k / 2) for k in range(5)]
    np.testing.assert_allclose(axis.values, expected, rtol=1e-14)
    assert axis.log and axis.name == "velocity"


def test_linear_grid_list_grid_and_setting():
    lin = parse_grid("radius=100nm:200nm:3", DIMS)
    np.testing.assert_allclose(lin.values, [100e-9, 150e-9, 200e-9], rtol=1e-14)
    assert not lin.log
    listed = parse_grid("theta0=-15deg,-10deg", DIMS)
    np.testing.assert_allclose(listed.values, [math.radians(-15), math.radians(-10)], rtol=1e-14)
    assert parse_grid("model=spring,beam", DIMS).values == ("spring", "beam")
    assert parse_setting("start=-20nm", DIMS) == ("start", pytest.approx(-20e-9))


def test_grid_table_is_the_full_product_first_axis_slowest():
    spec = SweepSpec(grid=(GridAxis("xi", (0.01, 0.1)), GridAxis("velocity", (1e-6, 2e-6, 3e-6))),
                     fixed=(("model", "beam"),))
    table = spec.table()
    assert spec.n_runs == 6 and spec.shape == (2, 3) and spec.is_grid
    assert table.index.name == "run" and list(table.index) == list(range(6))
    assert list(table["xi"]) == [0.01] * 3 + [0.1] * 3
    assert list(table["velocity"]) == [1e-6, 2e-6, 3e-6] * 2
    assert set(table["model"]) == {"beam"}


def test_latin_hypercube_puts_one_sample_in_each_stratum():
    # McKay et al. (1979): with n samples, each of the n equal-probability strata of every
    # parameter holds exactly one sample; in log for a log range.
    n = 16
    spec = build_spec(ranges=["xi=0.001:0.1:log", "radius=50nm:250nm"], sample="lhs", n=n, seed=3,
                      dimensions=DIMS)
    t = spec.table()
    u_xi = (np.log(t["xi"]) - np.log(0.001)) / (np.log(0.1) - np.log(0.001))
    u_r = (t["radius"] - 50e-9) / 200e-9
    for u in (u_xi, u_r):
        assert sorted(np.floor(u * n).astype(int)) == list(range(n))
    again = build_spec(ranges=["xi=0.001:0.1:log", "radius=50nm:250nm"], sample="lhs", n=n, seed=3,
                       dimensions=DIMS).table()
    assert t.equals(again)  # reproducible from the seed


def test_random_samples_stay_in_range_and_cross_the_grid():
    spec = build_spec(["model=spring,beam"], ["xi=0.01:0.1"], sample="random", n=5, dimensions=DIMS)
    t = spec.table()
    assert spec.n_runs == 10 and not spec.is_grid
    assert ((t["xi"] >= 0.01) & (t["xi"] < 0.1)).all()
    # every grid point gets the same samples
    np.testing.assert_array_equal(t["xi"][:5].to_numpy(), t["xi"][5:].to_numpy())


@pytest.mark.parametrize("text, error, words", [
    ("velocity=5nm:1nm:3", UnitError, "speed"),
    ("speed=1:2:3", ParameterError, "unknown parameter 'speed'"),
    ("velocity=0um/s:1um/s:3:log", ParameterError, "log spacing needs positive"),
    ("velocity=1um/s:2um/s:0", ParameterError, "positive integer"),
    ("velocity=1um/s:2um/s:two", ParameterError, "integer"),
    ("velocity", ParameterError, "name=value"),
])
def test_bad_grids_are_refused_with_a_clear_message(text, error, words):
    with pytest.raises(error, match=words):
        parse_grid(text, DIMS)


def test_inconsistent_specs_are_refused():
    with pytest.raises(ParameterError, match="more than once"):
        build_spec(["xi=0.01,0.1"], sets=["xi=0.1"], dimensions=DIMS)
    with pytest.raises(ParameterError, match="needs `n`"):
        build_spec(ranges=["xi=0.01:0.1"], sample="lhs", dimensions=DIMS)
    with pytest.raises(ParameterError, match="nothing to sweep"):
        build_spec(sets=["xi=0.1"], dimensions=DIMS)
    with pytest.raises(ParameterError, match="needs at least one `ranges`"):
        SweepSpec(grid=(GridAxis("xi", (1.0,)),), sample="lhs", n=3)
    with pytest.raises(ParameterError, match="log sampling"):
        SampledRange("xi", -1.0, 1.0, log=True)
    with pytest.raises(ParameterError, match="lo:hi"):
        parse_range("xi=0.1", DIMS)


def test_toml_file_and_flags_merge(tmp_path):
    path = tmp_path / "sweep.toml"
    path.write_text(
        '[sweep]\nchunk_size = 7\nseed = 2\n'
        '[grid]\nvelocity = "1um/s:10um/s:3:log"\nxi = { lo = 0.01, hi = 0.1, n = 2 }\n'
        'model = ["spring", "beam"]\n'
        '[set]\nstart = "-20nm"\n'
    )
    spec = build_spec(["xi=0.05,0.5,5"], sets=["start=-30nm"], config=path, dimensions=DIMS)
    names = [a.name for a in spec.grid]
    assert names == ["velocity", "model", "xi"]  # the flag replaced the file's xi axis
    assert spec.grid[2].values == (0.05, 0.5, 5.0)
    np.testing.assert_allclose(spec.grid[0].values, [1e-6, 10 ** -5.5, 1e-5], rtol=1e-14)
    assert dict(spec.fixed) == {"start": pytest.approx(-30e-9)}
    assert spec.seed == 2 and chunk_size_from_config(path) == 7
    bad = tmp_path / "bad.toml"
    bad.write_text("[grids]\nxi = 1\n")
    with pytest.raises(ParameterError, match="unknown table"):
        build_spec(config=bad, dimensions=DIMS)


def test_fingerprint_is_stable_and_sensitive_to_the_runs(tmp_path):
    path = tmp_path / "sweep.toml"
    path.write_text('[grid]\nvelocity = "1um/s:10um/s:3:log"\n')
    a = build_spec(["velocity=1um/s:10um/s:3:log"], dimensions=DIMS)
    b = build_spec(config=path, dimensions=DIMS)  # the same sweep from a file
    c = build_spec(["velocity=1um/s:10um/s:4:log"], dimensions=DIMS)
    d = build_spec(["velocity=1um/s:10um/s:3:log"], sets=["start=-20nm"], dimensions=DIMS)
    assert a.fingerprint() == b.fingerprint()
    assert len({a.fingerprint(), c.fingerprint(), d.fingerprint()}) == 3
