"""The faces audit (2026-11-29): values every face accepted and then failed on with a bug.

* ``z0`` (the soft-wall length) of 1e-30 m: the static jump-in's cubic raised ``OverflowError``
  (``1/z0^6`` past the largest float) in ``afmforce diagnose``, ``simulate``, ``fit`` (exit 1,
  "unexpected ... a bug") and ``POST /api/simulate`` (500). The cubic is now solved in
  ``u = (z0/h)^3``, finite for any z0, and z0 is declared from 1 pm (a wall thinner than an atom is no wall).
* ``L1`` (the rigid base) of 1e-30 m: the integrator's automatic step budget grew past a 64-bit
  integer (numba ``TypingError`` in the CLI, ``OverflowError`` 500 on the web); 0 was listed as valid
  (``[0, 1 mm]``) and refused by the library ("must be positive"). L1 is declared from 1 nm, and the
  automatic budget never exceeds ``max_steps``' declared most.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from afmforce._fields import QUANTITIES
from afmforce.cli.main import main
from afmforce.forces import static_jump_in_separation, vdw_force_gradient
from test_cli_ranges import refused


@pytest.mark.parametrize("z0", [1e-30, 1e-20, 1e-12, 0.165e-9, 1e-9, 3e-9])
def test_the_static_jump_in_is_the_largest_root_of_the_gradient_for_any_soft_wall(z0):
    k, radius, hamaker = 0.13, 1e-7, 1e-19
    h = float(static_jump_in_separation(k, radius, hamaker, z0))
    peak = 3.0 ** (1.0 / 6.0) * z0          # Fs' = (A R/6)(h^-3 - z0^6 h^-9) is largest here
    steepest = float(vdw_force_gradient(peak, radius, hamaker, z0))
    if steepest <= k:                        # a stiff spring: no instability, no jump
        assert math.isnan(h)
        return
    # independent: the largest root of Fs'(h) = k by bisection (h^3 scaled: the gradient spans decades)
    g = lambda x: float(vdw_force_gradient(x, radius, hamaker, z0)) / k - 1.0  # noqa: E731
    ref = brentq(g, peak, 1e-6, xtol=1e-30, rtol=1e-14)
    assert h == pytest.approx(ref, rel=1e-10)
    if z0 < 1e-15:                           # the hard-wall limit: Fs' = A R/(6 h^3) = k
        assert h == pytest.approx((hamaker * radius / (6.0 * k)) ** (1.0 / 3.0), rel=1e-12)


def test_no_jump_for_a_spring_stiffer_than_the_steepest_attraction():
    z0 = 0.2e-9
    steepest = (1e-19 * 1e-7 / 6.0) * (2.0 / 3.0) * 3.0 ** -0.5 * z0 ** -3     # the docstring's closed form
    h = static_jump_in_separation(np.array([1.01 * steepest, 0.99 * steepest]), 1e-7, 1e-19, z0)
    assert math.isnan(h[0]) and h[1] > 3.0 ** (1.0 / 6.0) * z0


def _refused(capsys, argv) -> str:
    err = refused(capsys, argv)               # exit 2, one line (test_cli_ranges' helper)
    assert err.startswith("error: ") and "unexpected" not in err, err
    return err


@pytest.mark.parametrize("argv, words", [
    (["diagnose", "--z0", "1e-30"], "--z0 1e-30 is out of range: z0"),
    (["simulate", "--z0", "1e-30"], "--z0 1e-30 is out of range: z0"),
    (["simulate", "--L1", "1e-30"], "--L1 1e-30 is out of range: L1"),
    (["simulate", "--L1", "0"], "must lie in [1 nm, 1 mm]"),
    (["statics", "--L1", "0"], "must lie in [1 nm, 1 mm]"),
])
def test_the_command_line_refuses_them_in_one_line(capsys, tmp_path, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    assert words in _refused(capsys, argv)


def test_the_declared_ranges_are_the_library_s():
    from afmforce.cantilever import InclinedCantilever
    from afmforce.errors import ParameterError

    lo = QUANTITIES["L1"].lo
    InclinedCantilever(L0=200e-6, L1=lo, L2=4e-6, theta0=-0.26, k0=0.13)      # the lowest declared: accepted
    with pytest.raises(ParameterError):
        InclinedCantilever(L0=200e-6, L1=0.0, L2=4e-6, theta0=-0.26, k0=0.13)
    assert not QUANTITIES["L1"].contains(0.0) and not QUANTITIES["z0"].contains(1e-30)


def test_the_automatic_step_budget_stays_a_64_bit_integer(monkeypatch):
    """A lever whose fastest mode is absurdly fast (patched in: the declared ranges no longer allow
    one) gets the most steps ``max_steps`` may be, not an integer numba cannot take."""
    import afmforce.dynamics._setup as setup
    from afmforce.dynamics import SimulationConfig, simulate

    monkeypatch.setattr(setup, "_beam_fmax", lambda *a: 1e40)
    monkeypatch.setattr(setup, "_BASES", {})        # a setup cached by an earlier test of this process is not rebuilt
    cfg = SimulationConfig(velocity=10e-6, sample_rate=1e4)
    assert setup._setup(cfg).budget == int(QUANTITIES["max_steps"].hi)
    assert simulate(cfg).solver.status == "success"


def test_the_web_answers_422_naming_the_field(tmp_path):
    pytest.importorskip("fastapi")
    from fastapi.testclient import TestClient

    from afmforce.web import Settings, create_app

    app = create_app(Settings(data=tmp_path / "data", spare_job=False))
    with TestClient(app, base_url="http://127.0.0.1", raise_server_exceptions=False) as client:
        for field in ("L1", "z0"):
            r = client.post("/api/simulate", json={field: 1e-30})
            assert r.status_code == 422, r.text
            assert r.json()["error"]["field"] == field


def test_sader_in_an_inviscid_medium_is_one_line_without_numpy_s_warning(capsys):
    """``calibrate sader --viscosity 0`` printed numpy's "divide by zero" RuntimeWarning (two lines of
    source) above its refusal; the method needs a viscous medium and now says so first."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("default")        # as the command runs: warnings shown, not errors
        err = _refused(capsys, ["calibrate", "sader", "--length", "200um", "--width", "30um",
                                "--frequency", "20kHz", "--quality-factor", "50", "--viscosity", "0"])
    assert "--viscosity 0" in err and "viscous" in err


