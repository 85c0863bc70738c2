"""Where a calibration value came from, as the warnings name it and as the spring constant follows it.

* ``--meta sensitivity=...`` / ``--meta spring_constant=...``: typed by the user, so named as the user's
  (was: "2 x the file's ... the file's is used", "give `spring_constant` if the file's k ...").
* ``--probe-calibration calib.json`` with a thermal k under ``--calibration fit``: k_thermal = chi kB T /
  (InvOLS^2 <V^2>) goes as 1/InvOLS^2, so it is rescaled by (the file's InvOLS / the fitted)^2; Sader's k
  (plan view, f0, Q) rests on no InvOLS and is kept (was: both kept).

The curve: tests/data/bruker-nanoscope_synthetic.txt (hard contact, measured Z sensor, its header's
DeflSens 45 nm/V and k 0.21 N/m, read here by regular expression, not by afmforce).
"""

from __future__ import annotations

import io
import json
from contextlib import redirect_stdout

import pytest

from afmforce.calibration.record import write_calibration
from afmforce.cli.main import main
from realdata import DATA, bruker_synthetic_header

PATH = DATA / "bruker-nanoscope_synthetic.txt"


_header = bruker_synthetic_header   # (InvOLS [m/V], k [N/m]) from the header lines, by regular expression


def _run(*flags: str) -> dict:
    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["analyze", str(PATH), "--json", *flags]) == 0
    (res,) = json.loads(out.getvalue())["results"].values()
    return res


def _warnings(res: dict) -> list[str]:
    return list(res["warnings"])


def test_a_sensitivity_given_with_meta_is_named_as_the_users():
    """Half the true InvOLS typed as metadata: the slope's 2 x is said against the user's value, and
    "yours is used", never "the file's", exactly as with --sensitivity."""
    sens, _ = _header()
    res = _run("--meta", f"sensitivity={sens * 0.5 * 1e9:.6g}nm/V")
    assert res["sensitivity"] == pytest.approx(sens * 0.5, rel=1e-9)
    (w,) = [w for w in _warnings(res) if w.startswith("the compliance slope gives a calibration")]
    assert "2 x the one you gave as metadata (meta sensitivity)" in w
    assert "yours is used" in w and "file's is used" not in w
    flag = _run("--sensitivity", f"{sens * 0.5 * 1e9:.6g}nm/V")      # the same value as a flag: "yours" too
    (wf,) = [w for w in _warnings(flag) if w.startswith("the compliance slope gives a calibration")]
    assert "yours is used" in wf and flag["sensitivity_used"] == res["sensitivity_used"]


def test_a_spring_constant_given_with_meta_is_named_as_the_users_when_rescaled():
    """--meta spring_constant under --calibration fit is rescaled as the file's would be (it replaces the
    file's metadata: k x (given / fitted InvOLS)^2), and the warning names it as the user's."""
    sens, _ = _header()
    res = _run("--meta", "spring_constant=0.1N/m", "--meta", f"sensitivity={sens * 0.5 * 1e9:.6g}nm/V",
               "--calibration", "fit")
    assert res["spring_constant"] == pytest.approx(0.1 * (sens * 0.5 / res["sensitivity_fit"]) ** 2, rel=1e-9)
    (w,) = [w for w in _warnings(res) if "rescaled" in w]
    assert "meta spring_constant" in w and "file's" not in w


def _calibration(tmp_path, method: str, k: float, invols: float | None):
    values = {"spring_constant": k, **({"sensitivity": invols} if invols is not None else {})}
    return write_calibration(tmp_path / f"{method}.json", method, values,
                             {"spring_constant": "N/m", "sensitivity": "m/V"})


def test_a_thermal_calibration_files_k_is_rescaled_with_a_refitted_sensitivity(tmp_path):
    """A thermal tune converted with half the true InvOLS (22.5 nm/V) gives 4 x the true k (0.84 N/m for the
    header's 0.21); refitting the sensitivity from the compliance slope must bring k back to the header's
    (within the slope's 1 %, squared: 2 %), and say it with the numbers."""
    sens, k_true = _header()
    k_cal, inv = k_true * 4, sens * 0.5
    res = _run("--probe-calibration", str(_calibration(tmp_path, "thermal", k_cal, inv)), "--calibration", "fit")
    assert res["sensitivity_used"] == pytest.approx(sens, rel=0.01)
    assert res["spring_constant"] * res["sensitivity_fit"] ** 2 == pytest.approx(k_cal * inv ** 2, rel=1e-9)
    assert res["spring_constant"] == pytest.approx(k_true, rel=0.02)
    (w,) = [w for w in _warnings(res) if "rescaled" in w]
    assert w.startswith("the probe calibration file's thermal spring constant rescaled")
    assert f"{k_cal:.4g} -> {res['spring_constant']:.4g} N/m" in w and f"{inv * 1e9:.4g} ->" in w


def test_a_sader_calibration_files_k_is_kept(tmp_path):
    """Sader's k comes from the lever's plan view, f0 and Q: no InvOLS in it, so a refitted sensitivity
    leaves it as it is, silently."""
    sens, _ = _header()
    res = _run("--probe-calibration", str(_calibration(tmp_path, "sader", 0.5, sens * 0.5)), "--calibration", "fit")
    assert res["sensitivity_used"] == pytest.approx(sens, rel=0.01)
    assert res["spring_constant"] == 0.5
    assert not any("rescaled" in w for w in _warnings(res))


def test_a_thermal_k_without_its_invols_is_kept_and_said(tmp_path):
    """A thermal calibration from a spectrum in m^2/Hz records no InvOLS: the factor is unknown, k kept, said."""
    sens, _ = _header()
    res = _run("--probe-calibration", str(_calibration(tmp_path, "thermal", 0.5, None)), "--calibration", "fit")
    assert res["spring_constant"] == 0.5
    (w,) = [w for w in _warnings(res) if "not rescaled" in w]
    assert "records no InvOLS" in w and "0.5 N/m" in w


def test_a_thermal_k_is_named_as_the_calibration_files_under_auto(tmp_path):
    """Under the default (auto) calibration the thermal file's InvOLS is used; the slope's 2 x is said
    against the probe calibration file's, and k is not touched."""
    sens, k_true = _header()
    res = _run("--probe-calibration", str(_calibration(tmp_path, "thermal", 0.3, sens * 0.5)))
    assert res["spring_constant"] == 0.3 and res["sensitivity_used"] == pytest.approx(sens * 0.5)
    (w,) = [w for w in _warnings(res) if w.startswith("the compliance slope gives a calibration")]
    assert "the probe calibration file's" in w and "the calibration file's is used" in w
