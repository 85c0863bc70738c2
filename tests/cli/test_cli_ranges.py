"""Issue 11 item 3: nonsense is refused up front -- exit 2, one line, before any work.

"Before any work" is checked by making the work itself fail loudly: the function
that would run (simulate, static_analysis, analyze_files, run_sweep, ...) is
replaced by one that raises, so a case that got past the checks fails the test
with a traceback instead of exit status 2.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from afmforce.cli.main import main


class WorkStarted(Exception):
    pass


def _boom(*args, **kwargs):
    raise WorkStarted("the work started although the input is nonsense")


@pytest.fixture
def no_work(monkeypatch):
    import afmforce.cli.diagnose as diagnose
    import afmforce.cli.statics as statics
    import afmforce.dynamics as dynamics
    import afmforce.sweep as sweep
    import afmforce.sweep.files as sweep_analysis

    monkeypatch.setattr(statics, "static_analysis", _boom)
    monkeypatch.setattr(diagnose, "diagnose", _boom)
    monkeypatch.setattr(dynamics, "simulate", _boom)
    monkeypatch.setattr(sweep, "run_sweep", _boom)
    monkeypatch.setattr(sweep_analysis, "plan_curves", _boom)
    monkeypatch.setattr(sweep_analysis, "analyze_files", _boom)
    import afmforce.paper.reproduce as reproduce

    monkeypatch.setattr(reproduce, "reproduce", _boom)


def refused(capsys, argv) -> str:
    """Run ``argv``; assert exit 2 and one line on stderr; return that line."""
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse refuses while parsing
        code = exc.code
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1, err
    assert err.startswith("error: ") and "Traceback" not in err
    return err


CURVE = str(Path(__file__).parents[1] / "data" / "asylum-mfp3d_SiN-tip_air.ibw")  # exists (a missing file is refused first), never analysed: the checks come first

CASES = [
    # (argv, fragments the one line must contain)
    (["statics", "--k0", "1e30N/m"], ["--k0 1e30N/m", "out of range", "[0.0001 N/m, 1000 N/m]"]),
    (["statics", "--L1", "1m", "--L0", "1um"], ["--L1 1m", "out of range", "1 mm"]),
    (["statics", "--L1", "1mm", "--L0", "1um"], ["--L1 1 mm is not shorter than the flexible beam --L0 1 um"]),
    (["statics", "--B", "1e-5"], ["k0 = 3B/L0^3", "out of range"]),
    (["statics", "--friction", "none", "--mu", "5nN"], ["--mu is ignored by --friction none"]),
    (["statics", "--friction", "constant", "--mu", "5nN", "--xi", "0.1"], ["--xi is ignored by --friction constant"]),
    (["diagnose", "--velocity", "1e6m/s"], ["--velocity 1e6m/s", "[0.1 nm/s, 10 mm/s]"]),
    (["diagnose", "--hamaker", "1J"], ["--hamaker 1J", "[1e-22 J, 1e-17 J]"]),
    (["analyze", CURVE, "--sensitivity", "1m/V"], ["--sensitivity 1m/V", "[0.1 nm/V, 10 um/V]"]),
    (["analyze", CURVE, "--radius", "-5nm"], ["--radius -5nm", "(0, 1 mm]"]),
    (["analyze", CURVE, "--resonance-frequency", "0"], ["--resonance-frequency 0", "[1 Hz, 100 MHz]"]),
    (["analyze", CURVE, "--map-quantity", "bogus"], ["--map-quantity bogus: unknown"]),
    (["simulate", "--sample-rate", "1e12Hz"], ["--sample-rate 1e12Hz", "[1 Hz, 100 MHz]"]),
    (["simulate", "--velocity", "1e-15m/s"], ["--velocity 1e-15m/s", "out of range"]),
    (["simulate", "--velocity", "1nm/s", "--sample-rate", "10MHz"], ["3.1e+09 samples", "273 GB"]),
    (["simulate", "--piezo-gain", "1.1"], ["--piezo-gain is ignored without a virtual-instrument output"]),
    (["simulate", "--instrument", "paper"], ["--instrument is ignored without"]),
    (["simulate", "--model", "spring", "--xi", "0.1kg/s"], ["--xi is ignored by --model spring"]),
    (["simulate", "--mass", "1ug"], ["--mass is ignored by --model beam (the default)"]),
    (["simulate", "--friction", "none", "--xi", "0.1kg/s"], ["--xi is ignored by --friction none"]),
    (["simulate", "--zeta", "1"], ["--zeta is ignored by --friction viscous (the default)"]),
    (["simulate", "--friction", "bogus"], ["--friction bogus: unknown; choose one of none, viscous, load"]),
    (["simulate", "--L1", "300um"], ["--L1 300 um is not shorter than the flexible beam --L0 200 um"]),
    (["simulate", "--max-steps", "1.5"], ["--max-steps expects a whole number"]),
    (["sweep", "--grid", "velocity=1um/s,2um/s", "--set", "model=bogus"], ["--set model bogus: unknown"]),
    (["sweep", "--grid", "velocity=1um/s,2um/s", "--set", "theta0=95deg"],
     ["--set theta0 95 deg is out of range", "[-89 deg, 89 deg]"]),
    (["sweep", "--grid", "theta0=-15deg,95deg"], ["--grid theta0 95 deg is out of range"]),
    (["sweep", "--grid", "friction=none,bogus"], ["--grid friction bogus: unknown"]),
    (["sweep", "--grid", "model=spring,beam", "--set", "k0=0.2N/m"],
     ["--set k0: k0 is a field of the beam model's probe", "model spring have none"]),
    (["sweep", "--grid", "velocity=1um/s,2um/s", "--set", "mass=1ug"],
     ["--set mass: mass is a field of the spring model's probe", "model beam have none"]),
    (["sweep", "--range", "velocity=1e-15:1e-6", "--n", "3"], ["--range velocity", "out of range"]),
    (["sweep", "--grid", "velocity=1nm/s,1um/s", "--set", "sample_rate=10MHz"],
     ["the most demanding run of this sweep", "samples"]),
    (["sweep", "--grid", "velocity=1e-6:1e-5:10000", "--grid", "xi=0.01:0.1:100"],
     ["1,000,000 runs is more than 100,000", "--yes"]),   # above limits.MAX_RUNS: refused even with --yes
]


@pytest.mark.parametrize("argv, fragments", CASES, ids=[" ".join(c[0])[:60] for c in CASES])
def test_nonsense_is_refused_before_work(capsys, tmp_path, monkeypatch, no_work, argv, fragments):
    monkeypatch.chdir(tmp_path)
    err = refused(capsys, argv)
    for fragment in fragments:
        assert fragment in err


def test_a_large_sweep_runs_with_yes(capsys, tmp_path, monkeypatch, no_work):
    # --yes lifts only the size check: the run then reaches the engine (here: the stub)
    monkeypatch.chdir(tmp_path)
    argv = ["sweep", "--grid", "velocity=1e-6:1e-5:1000", "--grid", "xi=0.01:0.1:1000", "--yes"]
    assert main(argv) == 1  # the stub's exception: one line, exit 1, no traceback (without --debug)
    assert "the work started" in capsys.readouterr().err
    with pytest.raises(WorkStarted):
        main(["--debug", *argv])


def _outputs(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    bad = str(blocker / "sub" / "out")  # a path below a file can never be created
    return [
        ["simulate", "--out", bad + ".csv"],
        ["simulate", "--plot", bad + ".png"],
        ["simulate", "--instrument", "ideal", "--raw", bad + ".txt"],
        ["analyze", CURVE, "--out", bad],
        ["sweep", "--grid", "velocity=1um/s,2um/s", "--out", bad],
        ["sweep", "--grid", "velocity=1um/s,2um/s", "--out", str(blocker)],
        ["reproduce", "--out", bad],
        ["demo", "--out", bad],
    ]


@pytest.mark.parametrize("i", range(8))
def test_unwritable_out_is_refused_before_work(capsys, tmp_path, monkeypatch, no_work, i):
    monkeypatch.chdir(tmp_path)
    argv = _outputs(tmp_path)[i]
    err = refused(capsys, argv)
    assert "a-file" in err and ("cannot be written" in err or "not a folder" in err)


def test_check_output_really_tries_to_write(tmp_path):
    # a folder where no file can be created is refused even for root (os.access would say yes)
    from afmforce.cli._validate import check_output
    from afmforce.errors import ParameterError

    check_output(tmp_path / "new" / "deeper" / "x.csv")  # creatable: fine, and nothing is left behind
    assert not (tmp_path / "new").exists() and list(tmp_path.iterdir()) == []
    with pytest.raises(ParameterError, match="no permission"):
        check_output("/proc/afmforce-test.csv")
