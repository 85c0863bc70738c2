"""``afmforce fit MAP`` as a user types it, on a force map: refused at once in one line, not fitted
for more than 15 minutes in 1 GB (found by the audit on the Nanosurf 10 x 10 map).

* More than :data:`~afmforce.fit.core.MAX_CURVES` curves (the map's 100) are refused before any work:
  ``--free hamaker --xi 0``, which the one-speed refusal suggests, ran past 900 s in 1.1 GB.
* Curves whose files set one speed are one speed: the map's header says 1 um/s for every curve, but
  the position channel of its first curve moves at 1.21 um/s against 0.96-0.99 for the others, so
  the measured speeds alone spanned 1.26x, past the 1.2x that counted as two speeds, and xi was fitted.
"""

from __future__ import annotations

import numpy as np
import pytest

from afmforce.cli.main import main
from afmforce.fit import fit_dynamic
from afmforce.fit.core import MAX_CURVES, IdentifiabilityError
from afmforce.io import load
from realdata import real_file

NID = "nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid"


@pytest.mark.parametrize("free", [[], ["--free", "hamaker", "--xi", "0"]])
def test_a_map_of_100_curves_is_refused_in_one_line(capsys, free):
    path = real_file(NID)
    before = path.read_bytes()
    assert main(["fit", str(path), *free]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: a joint fit of 100 curves: the dynamic fit takes at most {MAX_CURVES}")
    assert err.count("\n") == 1 and "Traceback" not in err
    assert path.read_bytes() == before


def test_curves_at_one_set_speed_are_one_speed_whatever_their_measured_scatter():
    curves = load(real_file(NID))[:8]
    assert {c.metadata["velocity"] for c in curves} == {1e-6}            # the header's one speed
    speeds = []
    for c in curves:                      # the measured position's speed over each approach (numpy)
        a = np.asarray(c.segment) == 0
        speeds.append(np.polyfit(np.asarray(c.time)[a], np.asarray(c.piezo_measured)[a], 1)[0])
    assert max(speeds) / min(speeds) > 1.2 and max(speeds) == pytest.approx(1.214e-6, rel=2e-3)
    with pytest.raises(IdentifiabilityError, match=r"^xi cannot be determined from curves at one driving speed "
                                                   r"\(1 um/s\)"):
        fit_dynamic(curves, "beam", free=("hamaker", "xi"))
