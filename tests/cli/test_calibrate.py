"""``afmforce calibrate`` (issue 34): thermal, sader, invols; --json, --out, --example; the file it
writes feeds analyze and simulate (--probe-calibration)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from afmforce import datasets
from afmforce.cli.main import build_parser, main

DATA = Path(__file__).resolve().parents[1] / "data"


def run(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_thermal_example_virtual_air(capsys, tmp_path):
    """The shipped virtual spectrum (k = 0.2 N/m): k within 3 standard errors and 2.5 %, the file's
    temperature and correction used and said so; --out writes the calibration."""
    out_file = tmp_path / "calib.json"
    code, out, err = run(capsys, ["calibrate", "thermal", "--example", "virtual-air", "--json", "--out", str(out_file)])
    assert code == 0, err
    d = json.loads(out)
    assert abs(d["spring_constant"] - 0.2) < 3 * d["spring_constant_se"]
    assert d["spring_constant"] == pytest.approx(0.2, rel=0.025)
    assert d["resonance_frequency"] == pytest.approx(20e3, rel=1e-3)
    assert d["sources"] == {"temperature": "file", "correction": "file", "tilt": "default (no tilt)"}
    saved = json.loads(out_file.read_text())
    assert saved["afmforce_calibration"] == 1 and saved["spring_constant"] == d["spring_constant"]


def test_thermal_jpk_file_agrees_with_the_vendor(capsys):
    code, out, _ = run(capsys, ["calibrate", "thermal", str(DATA / "jpk-tnd_PFQNM-water_thermal-noise_0-80kHz.tnd"),
                                "--json"])
    d = json.loads(out)
    assert code == 0 and d["file_spring_constant"] == pytest.approx(45.8785e-3)
    assert d["file_spring_constant_ratio"] == pytest.approx(1.0, abs=0.05)
    assert d["spring_constant_sader"] == pytest.approx(45.8785e-3, rel=0.05)   # lever size from the header
    assert d["spring_constant_normal"] == pytest.approx(d["spring_constant"] / math.cos(math.radians(10)) ** 2)


def test_thermal_defaults_and_overrides(capsys, tmp_path):
    """A spectrum without temperature or correction: 295 K and 0.817 by default, said so."""
    src = datasets.thermal_example("virtual-air").read_text().splitlines()
    bare = tmp_path / "bare.psd"
    bare.write_text("\n".join(l for l in src if not l.startswith(("# temperature", "# correction"))) + "\n")
    code, out, _ = run(capsys, ["calibrate", "thermal", str(bare), "--json"])
    d = json.loads(out)
    assert d["temperature"] == 295.0 and d["correction"] == 0.817
    assert d["sources"]["temperature"].startswith("default") and "Butt" in d["sources"]["correction"]
    code, out2, _ = run(capsys, ["calibrate", "thermal", str(bare), "--json", "--temperature", "25degC",
                                 "--correction", "1"])
    d2 = json.loads(out2)
    assert d2["spring_constant"] == pytest.approx(d["spring_constant"] / 0.817 * 298.15 / 295.0, rel=1e-6)


def test_thermal_table_and_refusals(capsys):
    code, out, _ = run(capsys, ["calibrate", "thermal", "--example", "jpk-water"])
    assert code == 0 and "mN/m" in out and "ratio" in out and "Sader" in out
    code, _, err = run(capsys, ["calibrate", "thermal"])
    assert code == 2 and err.startswith("error:") and "FILE" in err
    code, _, err = run(capsys, ["calibrate", "thermal", "--example", "virtual-air", "--invols", "50nm/V"])
    assert code == 2 and "m^2/Hz" in err
    code, _, err = run(capsys, ["calibrate", "thermal", "--example", "nope"])
    assert code == 2 and "virtual-air" in err


def test_sader_rectangular_and_general(capsys):
    code, out, _ = run(capsys, ["calibrate", "sader", "--length", "54um", "--width", "4.5um", "--frequency",
                                "24.25kHz", "--quality-factor", "2.05", "--medium", "water", "--json"])
    d = json.loads(out)
    assert code == 0 and d["method"] == "rectangular"
    assert d["spring_constant"] == pytest.approx(45.8785e-3, rel=0.05)
    code, out, _ = run(capsys, ["calibrate", "sader", "--frequency", "24.25kHz", "--quality-factor", "2.05",
                                "--medium", "water", "--reference-spring-constant", "0.0445N/m",
                                "--reference-frequency", "24.25kHz", "--reference-quality-factor", "2.05",
                                "--width", "4.5um", "--json"])
    g = json.loads(out)
    assert g["method"] == "general" and g["spring_constant"] == pytest.approx(0.0445, rel=1e-9)
    code, _, err = run(capsys, ["calibrate", "sader", "--frequency", "20kHz", "--quality-factor", "50"])
    assert code == 2 and "--length" in err


def test_invols_example_is_reported_undetermined(capsys, tmp_path):
    out_file = tmp_path / "inv.json"
    code, out, _ = run(capsys, ["calibrate", "invols", "--example", "--json", "--out", str(out_file)])
    d = json.loads(out)
    assert code == 0 and d["determined"] is False and d["n_points"] == 6
    from afmforce.calibration.record import read_calibration

    assert "sensitivity" not in read_calibration(out_file)     # an undetermined InvOLS is not handed on


def test_json_before_the_method_is_kept(capsys):
    code, out, _ = run(capsys, ["calibrate", "--json", "sader", "--length", "200um", "--width", "20um",
                                "--frequency", "13kHz", "--quality-factor", "30"])
    assert code == 0 and json.loads(out)["method"] == "rectangular"


def test_probe_calibration_feeds_analyze_and_simulate(capsys, tmp_path):
    calib = tmp_path / "calib.json"
    run(capsys, ["calibrate", "thermal", "--example", "virtual-air", "--out", str(calib)])
    saved = json.loads(calib.read_text())
    from afmforce.cli.calibrate import calibrated_probe, fill_from_calibration

    args = build_parser("analyze").parse_args(["analyze", "x", "--probe-calibration", str(calib),
                                               "--sensitivity", "40nm/V"])
    used = fill_from_calibration(args, ("spring_constant", "sensitivity", "resonance_frequency"))
    assert used == {"spring_constant": saved["spring_constant"], "resonance_frequency": saved["resonance_frequency"]}
    assert args.sensitivity == pytest.approx(40e-9)                     # a flag given wins
    args = build_parser("simulate").parse_args(["simulate", "--model", "spring", "--probe-calibration", str(calib)])
    calibrated_probe(args)
    from afmforce.cli.simulate import config_from_args

    cfg = config_from_args(args)
    assert cfg.probe.spring_constant == saved["spring_constant"]
    assert cfg.probe.quality_factor == saved["quality_factor"]
    assert math.sqrt(cfg.probe.spring_constant / cfg.probe.mass) / (2 * math.pi) == pytest.approx(
        saved["resonance_frequency"])


def test_probe_calibration_gives_the_fit_its_damping(capsys, tmp_path):
    """afmforce fit shares simulate's model flags: the calibrated Q damps the fitted model."""
    calib = tmp_path / "calib.json"
    run(capsys, ["calibrate", "thermal", "--example", "virtual-air", "--out", str(calib)])
    from afmforce.cli.fit import model_config

    args = build_parser("fit").parse_args(["fit", "a.txt", "b.txt", "--probe-calibration", str(calib)])
    assert model_config(args).probe.quality_factor == json.loads(calib.read_text())["quality_factor"]


