"""A bad value in a settings file is named as the user wrote it: the file and its key (faces audit 2026-11-29).

Was: ``[grid] velocity = [1e400]`` in a sweep TOML file answered ``--grid velocity inf um/s is out of range``
(a flag the user never typed, and no file); ``{lo = .., hi = 1e400}`` printed a numpy RuntimeWarning first; an
instrument TOML file's ``[noise] white = -1`` answered ``noise white must be zero or positive`` without the
file; a calibration JSON's ``"spring_constant": "abc"`` was dropped silently (the file's k used) and its
``-1`` was named ``probe.spring_constant``. The tests walk the declarations: every sweep parameter of
:data:`afmforce._fields.QUANTITIES`, every instrument parameter, every probe key of a calibration file."""

from __future__ import annotations

import argparse
import json
import math

import pytest

from afmforce._fields import QUANTITIES
from afmforce.calibration.record import PROBE_KEYS, parse_calibration
from afmforce.cli.main import main
from afmforce.errors import AfmforceError
from afmforce.instrument.config import PARAMETERS
from afmforce.sweep.simulation import simulation_dimensions

SWEPT = [n for n in simulation_dimensions() if n in QUANTITIES]


def _outside(spec) -> float:
    """A finite value [SI] outside the declared range."""
    if spec.lo is not None:
        return spec.lo - max(1.0, abs(spec.lo))
    return spec.hi + max(1.0, abs(spec.hi))


def _sweep_error(tmp_path, capsys, text: str) -> str:
    path = tmp_path / "my sweep.toml"
    path.write_text(text)
    out = tmp_path / "out"
    code = main(["sweep", "--config", str(path), "--serial", "--out", str(out)])
    err = [e for e in capsys.readouterr().err.strip().splitlines() if not e.startswith("afmforce: first run")]
    assert code == 2 and len(err) == 1, err
    assert not out.exists()                                  # nothing written
    assert f"--config {path}: " in err[0] and "Traceback" not in err[0], err[0]
    return err[0]


@pytest.mark.parametrize("table", ["set", "grid"])
@pytest.mark.parametrize("name", SWEPT)
def test_every_sweep_key_out_of_range_names_the_file_and_key(tmp_path, capsys, name, table):
    bad = _outside(QUANTITIES[name])
    other = "xi = [0.01]" if name != "xi" else "hamaker = [1e-20]"
    text = f"[{table}]\n{name} = {[bad] if table == 'grid' else bad}\n" + (f"[grid]\n{other}\n" if table == "set" else "")
    err = _sweep_error(tmp_path, capsys, text.replace("'", ""))
    assert f"[{table}] {name} " in err and "is out of range" in err, err
    assert "--grid" not in err and "--set" not in err


@pytest.mark.parametrize("value", ["1e400", "-1e400", "nan", "inf"])
@pytest.mark.parametrize("where", ["[grid]\nvelocity = [{v}]", "[grid]\nvelocity = {{lo = 1e-7, hi = {v}, n = 3}}",
                                   "[set]\nvelocity = {v}\n[grid]\nxi = [0.01]",
                                   "[range]\nvelocity = {{lo = 1e-7, hi = {v}}}\n[sweep]\nn = 2"])
def test_a_number_beyond_the_floats_names_the_file_and_key(tmp_path, capsys, value, where):
    err = _sweep_error(tmp_path, capsys, where.format(v=value) + "\n")
    table = where.split("]")[0][1:]
    assert f"[{table}] velocity" in err and "not a finite number" in err, err


@pytest.mark.parametrize("text,words", [("[grid]\nxi = [true]", "[grid] xi expects a number"),
                                        ("[grid]\nmodel = [\"spring\", \"bogus\"]", "[grid] model bogus: unknown"),
                                        ("[range]\nxi = {lo = 0.1, hi = 0.01}\n[sweep]\nn = 3", "[range] xi=0.1:0.01"),
                                        ("[grid]\nvelocity = \"-1um/s,1um/s\"", "[grid] velocity -1 um/s is out of range")])
def test_wrong_types_and_orders_name_the_file_and_key(tmp_path, capsys, text, words):
    assert words in _sweep_error(tmp_path, capsys, text + "\n")


def test_a_flag_still_names_the_flag_over_the_files_entry(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text("[grid]\nvelocity = [1e-6]\n")
    assert main(["sweep", "--config", str(path), "--grid", "velocity=1m/s,1um/s", "--serial",
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--grid velocity 1e+06 um/s is out of range" in err and str(path) not in err


# ---- the instrument TOML file: every scalar parameter, each bad kind of value ---------------------------
SCALARS = [k for k, p in PARAMETERS.items() if not p.is_list]


@pytest.mark.parametrize("key", SCALARS)
def test_every_instrument_key_refused_names_the_file_and_key(tmp_path, key):
    from afmforce.cli._instrument_opts import check_instrument_args

    table, name = key.split(".")
    refused = 0
    for value in ("nan", "1e400", "-1e400"):
        path = tmp_path / "instrument.toml"
        path.write_text(f"[{table}]\n{name} = {value}\n")
        args = argparse.Namespace(instrument="typical", instrument_config=str(path), raw=None, force=False)
        try:
            check_instrument_args(args)
        except AfmforceError as exc:
            refused += 1
            msg = str(exc)
            assert str(path) in msg and (f"[{table}] {name}" in msg or key in msg), msg
    assert refused == 3, key             # nan and the infinities are no instrument's values


# ---- the calibration file (--probe-calibration, the web's upload) ---------------------------------------
@pytest.mark.parametrize("key", list(PROBE_KEYS))
@pytest.mark.parametrize("value", ["\"abc\"", "true", "[1]", "-1", "1e400", "NaN"])
def test_every_calibration_key_refused_names_the_file_and_key(key, value):
    text = '{"afmforce_calibration": 1, "method": "thermal", "%s": %s}' % (key, value)
    with pytest.raises(AfmforceError) as exc:
        parse_calibration(text, "calib.json")
    assert str(exc.value).startswith(f"calib.json: {key} "), str(exc.value)


def test_a_calibration_key_in_range_is_read():
    values = {k: (QUANTITIES[k].lo * 10 if QUANTITIES[k].lo else 1.0) for k in PROBE_KEYS}
    text = json.dumps({"afmforce_calibration": 1, **values})
    assert parse_calibration(text, "c.json") == pytest.approx(values)
    assert all(math.isfinite(v) for v in values.values())


def test_the_cli_names_the_calibration_file_not_the_probe_field(tmp_path, capsys):
    cal = tmp_path / "calib.json"
    cal.write_text('{"afmforce_calibration": 1, "method": "sader", "spring_constant": -1}')
    from afmforce.datasets import path as example

    assert main(["analyze", str(example("asylum-air")), "--probe-calibration", str(cal)]) == 2
    err = capsys.readouterr().err
    assert f"{cal}: spring_constant -1 N/m is out of range" in err and "probe." not in err


def test_a_list_key_refused_is_named_not_its_partner(tmp_path):
    """``creep_times = [nan]`` beside a valid ``creep_amplitudes``: the message names creep_times (was: the
    partner, refused alone for its length)."""
    from afmforce.cli._instrument_opts import check_instrument_args

    path = tmp_path / "instrument.toml"
    path.write_text("[piezo]\ncreep_amplitudes = [0.01]\ncreep_times = [nan]\n")
    args = argparse.Namespace(instrument=None, instrument_config=str(path), raw=None, force=False)
    with pytest.raises(AfmforceError, match=r"\[piezo\] creep_times = \(nan,\): piezo creep_times must be"):
        check_instrument_args(args)
