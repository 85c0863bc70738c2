"""Issue 31 item 6: Ctrl-C prints one line in every executor, and a sweep stopped before any run
leaves no store (no manifest) behind.

The swept function itself sends SIGINT to the process group, as a terminal does on Ctrl-C
(so the test does not depend on timing): in the serial executor it reaches the command's own
process; with Dask it reaches the command and its worker processes, which must stay silent.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).parent
SCRIPT = """
import sys
import afmforce.sweep.simulation as simulation
import _interrupt_helper
simulation.simulate_run = _interrupt_helper.interrupting_run
from afmforce.cli.main import main
sys.exit(main(sys.argv[1:]))
"""


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)   # a background shell may have set it ignored


@pytest.mark.parametrize("where", [["--serial"], ["--workers", "2"]], ids=["serial", "dask"])
def test_ctrl_c_prints_one_line_and_leaves_no_empty_store(tmp_path, where):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(HERE), os.environ.get("PYTHONPATH", "")]))
    argv = [sys.executable, "-c", SCRIPT, "sweep", "--grid", "velocity=1um/s,2um/s", "--chunk-size", "1",
            "--out", str(tmp_path / "sw"), *where]
    proc = subprocess.run(argv, capture_output=True, text=True, env=env, timeout=300, start_new_session=True,
                          preexec_fn=_default_sigint)
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr.strip() == "error: interrupted", proc.stderr
    assert not list((tmp_path / "sw").glob("*/manifest.json"))