@pytest.mark.parametrize("host", ["999.1.1.1", "192.0.2.1"])
def test_serve_on_an_address_this_machine_lacks_names_the_host(capsys, host, tmp_path):
    """``serve --host 999.1.1.1`` (no such address) said "choose another --port"."""
    err = _refused(capsys, ["serve", "--host", host, "--data", str(tmp_path / "d"), "--token", "t" * 16])
    assert f"cannot listen on {host}:" in err and "--host" in err and "--port" not in err, err


def test_a_file_past_its_reading_budget_is_not_called_unexpected(capsys, tmp_path, monkeypatch):
    """``analyze FILE --file-timeout ...`` reported a file past its budget as "unexpected
    FileTimeoutError: ..." (the class lives in ``io._guard``, not ``afmforce.errors``), the words of a
    bug; it is the reader's budget, said as such (the CLI's failure line and the web's ``failed``)."""
    from pathlib import Path

    from afmforce.io._guard import FileTimeoutError
    from afmforce.sweep.report import clean_error

    assert clean_error("FileTimeoutError: reading took longer") == "reading took longer"
    assert clean_error("KeyError: 'x'") == "unexpected KeyError: 'x'"        # a bug still says so
    assert issubclass(FileTimeoutError, __import__("afmforce.errors").errors.AfmforceError)
    monkeypatch.chdir(tmp_path)
    curve = Path(__file__).parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw"
    assert main(["analyze", str(curve), "--file-timeout", "1e-9"]) == 1
    err = [e for e in capsys.readouterr().err.splitlines() if e.startswith("failed:")]
    assert len(err) == 1 and "reading took longer than" in err[0] and "unexpected" not in err[0], err
