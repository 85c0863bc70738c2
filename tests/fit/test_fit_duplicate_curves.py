"""One measurement given twice is refused: the joint fit counts every curve as independent data,
so a copy halves every variance. Before, ``afmforce fit a.txt a.txt`` (or the web's fit with an
upload's id listed twice) fitted it as two curves -- intervals tighter by sqrt(2), from no new data."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from afmforce.datasets import fit_example
from afmforce.errors import ParameterError
from afmforce.fit.data import prepare_curves
from afmforce.io import load


def test_the_same_samples_twice_are_refused(tmp_path):
    first = fit_example("speeds")[0]
    copy = tmp_path / "copy.txt"
    shutil.copy(first, copy)                       # the same measurement under another name
    a, b = load(first)[0], load(copy)[0]
    assert np.array_equal(a.deflection_signal, b.deflection_signal)
    with pytest.raises(ParameterError, match=rf"curves {first.name} and copy.txt hold the same samples"):
        prepare_curves([a, b], [first.name, "copy.txt"])


def test_curves_of_different_speeds_are_kept():
    paths = fit_example("speeds")[:2]
    fc = prepare_curves([load(p)[0] for p in paths], [p.name for p in paths])
    assert [c.name for c in fc] == [p.name for p in paths]
    assert fc[0].velocity != fc[1].velocity


def test_the_cli_names_the_duplicate(capsys):
    from afmforce.cli.main import main

    p = str(fit_example("speeds")[0])
    assert main(["fit", p, p, "--free", "hamaker", "--no-profile"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "hold the same samples" in err and err.startswith("error: curves ")

