"""Recovery, null and CLI form of the joint dynamic fit on virtual-AFM curves.

Truth: the beam model (Fig 5 lever, R = 100 nm, A = 5e-19 J), four speeds 0.5-5 um/s,
0.01 nm noise, random drift, random zero of position (~20 nm) and baseline offset
(~2 nm) per curve, written as raw text files and fitted through the CLI.
"""

from __future__ import annotations

import json

import pytest

from afmforce.cli.main import main
from afmforce.constants import FIG5
from afmforce.fit import fit_dynamic

from fit_virtual import make_curves, write_curves

XI = 0.005          # [kg/s]: xi*v = 2.5e-9 .. 2.5e-8 N
AR = FIG5["hamaker"] * 100e-9


@pytest.fixture(scope="module")
def cli_result(tmp_path_factory):
    d = tmp_path_factory.mktemp("fit")
    curves = make_curves(XI, seed=13)
    paths = write_curves(curves, d)
    out = d / "res.json"
    rc = main(["fit", *map(str, paths), "--model", "beam", "--radius", "100nm",
               "--free", "hamaker,xi", "--json", "--out", str(out), "--report", str(d / "r.md"),
               "--plots", str(d / "plots")])
    assert rc == 0
    return json.loads(out.read_text()), curves, d


def test_cli_json_form(cli_result):
    res, curves, d = cli_result
    for name in ("hamaker", "xi"):
        p = res["parameters"][name]
        assert {"value", "stderr", "interval"} <= set(p)
        assert p["interval"][0] < p["value"] < p["interval"][1]
    assert isinstance(res["friction_detected"], bool)
    assert 0.0 <= res["p_value"] <= 1.0
    assert len(res["curves"]) == 4
    assert (d / "r.md").read_text().startswith("# Dynamic fit")
    assert len(res["figures"]) == 6 and all((d / "plots").glob("*.png"))
    assert (d / "plots" / "fit_residuals.png").stat().st_size > 10_000


def test_recovery(cli_result):
    res, curves, _ = cli_result
    ar = res["derived"]["hamaker_radius"]
    xi = res["parameters"]["xi"]
    assert abs(ar["value"] / AR - 1) < 0.05
    assert abs(xi["value"] / XI - 1) < 0.20
    # interval coverage is a property of many seeds: test_fit_calibration.py, benchmarks/bench_fit.py
    assert res["friction_detected"] is True and res["p_value"] < 1e-6
    # nuisance parameters: the unknown zero of position and baseline offset of every curve
    for c, fit in zip(curves, res["curves"]):
        assert fit["shift"] == pytest.approx(c.truth["zero_offset"], abs=0.2e-9)
        assert fit["offset"] == pytest.approx(c.truth["baseline_offset"], abs=0.05e-9)
    comp = res["comparison"]
    assert comp["best_by_bic"] == "dynamic, friction"
    assert 0.7 < res["redchi"] < 1.4          # the model describes the data within their noise


def test_null_no_friction():
    curves = make_curves(0.0, seed=12)
    res = fit_dynamic(curves, "beam", free=("hamaker", "xi"))
    assert res.friction_detected is False
    assert res.p_value > 0.05
    lo, hi = res.parameters["xi"].interval
    assert lo == 0.0
    # an upper bound: far below the friction of the recovery test, which the data would show
    assert 0 < hi < 0.2 * XI
    assert "not detected" in res.comparison.verdict
    assert abs(res.derived["hamaker_radius"].value / AR - 1) < 0.05


def test_stderr_matches_plan(cli_result):
    """The fit's standard error of xi against the Fisher information of afmforce.fit.plan."""
    import numpy as np

    from afmforce.fit.core import base_config
    from afmforce.fit.plan import curve_information
    from fit_virtual import DRIVE, NOISE, SPEEDS

    res, curves, _ = cli_result
    base = base_config("beam", xi=XI, radius=100e-9, **DRIVE)
    infos = curve_information(base, SPEEDS, [c["sample_rate"] for c in res["curves"]], NOISE)
    sd = np.sqrt(np.diag(np.linalg.inv(sum(infos))))
    assert res["parameters"]["xi"]["stderr"] == pytest.approx(sd[1], rel=0.3)
    assert res["parameters"]["hamaker"]["stderr"] == pytest.approx(sd[0], rel=0.3)


def test_retract_fit_recovers_and_tightens_xi(cli_result, capsys):
    """``--retract``: the outward compliance line and its friction hysteresis join the fit.

    Truth xi = 0.005 kg/s, A = 5e-19 J. Measured: xi 0.00498 +- 0.00001 (approach only:
    0.00518 +- 0.00011), A 5.000e-19 +- 1.7e-21 J.
    """
    approach_only, curves, d = cli_result
    rc = main(["fit", *map(str, sorted(d.glob("v*.txt"))), "--model", "beam", "--radius", "100nm",
               "--free", "hamaker,xi", "--retract", "--no-profile", "--json"])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    xi = res["parameters"]["xi"]
    assert abs(xi["value"] / XI - 1) < 0.05
    assert abs(res["derived"]["hamaker_radius"]["value"] / AR - 1) < 0.02
    assert xi["stderr"] < approach_only["parameters"]["xi"]["stderr"] / 3
    assert res["friction_detected"] is True
    assert 0.7 < res["redchi"] < 1.4
    for c, fit in zip(curves, res["curves"]):
        assert fit["retract"] is True and fit["n_used"] > 1.5 * approach_only["curves"][0]["n_used"]
        assert fit["shift"] == pytest.approx(c.truth["zero_offset"], abs=0.2e-9)
