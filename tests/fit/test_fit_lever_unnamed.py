"""A file without the lever's spring constant is not fitted with the model's default lever in
silence (the walk of 2026-11-29): curves in metres (or volts with their sensitivity) need no k to be
calibrated, but the model's lever does, and the fitted A*R and friction scale with it. Virtual AFM
curves of a lever twice as stiff as the default (``simulate --instrument typical --B 7e-13``,
k = 0.2775 N/m, seed 4) with the spring-constant lines removed were fitted as typed with the
default 0.1387 N/m and no warning."""

from __future__ import annotations

import json

import pytest

from afmforce import datasets
from afmforce.cli.main import main

FAST = ["--free", "hamaker", "--xi", "0.01kg/s", "--no-profile", "--no-compare", "--json"]


def _copies(tmp_path, drop):
    """The shipped example's first two speeds; the spring-constant line dropped in the files ``drop``."""
    out = []
    for i, src in enumerate(datasets.fit_example("speeds")[:2]):
        lines = src.read_text().splitlines(keepends=True)
        if i in drop:
            lines = [ln for ln in lines if not ln.startswith("# spring_constant:")]
        dst = tmp_path / src.name
        dst.write_text("".join(lines))
        out.append(str(dst))
    return out


def _warnings(capsys):
    cap = capsys.readouterr()
    return json.loads(cap.out)["warnings"], cap.err


def test_no_file_gives_k_the_default_lever_is_named(tmp_path, capsys):
    assert main(["fit", *_copies(tmp_path, {0, 1}), *FAST]) == 0
    warns, err = _warnings(capsys)
    hit = [w for w in warns if "no curve's file gives the lever's spring constant" in w]
    assert len(hit) == 1 and "0.1387 N/m" in hit[0]
    assert "--meta spring_constant=VALUE" in err and "--k0" in err   # the flags, as the CLI renders keys


def test_one_file_without_k_is_named(tmp_path, capsys):
    files = _copies(tmp_path, {1})
    assert main(["fit", *files, *FAST]) == 0
    warns, _ = _warnings(capsys)
    name = files[1].rsplit("/", 1)[1]
    assert any(w.startswith(f"{name}: no spring constant in the file; taken as the other curves' 0.1387")
               for w in warns)


@pytest.mark.parametrize("drop", [set(), {0, 1}])
def test_no_warning_when_every_file_or_the_user_gives_k(tmp_path, capsys, drop):
    extra = ["--k0", "0.1387N/m"] if drop else []
    assert main(["fit", *_copies(tmp_path, drop), *FAST, *extra]) == 0
    warns, _ = _warnings(capsys)
    assert not any("spring constant" in w and ("no curve's file" in w or "no spring constant in" in w)
                   for w in warns)