def test_plain_text_spectrum_with_its_unit_given(capsys, tmp_path):
    """The virtual spectrum's two columns without its header: --psd-unit, and the flags give what
    the file would (295 K default, correction 1): the same k as from the own format."""
    src = datasets.thermal_example("virtual-air")
    rows = [line for line in src.read_text().splitlines() if line[:1].isdigit()]
    plain = tmp_path / "plain.txt"
    plain.write_text("\n".join(r.replace(",", "\t") for r in rows) + "\n")
    code, out, err = run(capsys, ["calibrate", "thermal", str(plain), "--psd-unit", "m^2/Hz", "--correction", "1",
                                  "--json"])
    assert code == 0, err
    code, ref, _ = run(capsys, ["calibrate", "thermal", "--example", "virtual-air", "--json"])
    assert json.loads(out)["spring_constant"] == pytest.approx(json.loads(ref)["spring_constant"], rel=1e-9)
    code, _, err = run(capsys, ["calibrate", "thermal", str(plain)])
    assert code == 2 and "--psd-unit" in err


def test_out_is_not_replaced_without_force(capsys, tmp_path):
    out_file = tmp_path / "calib.json"
    out_file.write_text("{}")
    argv = ["calibrate", "sader", "--length", "200um", "--width", "20um", "--frequency", "13kHz",
            "--quality-factor", "30", "--out", str(out_file)]
    code, _, err = run(capsys, argv)
    assert code == 2 and "--force" in err and out_file.read_text() == "{}"
    code, out, _ = run(capsys, argv + ["--force"])
    assert code == 0 and json.loads(out_file.read_text())["method"] == "rectangular" and f"wrote {out_file}" in out


@pytest.mark.parametrize("model", ["spring", "beam"])
def test_virtual_spectrum_round_trip(capsys, tmp_path, model):
    """calibrate virtual writes a spectrum of known k; calibrate thermal gives it back within 2 %."""
    spectrum = tmp_path / "v.psd"
    code, out, err = run(capsys, ["calibrate", "virtual", "--model", model, "--quality-factor", "20",
                                  "--averages", "2048", "--spectrum", str(spectrum), "--json"])
    assert code == 0, err
    truth = json.loads(out)["spring_constant"]
    code, out, _ = run(capsys, ["calibrate", "thermal", str(spectrum), "--json"])
    assert json.loads(out)["spring_constant"] == pytest.approx(truth, rel=0.02)


def test_thermal_plot(capsys, tmp_path):
    png = tmp_path / "fit.png"
    code, out, _ = run(capsys, ["calibrate", "thermal", "--example", "jpk-water", "--plot", str(png)])
    assert code == 0 and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"wrote {png}" in out


def test_thermal_s_sader_cross_check_that_is_no_result_is_a_warning(monkeypatch, capsys):
    """The Sader cross-check of `calibrate thermal` may now be refused as no lever's k (AnalysisError,
    audit): the thermal calibration still stands, with a warning."""
    import afmforce.calibration as calibration
    from afmforce.errors import AnalysisError

    def refuse(*args, **kwargs):
        raise AnalysisError("the rectangular Sader method gives spring_constant = 1e7 N/m, outside any lever's")

    monkeypatch.setattr(calibration, "sader_rectangular", refuse)
    code = main(["calibrate", "thermal", "--example", "jpk-water", "--length", "100um", "--width", "20um"])
    out, err = capsys.readouterr()
    assert code == 0 and "warning: no Sader k: the rectangular Sader method gives" in err, err
    assert "Sader k" not in out and "spring constant k" in out
