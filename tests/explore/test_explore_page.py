"""The interactive page: its embedded data are the simulations, and the page is self-contained."""

import json
import re

import numpy as np
import pytest

from afmforce.cli.main import main
from afmforce.dynamics import simulate
from afmforce.explore import build_page, compute_grid


@pytest.fixture(scope="module")
def grid():
    return compute_grid(velocities=(0.1e-6, 1e-6), xis=(0.01, 0.1), points=200)


def test_grid_shape_and_data_match_direct_simulation(grid):
    assert len(grid.runs) == 4
    run = grid.runs[1]  # row-major in velocity: (0.1 um/s, xi = 0.1)
    assert run["velocity"] == 0.1e-6 and run["xi"] == 0.1
    ev = simulate(velocity=0.1e-6, xi=0.1).events
    # summary numbers are the engine's events (spec 7: -1.04 nm, 0.454 nm)
    assert run["summary"]["min_apparent_deflection"] == pytest.approx(ev.min_apparent_deflection, abs=2e-12)
    assert run["summary"]["min_apparent_deflection"] == pytest.approx(-1.04e-9, abs=0.02e-9)
    assert run["summary"]["hysteresis_offset"] == pytest.approx(0.454e-9, abs=0.01e-9)
    # curves are thinned but real: the apparent minimum on the page is close to the event's
    z2a = np.array([v for v in run["z2_app"] if v is not None])
    assert z2a.min() <= ev.min_apparent_deflection + 0.05e-9


def test_page_is_self_contained_and_embeds_json(grid, tmp_path):
    path = build_page(tmp_path / "page.html", grid)
    html = path.read_text()
    assert "<script src" not in html and "http://" not in html.replace("http://www.w3.org/2000/svg", "")
    m = re.search(r"const DATA = (\{.*?\});\n", html, re.S)
    data = json.loads(m.group(1))
    assert data["velocities"] == [0.1e-6, 1e-6]
    assert len(data["runs"]) == 4
    assert data["static"]["jump_in_separation"] == pytest.approx(3.92e-9, rel=0.01)  # spec 7, k = 0.1387


def test_cli_refuses_to_overwrite(tmp_path, capsys):
    out = tmp_path / "x.html"
    out.write_text("keep me")
    assert main(["explore", "--out", str(out), "--velocities", "1um/s", "--xis", "0.1kg/s"]) == 2
    assert out.read_text() == "keep me"
    assert "exists" in capsys.readouterr().err
    assert main(["explore", "--out", str(out), "--velocities", "1um/s", "--xis", "0.1kg/s", "--force"]) == 0
    assert "const DATA" in out.read_text()
