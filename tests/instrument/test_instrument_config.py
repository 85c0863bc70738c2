"""TOML configuration, parameter overrides and the CLI option helpers (issue 4, item 3)."""


import numpy as np
import pytest

from afmforce.cli._instrument_opts import add_instrument_arguments, check_raw_output, record_from_args
from afmforce.cli.main import _Parser
from afmforce.errors import FileFormatError, OutputExistsError, ParameterError, UnitError
from afmforce.instrument import build_instrument, get_preset, load_config
from afmforce.instrument.config import PARAMETERS, parse_config, parse_parameter
from afmforce.io.native.rawfile import read_raw

from afm_trajectories import ramp_trajectory

TOML = """
preset = "paper"
seed = 9

[piezo]
hysteresis = 0.05
creep_times = ["50 ms", "2 s"]

[photodiode]
sensitivity = "25 nm/V"
saturation = "none"

[drift]
rates = ["0.1 V/s", "-20 mV/s"]

[acquisition]
adc_bits = 12
"""


def _trajectory():
    return ramp_trajectory([-0.3e-6, 0.05e-6, -0.3e-6], 2e-6, 4e3, contact=0.0)


def test_toml_configuration(tmp_path):
    path = tmp_path / "inst.toml"
    path.write_text(TOML)
    cfg = load_config(path)
    assert cfg["preset"] == "paper" and cfg["seed"] == 9
    inst = build_instrument(config=cfg)
    assert inst.name == "paper+custom"
    assert inst.piezo.hysteresis == 0.05
    assert inst.piezo.creep_times == pytest.approx((0.05, 2.0))
    assert inst.piezo.creep_amplitudes == get_preset("paper").piezo.creep_amplitudes
    assert inst.photodiode.sensitivity == pytest.approx(25e-9) and inst.photodiode.saturation is None
    assert inst.drift.rates == pytest.approx((0.1, -0.02))
    assert inst.acquisition.adc_bits == 12
    # an explicit preset wins over the file's, and overrides over both
    cfg2 = parse_config({"preset": "paper", "noise": {"white": "1 mV"}})
    other = build_instrument("typical", cfg2, {"piezo.hysteresis": "0.2"})
    assert other.name == "typical+custom" and other.piezo.hysteresis == 0.2
    assert other.noise.white == pytest.approx(1e-3) and other.piezo.creep_times == (0.5,)
    assert build_instrument("typical") == get_preset("typical")


def test_instrument_table_inside_a_larger_file(tmp_path):
    path = tmp_path / "all.toml"
    path.write_text('[simulation]\nxi = 0.1\n[instrument]\npreset = "typical"\n[instrument.noise]\nwhite = "2 mV"\n')
    cfg = load_config(path)
    assert build_instrument(config=cfg).noise.white == pytest.approx(2e-3)


@pytest.mark.parametrize("text, error, match", [
    ("[piezo]\nhysterisis = 0.1\n", ParameterError, "unknown instrument parameter"),
    ("[pizeo]\ngain = 1\n", ParameterError, "unknown entry"),
    ("[piezo]\ngain = -1\n", ParameterError, "gain"),
    ("[photodiode]\nsensitivity = \"5 nN\"\n", UnitError, "sensitivity"),
    ("[acquisition]\nadc_bits = 0\n", ParameterError, "adc_bits"),
    ("[acquisition]\nadc_bits = 2.5\n", ParameterError, "whole number"),
    ("preset = 3\n", ParameterError, "preset"),
    ("[piezo\n", FileFormatError, "TOML"),
])
def test_bad_configurations(tmp_path, text, error, match):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(error, match=match):
        build_instrument(config=load_config(path))


def test_missing_config_file(tmp_path):
    with pytest.raises(FileFormatError, match="cannot read"):
        load_config(tmp_path / "nope.toml")


