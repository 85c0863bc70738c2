"""The curves users bring: real and virtual curves stored the ways instruments and export scripts store them.

Each transformed curve gives either the intact curve's numbers (checked against an independent
computation: the virtual curve's known truth, numpy on the raw columns) or a refusal that says why; never
a different number in silence.

* the segment labels swapped, a run stored from its end to its start (with its time column running down,
  or a fresh one), both runs stored backwards, several approach-retract cycles in one record
  (:mod:`afmforce.analysis.orientation`); before: a static curve's 56 nN pull-off came out 0.03 nN with
  its labels swapped, two cycles made a hard contact "soft" with no adhesion, a reversed retract was
  refused as "no contact region found on the retract run";
* a curve entirely in contact (no free baseline): refused, where before it reported a sensitivity of
  -1.2 um/V (negative) or 7 x the truth (:func:`afmforce.analysis.steps.contact._check_free_baseline`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from afmforce import forces
from afmforce.analysis.orientation import contact_side, orient
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.synthetic import static_curve
from afmforce.constants import HAMAKER, Z0
from afmforce.errors import AnalysisError
from afmforce.io import load

DATA = Path(__file__).resolve().parents[1] / "data"


def _take(c, order, *, keep_time=False):
    """The curve with its samples in ``order`` (the time column left in array order with ``keep_time``)."""
    pick = lambda a: None if a is None else np.asarray(a)[order]  # noqa: E731
    return dataclasses.replace(c, time=np.asarray(c.time) if keep_time else pick(c.time),
                               piezo_nominal=pick(c.piezo_nominal), piezo_measured=pick(c.piezo_measured),
                               deflection_signal=pick(c.deflection_signal), segment=pick(c.segment))


def _runs(c):
    seg = np.asarray(c.segment)
    return np.flatnonzero(seg == 0), np.flatnonzero(seg == 1)


def labels_swapped(c):
    seg = np.asarray(c.segment)
    return dataclasses.replace(c, segment=np.where(seg == 0, 1, 0).astype(seg.dtype))


def retract_backwards_in_time(c):
    a, r = _runs(c)
    return _take(c, np.concatenate([a, r[::-1]]))


def retract_backwards_fresh_time(c):
    a, r = _runs(c)
    return _take(c, np.concatenate([a, r[::-1]]), keep_time=True)


def both_backwards_fresh_time(c):
    a, r = _runs(c)
    return _take(c, np.concatenate([a[::-1], r[::-1]]), keep_time=True)


def two_cycles(c):
    t = np.asarray(c.time)
    cat = lambda a: None if a is None else np.concatenate([a, a])  # noqa: E731
    return dataclasses.replace(c, time=np.concatenate([t, t + t[-1] + (t[1] - t[0])]),
                               piezo_nominal=cat(c.piezo_nominal), piezo_measured=cat(c.piezo_measured),
                               deflection_signal=cat(c.deflection_signal), segment=cat(c.segment))


TRANSFORMS = {f.__name__: f for f in (labels_swapped, retract_backwards_in_time, retract_backwards_fresh_time,
                                      both_backwards_fresh_time, two_cycles)}
#: What each transform's warning says.
SAYS = {"labels_swapped": "labels are swapped", "retract_backwards_in_time": "stored backwards in time",
        "retract_backwards_fresh_time": "retract is stored from its end", "both_backwards_fresh_time":
        "both runs are stored from their end", "two_cycles": "2 approach-retract cycles"}


def _numbers(r):
    return (r.spring_constant, r.sensitivity_used, r.adhesion_force, r.pull_off_force,
            r.jump_in_separation, r.hamaker_radius)


@pytest.fixture(scope="module")
def virtual():
    """A static curve of known truth: k 0.21 N/m, R 220 nm, eq 2, InvOLS 50 nm/V, 0.05 nm noise."""
    c = static_curve(noise=0.05e-9)
    return c, analyze(c)


@pytest.fixture(scope="module")
def sin():
    c = load(DATA / "asylum-mfp3d_SiN-tip_air.ibw")[0]
    return c, analyze(c)


def test_intact_virtual_curve_meets_its_truth(virtual):
    """The anchor of the battery: the intact virtual curve's numbers against its known truth."""
    c, r = virtual
    assert r.contact_kind == "hard"
    assert r.sensitivity_used == pytest.approx(c.truth["sensitivity"], rel=0.01)
    pull_off = forces.max_attraction_force(220e-9, HAMAKER, Z0)      # the static pull-off: the law's minimum
    assert r.pull_off_force == pytest.approx(pull_off, rel=0.01)
    assert r.hamaker_radius == pytest.approx(c.truth["hamaker_radius"], rel=0.05)
    j = c.truth["jump_in_index"]
    assert r.jump_in_separation == pytest.approx(c.truth["separation"][j], abs=0.3e-9)


def test_intact_real_curve_meets_numpy(sin):
    """The real anchor: the Asylum SiN tip's adhesion against numpy on the raw force column (the retract's
    lowest force less its far baseline's median)."""
    c, r = sin
    f = np.asarray(c.deflection_signal)
    ret = f[np.asarray(c.segment) == 1]
    assert c.deflection_unit == "N"
    expected = float(ret.min() - np.median(ret[int(0.7 * ret.size):]))
    assert r.adhesion_force == pytest.approx(expected, rel=0.03)


