"""The CLI forms of issue 2 (statics, diagnose, demo) and its error handling."""

import json
import math

import pytest

from afmforce.cli.main import main

GEOM = "--k0 0.13N/m --L0 200um --L1 2um --L2 4um --theta0 -15deg".split()


def run(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_statics_none(capsys):
    code, out, _ = run(capsys, ["statics", *GEOM, "--friction", "none", "--json"])
    d = json.loads(out)
    assert code == 0
    assert d["spring_constant"] == pytest.approx(0.13741, rel=1e-4)
    assert d["calibration_factor"] == pytest.approx(1.29391e-4, rel=1e-5)
    assert d["intrinsic_spring_constant"] == pytest.approx(0.13)
    assert d["spring_constant_tilt_only"] == pytest.approx(0.13 / math.cos(math.radians(15)) ** 2)


def test_statics_constant(capsys):
    _, out, _ = run(capsys, ["statics", *GEOM, "--friction", "constant", "--mu", "5nN", "--json"])
    assert json.loads(out)["hysteresis_offset"] == pytest.approx(0.7622e-9, rel=1e-3)


def test_statics_load(capsys):
    _, out, _ = run(capsys, ["statics", *GEOM, "--friction", "load", "--lambda", "2", "--json"])
    d = json.loads(out)
    assert d["inward"]["spring_constant"] == pytest.approx(0.3434, rel=2e-4)
    assert d["outward"]["calibration_factor"] == pytest.approx(1.2772e-4, rel=1e-4)


def test_statics_pinned(capsys):
    _, out, _ = run(capsys, ["statics", *GEOM, "--friction", "pinned", "--json"])
    d = json.loads(out)
    assert d["calibration_factor"] < 0
    assert d["calibration_factor"] == pytest.approx(-1.5455e-5, rel=1e-4)
    assert d["spring_constant"] > 0


def test_statics_viscous(capsys):
    _, out, _ = run(capsys, ["statics", *GEOM, "--friction", "viscous", "--xi", "0.1kg/s",
                             "--velocity", "0.1um/s", "--json"])
    d = json.loads(out)
    assert d["friction_force"] == pytest.approx(3.0e-9, rel=2e-3)
    # k0 = 0.13 N/m here (B = 3.467e-13); the spec's 0.453 nm uses B = 3.5e-13
    assert d["hysteresis_offset"] == pytest.approx(0.453e-9 * 3.5e-13 / (0.13 * 200e-6**3 / 3), rel=2e-3)


def test_diagnose(capsys):
    argv = ("diagnose --spring-constant 0.21N/m --mass 10ug --radius 100nm --hamaker 5e-19J --z0 0.35nm "
            "--velocity 10um/s --resolution 0.5nm --separation 5nm --json").split()
    code, out, _ = run(capsys, argv)
    d = json.loads(out)
    assert code == 0
    assert d["resonance_frequency"] == pytest.approx(730, rel=0.01)
    assert d["force_gradient"] == pytest.approx(0.067, rel=0.01)
    assert d["inertia_parameter"] == pytest.approx(2.2, rel=0.02)
    assert d["inertial_lag"] == pytest.approx(3.4e-9, rel=0.02)
    assert d["surface_energy"] == pytest.approx(0.0812, rel=1e-3)
    assert d["pull_off_force_jkr"] == pytest.approx(-3 * math.pi * d["surface_energy"] * 100e-9 / 4)
    assert d["static_jump_in_separation"] > 0


def test_tables_print_units(capsys):
    _, out, _ = run(capsys, ["statics"])
    assert "N/m" in out and "nm/rad" in out
    _, out, _ = run(capsys, ["diagnose"])
    assert "Hz" in out and "nm" in out


@pytest.mark.parametrize("argv, fragment", [
    (["statics", "--L0", "5nN"], "error: --L0 expects a length, got 5nN"),
    (["statics", "--theta0", "-95deg"], "theta0"),
    (["statics", "--L0", "-3um"], "L0"),
    (["statics", "--friction", "constant"], "needs mu"),
    (["statics", "--friction", "load"], "needs lam"),
    (["statics", "--k0", "1 parsec"], "--k0 expects"),
    (["diagnose", "--mass", "0kg"], "mass"),
])
def test_bad_input_one_line_exit_2(capsys, argv, fragment):
    code = None
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse usage errors exit directly
        code = exc.code
    out, err = capsys.readouterr()
    assert code == 2
    assert fragment in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


def test_first_run_notice_only_when_the_integrator_is_not_cached(capsys, monkeypatch):
    """A simulating command says on stderr that it compiles (first run, no cache); stdout of
    --json stays JSON; a cached integrator gives no notice, and other commands never do; a usage
    error comes alone (the notice is printed when the compile starts, after the checks)."""
    from afmforce.dynamics import _helper

    argv = ["simulate", "--model", "spring", "--start=-20nm", "--turn", "-5nm", "--end=-20nm",
            "--check", "off", "--json"]
    monkeypatch.setattr(_helper, "cache_missing", lambda disp: True)
    monkeypatch.setattr(_helper, "_TRIED", False)
    code, _, err = run(capsys, argv[:-1] + ["--xi", "1kg/s"])  # ignored by the spring: usage error first
    assert code == 2 and err.count("\n") == 1 and "compiling" not in err
    code, out, err = run(capsys, argv)
    assert code == 0 and "compiling the integrator" in err
    json.loads(out)
    code, _, err = run(capsys, ["statics", *GEOM, "--json"])
    assert "compiling" not in err
    monkeypatch.undo()
    _, _, err = run(capsys, argv)             # compiled in this process by now
    assert "compiling" not in err


def test_cache_missing_sees_the_numba_cache_index(tmp_path, monkeypatch):
    """``cache_missing``: True for a cache=True function never compiled and without an index
    file, False once compiled (and for a fresh dispatcher of it, which finds the index)."""
    import importlib
    import sys

    from afmforce.dynamics._jit import cache_missing

    (tmp_path / "cm_mod.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return x + 1.0\n")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.syspath_prepend(str(tmp_path))
    import numba.core.config as nconfig

    monkeypatch.setattr(nconfig, "CACHE_DIR", str(tmp_path / "cache"))
    mod = importlib.import_module("cm_mod")
    assert cache_missing(mod.f)
    assert mod.f(1.0) == 2.0
    assert not cache_missing(mod.f)
    del sys.modules["cm_mod"]
    fresh = importlib.import_module("cm_mod")
    assert not fresh.f.signatures and not cache_missing(fresh.f)
    # the source changed (an upgrade): the index on disk is stale, the call will compile
    with open(tmp_path / "cm_mod.py", "a") as fh:
        fh.write("# changed\n")
    del sys.modules["cm_mod"]
    changed = importlib.import_module("cm_mod")
    assert (tmp_path / "cache").exists() and cache_missing(changed.f)