def test_parameter_parsing_with_units():
    assert parse_parameter("detector.backlash", "57nm") == pytest.approx(57e-9)
    assert parse_parameter("detector.backlash_speed", "17um/s") == pytest.approx(17e-6)
    assert parse_parameter("photodiode.incidence_angle", "30deg") == pytest.approx(np.pi / 6)
    assert parse_parameter("acquisition.sample_rate", "2kHz") == pytest.approx(2e3)
    assert parse_parameter("acquisition.sample_rate", "none") is None
    assert parse_parameter("piezo.creep_amplitudes", "0.3, 0.1") == (0.3, 0.1)
    assert parse_parameter("drift.rate_rms", "5 mV/s") == pytest.approx(5e-3)
    assert len(PARAMETERS) == 27   # + photodiode.nonlinearity_length (issue 25)


def _parser(**existing):
    p = _Parser(prog="afmforce-test")
    for flag in existing:
        p.add_argument(flag, action="store_true" if flag == "--force" else "store")
    add_instrument_arguments(p)
    return p


def test_cli_records_and_writes_raw(tmp_path):
    out = tmp_path / "run.txt"
    args = _parser().parse_args(["--instrument", "paper", "--seed", "3", "--raw", str(out),
                                 "--detector-step", "2nm", "--photodiode-sensitivity", "30nm/V"])
    raw = record_from_args(args, _trajectory())
    assert raw.metadata["instrument"] == "paper+custom" and raw.metadata["seed"] == 3
    back = read_raw(out)
    assert back.deflection_signal.tobytes() == raw.deflection_signal.tobytes()
    assert back.truth["instrument"]["detector"]["step"] == pytest.approx(2e-9)
    assert np.allclose(raw.piezo_measured / 2e-9, np.round(raw.piezo_measured / 2e-9))
    # refuses to overwrite, then --force
    with pytest.raises(OutputExistsError):
        record_from_args(args, _trajectory())
    with pytest.raises(OutputExistsError):
        check_raw_output(args)
    args = _parser().parse_args(["--instrument", "paper", "--raw", str(out), "--force"])
    record_from_args(args, _trajectory())


def test_cli_hdf5_and_config(tmp_path):
    cfg = tmp_path / "inst.toml"
    cfg.write_text(TOML)
    out = tmp_path / "run.h5"
    args = _parser().parse_args(["--config", str(cfg), "--raw", str(out)])
    raw = record_from_args(args, _trajectory())
    assert raw.metadata["seed"] == 9 and raw.metadata["instrument"] == "paper+custom"
    assert read_raw(out).deflection_signal.tobytes() == raw.deflection_signal.tobytes()


def test_cli_nothing_requested_returns_none():
    assert record_from_args(_parser().parse_args([]), _trajectory()) is None


def test_cli_shares_existing_seed_force_and_config_flags(tmp_path):
    p = _parser(**{"--seed": None, "--force": None, "--config": None})
    args = p.parse_args(["--instrument", "typical", "--seed", "4", "--instrument-config",
                         str(tmp_path / "none.toml")])
    assert args.seed == "4" and args.instrument_config.endswith("none.toml")
    assert args.config is None


@pytest.mark.parametrize("argv", [["--photodiode-sensitivity", "5nN"], ["--instrument", "park"],
                                  ["--seed", "-1"], ["--acquisition-adc-bits", "0.5"]])
def test_cli_bad_values_exit_2(capsys, argv):
    with pytest.raises(SystemExit) as exc:
        _parser().parse_args(argv)
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("error:") and err.count("\n") == 1


def test_cli_bad_combination_is_an_afmforce_error():
    args = _parser().parse_args(["--instrument", "ideal", "--noise-white", "1mV"])
    with pytest.raises(ParameterError, match="sensitivity"):
        record_from_args(args, _trajectory())
    args = _parser().parse_args(["--instrument", "ideal", "--acquisition-sample-rate", "1MHz"])
    with pytest.raises(ParameterError, match="above the trajectory"):
        record_from_args(args, _trajectory())


def test_docs_parameter_table_is_current():
    # docs/instrument.md embeds the table built from the registry (style guide: docs from registries).
    from pathlib import Path

    from afmforce.instrument.config import parameters_markdown

    doc = (Path(__file__).parents[2] / "docs" / "instrument.md").read_text(encoding="utf-8")
    start, end = "<!-- parameters:start -->\n", "<!-- parameters:end -->"
    embedded = doc[doc.index(start) + len(start):doc.index(end)]
    assert embedded == parameters_markdown()
