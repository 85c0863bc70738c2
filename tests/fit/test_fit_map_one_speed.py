"""``afmforce fit MAP`` as a user types it, on a force map recorded at one set speed: refused at
once (xi needs >= 2 speeds), not fitted for more than 10 minutes in 1 GB.

The Nanosurf 10 x 10 map (1 um/s in its header for every curve): the speeds measured on its
position channel scatter, one curve at 1.21 um/s against 0.96 for the rest, so the measured
speeds alone spanned 1.26x, past the 1.2x that counted as two speeds, and the 100-curve joint
fit of xi ran past 600 s (found by the audit). The files' set speeds now decide too."""

from __future__ import annotations

import warnings

import pytest

from afmforce.cli.main import main
from afmforce.fit import prepare_curves
from afmforce.io import load
from realdata import real_file

NID = "nanosurf-nid_spectroscopy-map_10x10_Tap150Al.nid"


def test_a_map_at_one_set_speed_is_refused_in_one_line(capsys):
    path = real_file(NID)
    curves = load(path)
    assert {c.metadata["velocity"] for c in curves} == {1e-6}            # the header's one speed
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        measured = [fc.velocity for fc in prepare_curves(curves, [f"#{i}" for i in range(len(curves))])]
    assert max(measured) / min(measured) > 1.2                               # the premise: the scatter
    assert main(["fit", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: xi cannot be determined from curves at one driving speed (1 um/s)")
    assert err.count("\n") == 1 and "Traceback" not in err