@pytest.mark.parametrize("name", sorted(TRANSFORMS))
@pytest.mark.parametrize("which", ["virtual", "sin"])
def test_stored_otherwise_gives_the_intact_numbers(name, which, virtual, sin):
    c, ref = virtual if which == "virtual" else sin
    bad = TRANSFORMS[name](c)
    res = analyze(bad)
    assert res.contact_kind == ref.contact_kind
    assert _numbers(res) == pytest.approx(_numbers(ref), rel=1e-9, nan_ok=True)
    assert any(SAYS[name] in w for w in res.warnings), res.warnings
    assert not any(SAYS[name] in w for w in ref.warnings)


def test_position_from_the_sample_is_still_turned_round_not_relabelled(virtual):
    """The case the relabelling must not take: a position stored as the distance from the sample (the
    contact at its low end) is turned round, as before."""
    c, ref = virtual
    z = -np.asarray(c.piezo_nominal)
    res = analyze(dataclasses.replace(c, piezo_nominal=z, piezo_measured=z))
    assert res.contact_kind == ref.contact_kind
    assert _numbers(res) == pytest.approx(_numbers(ref), rel=1e-9, nan_ok=True)
    assert any("turned round" in w for w in res.warnings)
    assert not any("relabelled" in w or "order of acquisition" in w for w in res.warnings)


def test_contact_side_is_read_off_the_signal(virtual):
    c, _ = virtual
    z, s = np.asarray(c.piezo_nominal), np.asarray(c.deflection_signal)
    assert contact_side(z, s) == 1
    assert contact_side(-z, s) == -1
    flat = np.random.default_rng(1).normal(0.0, 1e-3, z.size)   # never reaches the surface: unclear
    assert contact_side(z, flat) == 0


#: The stand-in calibrations of the files that store none (tests/data/meta_override.json).
OVERRIDES = {k: v for k, v in json.loads((DATA / "meta_override.json").read_text()).items() if not k.startswith("_")}


@pytest.mark.parametrize("path", sorted(p for p in DATA.glob("*.*") if not p.name.startswith(".") and p.suffix not in (".md", ".py", ".json", ".psd",
                                                                                       ".tnd", ".gitattributes")),
                         ids=lambda p: p.name)
def test_readers_curves_are_left_as_they_are(path):
    """The readers give every curve in the conventions: nothing is reordered or relabelled (the same object
    back, no note). Measured on the 790 curves of tests/data, its corpus and the shared real files: none."""
    for c in load(path, meta_override=OVERRIDES.get(path.name))[:8]:
        out, notes = orient(c)
        assert out is c and notes == ()


@pytest.mark.parametrize("start", [-5e-9, 0.0, 2e-9, 10e-9])
def test_curve_entirely_in_contact_is_refused(start):
    """An approach that starts on its hard contact line has no zero of force: refused (before: sensitivity -1.23 um/V at
    2 nm, 0.36 um/V at 10 nm, 5.2 um/V with a "soft" contact at 0, against the truth 50 nm/V)."""
    c = static_curve(noise=0.05e-9)
    keep = np.asarray(c.piezo_nominal) > start
    with pytest.raises(AnalysisError, match="no free baseline.*zero of force is undetermined"):
        analyze(_take(c, np.flatnonzero(keep)))


def test_real_curve_cut_to_its_contact_is_refused(sin):
    """The SiN tip's curve keeping only the samples pressed beyond contact (the force above its baseline by
    more than a third of its largest): no free baseline, refused."""
    c, _ = sin
    f = np.asarray(c.deflection_signal)
    app = np.asarray(c.segment) == 0
    base = float(np.median(f[app][: app.sum() // 3]))
    keep = np.flatnonzero(f - base > (f.max() - base) / 3)
    with pytest.raises(AnalysisError, match="no free baseline"):
        analyze(_take(c, keep))


@pytest.mark.parametrize("end", [-100e-9, -200e-9, -260e-9])
def test_retract_ending_before_the_pull_off_reports_no_adhesion_but_its_bound(end):
    """The record stops while the tip is still held on its adhesive contact line (the static curve's
    pull-off is at -267 nm): no adhesion, but why, with the pull at the last sample as a lower bound
    (k x the truth's deflection there). Before: an adhesion of 0.11 nN "at -3237 nm from contact" (at
    -100 nm), against the truth's 56 nN pull-off."""
    c = static_curve(noise=0.05e-9)
    keep = np.flatnonzero(np.asarray(c.piezo_nominal) > end)
    res = analyze(_take(c, keep))
    assert math.isnan(res.adhesion_force) and math.isnan(res.pull_off_force)
    why = res.not_applicable["adhesion"]
    assert why.startswith("not available: the retract ends before the pull-off")
    bound = float(why.split("larger than ")[1].split(" nN")[0]) * 1e-9
    pulled = -c.truth["spring_constant"] * c.truth["deflection"][keep[-1]]     # the pull at the last sample
    assert bound == pytest.approx(pulled, rel=0.05)
    assert bound < -forces.max_attraction_force(220e-9, HAMAKER, Z0)           # a lower bound of the truth


def test_retract_reaching_past_the_pull_off_keeps_its_adhesion(virtual):
    """The same curve with the whole retract: the adhesion is the truth's, no such reason."""
    c, r = virtual
    assert "adhesion" not in r.not_applicable
    assert r.adhesion_force == pytest.approx(forces.max_attraction_force(220e-9, HAMAKER, Z0), rel=0.01)
