"""The server's warm-up loads the analysis kernels too, not only the integrator: before, the first
upload of a session on a cold numba cache compiled them inside its request and, on a busy machine,
ran past the 60 s budget (504 for a 221-sample raw file that takes 6 s once compiled). Checked in a
fresh interpreter (other tests of this process may have run the analysis already)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

pytest.importorskip("fastapi")

SCRIPT = textwrap.dedent("""
    import tempfile, time
    from pathlib import Path
    from fastapi.testclient import TestClient
    from afmforce.web import Settings, create_app
    from afmforce.analysis._regions_kernel import run_regions_kernel
    app = create_app(Settings(data=Path(tempfile.mkdtemp()) / "data", spare_job=False))
    with TestClient(app, base_url="http://127.0.0.1") as c:
        deadline = time.monotonic() + 600
        while not c.get("/api/health").json()["warm"] and time.monotonic() < deadline:
            time.sleep(0.2)
        print(c.get("/api/health").json()["warm"], len(run_regions_kernel.signatures))
""")


def test_the_warm_up_loads_the_analysis_kernels():
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stderr[-2000:]
    warm, signatures = r.stdout.split()
    assert warm == "True" and int(signatures) >= 1, r.stdout
