"""The next curves users bring: virtual curves of known truth, spoiled the ways instruments and users spoil them.

Each goes through the default :func:`~afmforce.analysis.pipeline.analyze` (what ``afmforce analyze FILE``
runs) and gives the truth's numbers within a stated tolerance, or says why it cannot (a warning naming the
problem, contact kind "none", a step's reason in ``not_applicable``, a refusal); never a wrong number in
silence. The hard curve is :func:`~afmforce.analysis.synthetic.static_curve` (k 0.21 N/m, R 220 nm, eq 2,
InvOLS 50 nm/V, 0.05 nm noise); the soft one the virtual AFM's QI pixel
(:func:`~afmforce.instrument.soft_map.soft_curve`: Hertz approach, DMT retract, E 5 kPa, R 5 um).

Before (the code of fe96f8b) and after, per pathology:

* photodiode clipped over a soft contact (the top 30-60 % of the deflection flat): modulus 3155 and 1082 Pa for
  5000 (the clipped samples were fitted as forces); now 4990-5015 Pa;
* an approach that turns 0.5-3 nm short of the jump-in: a "hard" contact with a sensitivity of -246 and
  -687 nm/V (the attraction's bend fitted as a compliance line); now contact kind "none" and why; one that
  turns 1 nm past it: "hard" with the file's sensitivity, the adhesion right, a jump-in at 3.9 nm for 5.0 and
  A R 3 x low (flagged dynamic); now "none", the adhesion only;
* one sample off by 150 nm in the contact: the jump-in put at 150 nm for 5 nm and no van der Waals fit;
  one 250 nm low on the baseline: the jump-in at 9.9 nm; now the intact numbers and a warning;
* fringes 15 and 50 nm deep (0.3 and 1 V at 50 nm/V, period 320 nm) on a 37 nm contact: sensitivity 214
  and 76 nm/V, adhesion 240 and 84 nN for 56; now the truth's within 0.5 and 2 % and a note;
* already right, kept by these tests: a clipped hard contact, too few samples (refused below 12 a run),
  NaN or inf in any column (refused, naming the column), repeated positions, a drift of 2 V/s, a dwell
  segment with creep, a file's sensitivity 10 x off either way (said, with the factor), a 1 nm jump-in,
  a stiff lever with none, a soft retract's adhesion with no attraction on the approach.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from afmforce import forces
from afmforce.analysis.glitches import GLITCH_SIGMAS, find_glitches
from afmforce.analysis.pipeline import analyze
from afmforce.analysis.steps.contact import CONTACT_RISE_SIGMAS, contact_rise
from afmforce.analysis.synthetic import static_curve
from afmforce.constants import HAMAKER, Z0
from afmforce.errors import AnalysisError
from afmforce.instrument.soft_map import SoftMapConfig, soft_curve

NOISE = 0.05e-9
RADIUS = 220e-9
#: The hard curve's pull-off [N]: the static tip leaves at eq 2's largest attraction.
PULL_OFF = forces.max_attraction_force(RADIUS, HAMAKER, Z0)
SOFT = SoftMapConfig()
MODULUS, HEIGHT, WORK = 5e3, 0.1e-6, 10e-6


def _take(c, order):
    pick = lambda a: None if a is None else np.asarray(a)[order]  # noqa: E731
    return dataclasses.replace(c, time=pick(c.time), piezo_nominal=pick(c.piezo_nominal),
                               piezo_measured=pick(c.piezo_measured), deflection_signal=pick(c.deflection_signal),
                               segment=pick(c.segment))


def _signal(c, s):
    return dataclasses.replace(c, deflection_signal=s)


def _said(res, text):
    return any(text in w for w in res.warnings)


@pytest.fixture(scope="module")
def hard():
    c = static_curve(noise=NOISE)
    return c, analyze(c)


@pytest.fixture(scope="module")
def soft():
    c = soft_curve(SOFT, MODULUS, HEIGHT, WORK, seed=1)
    c = dataclasses.replace(c, metadata={**c.metadata, "radius": SOFT.radius})
    return c, analyze(c)


def _meets_hard_truth(c, r, rel=0.01):
    assert r.contact_kind == "hard"
    assert r.sensitivity_used == pytest.approx(c.truth["sensitivity"], rel=rel)
    assert r.adhesion_force == pytest.approx(PULL_OFF, rel=rel)


def test_intact_curves_meet_their_truth(hard, soft):
    c, r = hard
    _meets_hard_truth(c, r)
    j = c.truth["jump_in_index"]
    assert r.jump_in_separation == pytest.approx(c.truth["separation"][j], abs=0.3e-9)
    c, r = soft
    assert r.contact_kind == "soft"
    assert r.youngs_modulus == pytest.approx(MODULUS, rel=0.01)
    # the retract's adhesion with no attraction on the approach (DMT): 2 pi R w
    assert -r.adhesion_force == pytest.approx(2 * math.pi * SOFT.radius * WORK, rel=0.03)


# --- a clipped photodiode ---------------------------------------------------------------------------------

@pytest.mark.parametrize("level", [0.75, 0.6])
def test_clipped_hard_contact_keeps_its_calibration(hard, level):
    c, _ = hard
    r = analyze(_signal(c, np.minimum(c.deflection_signal, level)))      # the signal tops 0.9 V at the turn
    _meets_hard_truth(c, r)
    assert _said(r, "saturated samples (photodiode clipped) left out of the fits")


@pytest.mark.parametrize("fraction", [0.7, 0.4])
def test_clipped_soft_contact_keeps_its_modulus(soft, fraction):
    """Before: 3155 and 1082 Pa for 5000 (the flat top fitted as a force that stopped growing)."""
    c, _ = soft
    s = np.asarray(c.deflection_signal)
    top = s.min() + fraction * (s.max() - s.min())
    r = analyze(_signal(c, np.minimum(s, top)))
    assert r.youngs_modulus == pytest.approx(MODULUS, rel=0.02)
    assert _said(r, "saturated samples (photodiode clipped)")


# --- an approach that never reaches the surface ------------------------------------------------------------

def _jump_position(c):
    return float(c.truth["position"][c.truth["jump_in_index"]])


@pytest.mark.parametrize("short", [30e-9, 3e-9, 0.5e-9])
def test_approach_stopping_short_has_no_contact(hard, short):
    """The piezo turns ``short`` before the jump-in position: no contact, so no sensitivity, no jump, no
    adhesion; the reason says the approach stopped short. Before: at 3 and 0.5 nm a "hard" contact with a
    sensitivity of -687 and -246 nm/V (the attraction's bend taken for the compliance line)."""
    c = static_curve(noise=NOISE, turn=_jump_position(hard[0]) - short)
    r = analyze(c)
    assert r.contact_kind == "none"
    assert math.isnan(r.sensitivity_used) and math.isnan(r.adhesion_force) and math.isnan(r.jump_in_separation)
    assert "no contact reached" in r.verdict
    assert r.not_applicable["jumps"] == r.not_applicable["adhesion"] == "no contact reached"
    if short < 10e-9:   # the attraction bends the approach's end down (at 30 nm it is flat: the regions' own test)
        assert "the approach's end bends down (an attraction only)" in r.verdict


def test_contact_rise_tells_attraction_from_contact(hard):
    """The check itself: the intact approach climbs hundreds of sigmas (416) above its baseline's line."""
    from afmforce.analysis.state import prepare
    from afmforce.analysis.steps.contact import contact
    from afmforce.analysis.options import ContactOptions

    st = contact(prepare(hard[0], "auto"), ContactOptions())
    assert contact_rise(st.z, st.signal, st.approach) > 50 * CONTACT_RISE_SIGMAS


def test_approach_ending_just_past_the_jump_gives_the_adhesion_only(hard):
    """Turned 1 nm past the jump-in: no compliance line to calibrate, but the retract's pull-off shows the
    touch; with the file's sensitivity it is the truth's adhesion."""
    c = static_curve(noise=NOISE, turn=_jump_position(hard[0]) + 1e-9)
    c = dataclasses.replace(c, metadata={**c.metadata, "sensitivity": c.truth["sensitivity"]})
    r = analyze(c)
    assert r.contact_kind == "none"
    assert "adhesion only" in r.verdict
    assert r.adhesion_force == pytest.approx(PULL_OFF, rel=0.02)


def test_soft_approach_that_never_reaches_the_sample(soft):
    c, _ = soft
    r = analyze(_take(c, np.flatnonzero(np.asarray(c.piezo_nominal) < -HEIGHT - 0.2e-6)))
    assert r.contact_kind == "none" and math.isnan(r.youngs_modulus) and math.isnan(r.adhesion_force)
    assert r.not_applicable["indentation"] == "no contact reached"


# --- few and many samples ------------------------------------------------------------------------------------

def _every(c, n):
    seg = np.asarray(c.segment)
    a, r = np.flatnonzero(seg == 0), np.flatnonzero(seg == 1)
    return np.concatenate([a[np.linspace(0, a.size - 1, n).astype(int)], r[np.linspace(0, r.size - 1, n).astype(int)]])


def test_ten_samples_a_run_are_refused(hard):
    with pytest.raises(AnalysisError, match=r"the approach holds only 10 sample\(s\)"):
        analyze(_take(hard[0], _every(hard[0], 10)))


@pytest.mark.parametrize("n", [20, 30])
def test_few_samples_give_the_sampled_truth(hard, n):
    """20-30 samples a run: the adhesion is the lowest sampled point of the truth's retract (k x its
    deflection; the grid misses the true pull-off by up to a step), the few contact samples said."""
    c, _ = hard
    keep = _every(c, n)
    r = analyze(_take(c, keep))
    ret = keep[np.asarray(c.segment)[keep] == 1]
    sampled = c.truth["spring_constant"] * float(np.min(c.truth["deflection"][ret]))
    assert r.adhesion_force == pytest.approx(sampled, rel=0.01)
    assert r.sensitivity_used == pytest.approx(c.truth["sensitivity"], rel=0.01)
    assert _said(r, "contact samples (fewer than 20")


def test_many_samples(hard):
    """20 x the samples (40,600): the same truth."""
    c = static_curve(noise=NOISE, sample_rate=40e3)
    r = analyze(c)
    _meets_hard_truth(c, r)


# --- glitches, NaN, repeated and wandering positions ------------------------------------------------------------

@pytest.mark.parametrize("where,volts", [("baseline", 5.0), ("baseline", -5.0), ("contact", 3.0)])
def test_single_sample_glitch_is_repaired_and_said(hard, where, volts):
    """One sample 250 nm (5 V) off on the baseline, or 150 nm in the contact. Before: the jump-in at 9.9 nm
    (baseline, low) and 150 nm with no van der Waals fit (contact), for 5.1 nm."""
    c, ref = hard
    i = 200 if where == "baseline" else c.truth["jump_in_index"] + 20
    s = np.array(c.deflection_signal)
    s[i] += volts
    assert find_glitches(s).tolist() == [i]
    r = analyze(_signal(c, s))
    _meets_hard_truth(c, r)
    assert r.jump_in_separation == pytest.approx(ref.jump_in_separation, abs=0.05e-9)
    assert r.hamaker_radius == pytest.approx(ref.hamaker_radius, rel=0.02)
    assert _said(r, f"1 single-sample glitch in the deflection signal (sample {i}: more than {GLITCH_SIGMAS:g}")


def test_jumps_and_turns_are_no_glitches(hard):
    """The jump-in, the pull-off and the turning point change the signal by up to 5000 noise sigmas in one
    sample: none is a glitch (their neighbours do not lie on one line)."""
    assert find_glitches(np.asarray(hard[0].deflection_signal)).size == 0
    assert not any("glitch" in w for w in hard[1].warnings)


@pytest.mark.parametrize("column,name", [("deflection_signal", "deflection signal"), ("piezo_nominal", "position"),
                                         ("time", "time")])
@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_nan_or_inf_in_a_column_is_refused(hard, column, name, bad):
    c, _ = hard
    x = np.array(getattr(c, column), float)
    x[150] = bad
    kw = {column: x, **({"piezo_measured": x} if column == "piezo_nominal" else {})}
    with pytest.raises(AnalysisError, match=f"the {name} has 1 NaN or infinite samples \\(first at 150\\)"):
        analyze(dataclasses.replace(c, **kw))


def test_repeated_positions(hard):
    """A position sensor stepping by 2 nm (eight samples on each value): the same truth."""
    c, _ = hard
    z = np.round(np.asarray(c.piezo_nominal) / 2e-9) * 2e-9
    _meets_hard_truth(c, analyze(dataclasses.replace(c, piezo_nominal=z, piezo_measured=z)))


# --- drift and fringes -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("drift", [0.5, 2.0])
def test_huge_drift(drift):
    """2 V/s: 100 nm of apparent deflection over the 1 s record, three times the contact's own travel."""
    c = static_curve(noise=NOISE, drift=drift)
    _meets_hard_truth(c, analyze(c))


@pytest.mark.parametrize("amplitude", [0.02, 0.3, 1.0])
def test_deep_fringes(amplitude):
    """Fringes 1, 15 and 50 nm deep (period 320 nm) on a 1.2 um approach and retract. Before, at 15 nm: the
    contact split on a fringe's flank, sensitivity 214 nm/V and adhesion 240 nN for 50 nm/V and 56 nN."""
    c = static_curve(noise=NOISE, fringe_amplitude=amplitude, start=-1200e-9, end=-1200e-9)
    r = analyze(c)
    assert r.sensitivity_used == pytest.approx(c.truth["sensitivity"], rel=0.005)
    assert r.adhesion_force == pytest.approx(PULL_OFF, rel=0.02)
    assert r.details["fringes"].approach.amplitude == pytest.approx(amplitude, rel=0.01)
    assert _said(r, "hid the contact") == (amplitude >= 0.3)


# --- the file's calibration ------------------------------------------------------------------------------------

def test_file_sensitivity_ten_times_too_large_is_impossible(hard):
    c, _ = hard
    r = analyze(dataclasses.replace(c, metadata={**c.metadata, "sensitivity": 10 * c.truth["sensitivity"]}))
    assert math.isnan(r.adhesion_force) and math.isnan(r.jump_in_separation)
    assert r.not_applicable["adhesion"].startswith("physically impossible")
    assert r.sensitivity_fit == pytest.approx(c.truth["sensitivity"], rel=0.01)      # the slope's, shown


def test_file_sensitivity_ten_times_too_small_is_used_and_said(hard):
    """0.1 x: a hard contact's line moving the deflection 0.1 x the position is possible (a soft layer), so the
    file's is used; the warning gives the factor, and the factor times the numbers is the truth."""
    c, _ = hard
    r = analyze(dataclasses.replace(c, metadata={**c.metadata, "sensitivity": 0.1 * c.truth["sensitivity"]}))
    w = next(w for w in r.warnings if "the compliance slope gives a calibration" in w)
    factor = float(re.search(r"calibration ([0-9.]+) x the file's", w).group(1))
    assert factor == pytest.approx(10, rel=0.01)
    assert factor * r.adhesion_force == pytest.approx(PULL_OFF, rel=0.01)


# --- a dwell, and the jump-in's size ------------------------------------------------------------------------------

def test_dwell_with_creep_between_the_runs(hard):
    """200 samples held at the turn (segment 2) while the piezo creeps 2 nm further: the runs' numbers."""
    c, ref = hard
    seg = np.asarray(c.segment)
    a, r = np.flatnonzero(seg == 0), np.flatnonzero(seg == 1)
    n, creep = 200, 2e-9
    frac = 1 - np.exp(-np.arange(1, n + 1) / (n / 4))
    z_hold = c.piezo_nominal[a[-1]] + creep * frac
    s_hold = c.deflection_signal[a[-1]] + creep * frac / c.truth["sensitivity"]
    cat = lambda x, mid: np.concatenate([np.asarray(x)[a], mid, np.asarray(x)[r]])  # noqa: E731
    dt = c.time[1] - c.time[0]
    t = np.concatenate([c.time[a], c.time[a[-1]] + dt * np.arange(1, n + 1), c.time[r] + n * dt])
    dwell = dataclasses.replace(c, time=t, piezo_nominal=cat(c.piezo_nominal, z_hold),
                                piezo_measured=cat(c.piezo_measured, z_hold),
                                deflection_signal=cat(c.deflection_signal, s_hold),
                                segment=cat(c.segment, np.full(n, 2, np.int8)))
    res = analyze(dwell)
    _meets_hard_truth(c, res)
    assert res.jump_in_separation == pytest.approx(ref.jump_in_separation, abs=0.05e-9)


def test_tiny_jump_in():
    """R 5 nm: the tip jumps in from 1.6 nm, by 1.1 nm of deflection (110 noise sigmas, 4 samples' travel): the
    truth's pull-off and jump-in."""
    c = static_curve(noise=0.01e-9, radius=5e-9)
    r = analyze(c)
    assert r.contact_kind == "hard"
    # the sampled truth: the last retract sample on the contact branch (0.25 nm steps miss the fold's last
    # 0.16 nm of deflection, 2.6 % of eq 2's largest attraction)
    sampled = c.truth["spring_constant"] * float(np.min(c.truth["deflection"][np.asarray(c.segment) == 1]))
    assert r.adhesion_force == pytest.approx(sampled, rel=0.01)
    assert r.adhesion_force == pytest.approx(forces.max_attraction_force(5e-9, HAMAKER, Z0), rel=0.03)
    j = c.truth["jump_in_index"]
    assert r.jump_in_separation == pytest.approx(c.truth["separation"][j], abs=0.3e-9)


def test_no_jump_in_on_a_stiff_lever():
    """k 50 N/m, R 5 nm: the jump and the pull-off are below the noise: both said absent, none reported."""
    c = static_curve(noise=0.01e-9, radius=5e-9, spring_constant=50.0)
    r = analyze(c)
    assert r.contact_kind == "hard"
    assert r.sensitivity_used == pytest.approx(c.truth["sensitivity"], rel=0.01)
    assert math.isnan(r.jump_in_separation) and math.isnan(r.pull_off_force)
    assert _said(r, "no significant jump into contact") and _said(r, "no pull-off found")


# --- the same through the command line, from files ------------------------------------------------------------

def test_cli_says_each_problem_in_one_line(tmp_path, hard, capsys):
    """The pathologies written as afmforce text files (the calibration a file stores: k and the rate) and
    analysed by ``afmforce analyze DIR``: the good ones in the table with their note, the bad ones one
    ``failed:`` line each, no traceback."""
    from afmforce.cli.main import main
    from afmforce.io.native.rawfile import write_raw

    c, _ = hard
    md = {"spring_constant": c.truth["spring_constant"], "sample_rate": c.metadata["sample_rate"]}

    def write(name, curve):
        write_raw(dataclasses.replace(curve, metadata=md, truth=None), tmp_path / f"{name}.txt")

    s = np.array(c.deflection_signal)
    s[c.truth["jump_in_index"] + 20] += 3.0
    write("glitch", _signal(c, s))
    write("clipped", _signal(c, np.minimum(c.deflection_signal, 0.6)))
    write("short", static_curve(noise=NOISE, turn=_jump_position(c) - 3e-9))
    write("fringes", static_curve(noise=NOISE, fringe_amplitude=0.3, start=-1200e-9, end=-1200e-9))
    s = np.array(c.deflection_signal)
    s[150] = np.nan
    write("nan", _signal(c, s))
    write("ten", _take(c, _every(c, 10)))
    code = main(["analyze", str(tmp_path), "--serial"])
    out = capsys.readouterr()
    assert code == 1 and "Traceback" not in out.err + out.out
    failed = [ln for ln in out.err.splitlines() if ln.startswith("failed:")]
    assert len(failed) == 2
    assert any("nan.txt" in ln and "non-finite" in ln for ln in failed)
    assert any("ten.txt" in ln and "holds only 10 sample(s)" in ln for ln in failed)
    said = {"glitch.txt": "single-sample glitch", "clipped.txt": "saturated samples",
            "short.txt": "no contact reached", "fringes.txt": "hid the contact"}
    text = out.out + out.err
    for name, words in said.items():
        block = text.split(f"{name}:", 1)[1].split(".txt:", 1)[0]
        assert words in block, (name, block)
    rows = {ln.split()[0]: ln.split() for ln in out.out.splitlines() if ln.split() and ln.split()[0] in said}
    for name in ("glitch.txt", "clipped.txt", "fringes.txt"):   # file, contact, k, sensitivity used [nm/V], ...
        assert rows[name][1] == "hard" and float(rows[name][3]) == pytest.approx(50.0, rel=0.005)
    assert rows["short.txt"][1] == "none"
