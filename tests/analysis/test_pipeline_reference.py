"""The pipeline's speed work changes no number (issue 35, item 2).

``pipeline_reference.json.gz`` holds the full ``analyze`` JSON (per-sample arrays included) of
34 soft curves, produced by ``make_pipeline_reference.py`` with the code of main before the
speed work (commit 8787912). Today's code must give the same keys, the same strings and every
number within 1e-9 relative (NaN where NaN).

Since stored: the calibration-mismatch warning's wording (the file's calibration became the default, its
warning now says the file's is used and names the causes as `afmforce calibrate invols` does) was
substituted in the stored strings (32 warnings of the 34 soft curves, none of which the new default
recalibrates); every number is still main's of 8787912, checked equal before the substitution. The Chiaro reader
now passes the header's tip radius (a modulus is fitted): its case is analysed without it, as stored
(``make_pipeline_reference.WITHOUT_RADIUS``).
"""

from __future__ import annotations

import copy
import gzip
import json
import math
import re
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import make_pipeline_reference as M  # noqa: E402

from afmforce.analysis.steps.calibration import SLOPE_FACTOR, SOFT_SLOPE  # noqa: E402

REFERENCE = json.loads(gzip.decompress(M.OUT.read_bytes()))
RTOL = 1e-9
#: Keys declared after the reference was made (new quantities, no number of the old ones changed): they
#: may appear in today's JSON; every key of the reference must still be there with its value.
ADDED = {"barrier_force", "barrier_jump_distance", "through_barrier",
         # the friction signature's bounds (coincident lines bound friction, never exclude it)
         "friction_offset_bound", "friction_force_bound", "viscous_friction_bound", "load_friction_bound",
         "offset_bound", "slope_difference_bound",
         # the tethers of a hard contact (analysis.tethers): empty and 0 on these soft curves
         "tethers", "tether_force",
         # their worm-like-chain fits (analysis.wlc): NaN and empty on these soft curves
         "tether_contour_length", "tether_contour_length_se", "tether_persistence_length",
         "tether_persistence_length_se", "tether_loading_rate", "tether_fits",
         # where the indentation's Poisson ratio came from (user, file, default): the ratio itself is compared
         "poisson_source",
         # the drift step's climb of its approach line (NaN unless its warning fires; the indentation then widens)
         "baseline_climb",
         # the drift lines' bound on the shift and on a hard contact's rupture (NaN on these soft curves)
         "shift_drift", "rupture_distance_drift",
         # the adhesion's dip in sigmas, its baseline model's systematic and the return to the baseline
         # (branch adhesion2; the rupture it changed is undone in _before_adhesion2)
         "adhesion_significance", "adhesion_baseline_spread", "adhesion_return_distance", "dip_sigmas",
         "dip_force", "baseline_spread", "return_distance",
         # whether the shift and a slope's InvOLS are determined (plausibility.undetermined, invols.line_notes):
         # true on these soft curves, none of which the slope calibrates
         "determined"}


def _compare(new, old, where: str, out: list[str]) -> None:
    if isinstance(old, dict):
        if not isinstance(new, dict) or (set(new) - ADDED) != set(old):
            out.append(f"{where}: keys {sorted(set(new) ^ set(old)) if isinstance(new, dict) else type(new)}")
            return
        for k in old:
            _compare(new[k], old[k], f"{where}.{k}", out)
    elif isinstance(old, list):
        if not isinstance(new, list) or len(new) != len(old):
            out.append(f"{where}: length {len(new) if isinstance(new, list) else new!r} != {len(old)}")
            return
        for i, (a, b) in enumerate(zip(new, old)):
            _compare(a, b, f"{where}[{i}]", out)
    elif isinstance(old, (int, float)) and not isinstance(old, bool) and isinstance(new, (int, float)):
        if not math.isclose(new, old, rel_tol=RTOL, abs_tol=0.0) and not (old == 0 and abs(new) < 1e-300):
            out.append(f"{where}: {new!r} != {old!r}")
    elif where.endswith(".source") and isinstance(new, str) and isinstance(old, str):
        if Path(new).name != Path(old).name:          # the checkout's folder differs (CI, worktrees)
            out.append(f"{where}: {Path(new).name!r} != {Path(old).name!r}")
    elif new != old:
        out.append(f"{where}: {str(new)[:80]!r} != {str(old)[:80]!r}")


#: Since stored (public files tried after the corpus, docs/analysis.md "Curves that never reached the
#: surface"): the adhesion's distances count from where the retract leaves its contact when that lies
#: inside the approach's contact point (``details.adhesion.detach_position`` > 0; measured from the
#: approach's contact point they came out negative on relaxing cells). Undone here before comparing (the
#: distances less ``detach_position``; the verdicts without their distances): every other number is main's.
_AT = re.compile(r" at -?[\d.e+-]+ nm from contact; last rupture at (?:-?[\d.e+-]+|x) nm"
                 r"| \(distances from where the retract leaves its contact, [^)]*\)")


#: Since stored (branch adhesion2, docs/analysis.md "The adhesion's baseline, its ruptures and a dip under the
#: threshold"): on a soft contact a return to the baseline that is no step is no rupture (the last rupture is
#: then the last step, or NaN; ``return_distance`` keeps the old number), the unbinding steps are placed where
#: the two-window jump is largest (compared with that off, in ``_results``), and the verdicts name the dip under
#: the threshold, the baseline model's systematic and a gradual return. Undone on today's result.
_ADHESION2 = re.compile(r"; the retract comes back to its baseline gradually at [^)]*\)"
                        r"|; baseline model \+-[^)]*\)|, adhesion\.nsigma")


def _before_adhesion2(result):
    """``result`` with its rupture and verdicts as before branch adhesion2 (see above)."""
    if not isinstance(result, dict) or not isinstance(result.get("details"), dict):
        return result
    result = copy.deepcopy(result)
    d = result["details"].get("adhesion")
    if not isinstance(d, dict):
        return result
    back = d.get("return_distance")
    if isinstance(back, float) and math.isfinite(back):
        d["rupture_distance"] = result["rupture_distance"] = back
    for obj, key in ((d, "verdict"), (result, "adhesion_verdict")):
        if isinstance(obj.get(key), str):
            v = _ADHESION2.sub("", obj[key]).replace("; last rupture undetermined;", "; last rupture at x nm;")
            obj[key] = re.sub(r"the deepest dip, [^,]*, is", "the deepest dip is", v)
    return result


def _before_detach(result, strip_only: bool = False):
    """``result`` as it was before the detach reference (``strip_only``: the stored one, verdicts only)."""
    if not isinstance(result, dict) or not isinstance(result.get("details"), dict):
        return result
    result = copy.deepcopy(result)
    d = result["details"].get("adhesion")
    if not isinstance(d, dict):
        return result
    ref = d.pop("detach_position", 0.0) or 0.0
    result.get("details_units", {}).get("adhesion", {}).pop("detach_position", None)
    if ref > 0 and not strip_only:
        for obj, key in ((d, "distance"), (d, "rupture_distance"), (result, "adhesion_distance"),
                         (result, "rupture_distance")):
            if isinstance(obj.get(key), float):
                obj[key] -= ref
        for step in d.get("steps") or []:
            step["distance"] -= ref
    for obj, key in ((d, "verdict"), (result, "adhesion_verdict")):
        if isinstance(obj.get(key), str):
            obj[key] = _AT.sub("", obj[key])
    return result


#: Since stored (branch corpus, public files tried): (1) a run with a time base but fewer than 32 samples in
#: contact reports its Nyquist frequency and "too few samples", where the stored verdict said "no time base";
#: (2) an Optics11 reader's interferometric deflection raises the kind step's least stiffness of a hard contact
#: to 0.9 (the kind is unchanged on these curves; its reason quotes the threshold); (3) the drift step warns when
#: its baseline line climbs by more than half the approach's rise after it (the stress-relaxation cell presses
#: from the start of its extend); (4) on a soft contact the summary's ``sensitivity_fit`` is NaN (the slope is
#: not the lever's: ``steps.calibration.soft_slope``; ``details.calibration.sensitivity_fit`` keeps the slope's
#: number and is compared) and its warning replaces the slope's factor. Undone on today's result.
_NO_TIME_BASE = "oscillation not assessed: no time base"
_SOFT_SLOPE = SOFT_SLOPE.split(":")[0]


def _before_short_runs(new, old):
    """``new`` with the stored wording of (1) and (2) where ``old`` has it: every number is compared as before."""
    if not isinstance(new, dict) or not isinstance(old, dict) or not isinstance(new.get("details"), dict):
        return new
    new = copy.deepcopy(new)
    osc_new, osc_old = new["details"].get("oscillation"), (old.get("details") or {}).get("oscillation")
    if isinstance(osc_new, dict) and isinstance(osc_old, dict):
        if osc_old.get("verdict") == _NO_TIME_BASE and "too few samples" in str(osc_new.get("verdict")):
            osc_new["verdict"] = new["oscillation_verdict"] = _NO_TIME_BASE
        for run in ("approach", "retract"):
            a, b = osc_new.get(run), osc_old.get(run)
            if isinstance(a, dict) and isinstance(b, dict) and b.get("nyquist") is None and not a.get("found"):
                a["nyquist"] = None
                short = re.compile(run + r": no peak, too few samples \(Nyquist [^)]*\)")
                osc_new["verdict"] = new["oscillation_verdict"] = short.sub(run + ": no time base", osc_new["verdict"])
    if isinstance(new.get("warnings"), list):  # (3) the drift step's warning of a baseline that climbs with the contact
        new["warnings"] = [w for w in new["warnings"] if "the baseline line fitted before contact climbs" not in w]
    if new.get("contact_kind") == "soft" and new.get("sensitivity_fit") is None:     # (4)
        new["sensitivity_fit"] = (new["details"].get("calibration") or {}).get("sensitivity_fit")
        if isinstance(new.get("warnings"), list):
            new["warnings"] = [w for w in new["warnings"] if not w.startswith(_SOFT_SLOPE)]
            was = [i for i, w in enumerate(old.get("warnings") or []) if w.startswith(SLOPE_FACTOR)]
            for i in was if not any(w.startswith(SLOPE_FACTOR) for w in new["warnings"]) else ():
                new["warnings"].insert(i, old["warnings"][i])
    for obj, key in ((new, "contact_kind_reason"), (new["details"].get("kind"), "reason")):
        if isinstance(obj, dict) and isinstance(obj.get(key), str):
            obj[key] = obj[key].replace("in contact (< 0.9)", "in contact (< 0.7)")
    return new


def _bug(result) -> bool:
    """The reference holds an exception that is no AfmforceError (e.g. a ZeroDivisionError)."""
    import afmforce.errors as E

    if "error" not in result:
        return False
    cls = getattr(E, result["error"].split(":", 1)[0], None)
    return not (isinstance(cls, type) and issubclass(cls, E.AfmforceError))


def test_reference_covers_the_cases():
    assert len(REFERENCE) == 34
    assert sum("error" not in v for v in REFERENCE.values()) >= 30
    # two 300-point thinnings of the JPK map raised ZeroDivisionError on main (8787912): not compared
    assert sum(_bug(v) for v in REFERENCE.values()) == 2


#: Since stored (branch zerostep, docs/analysis.md "A level step in the approach's free baseline"): the contact
#: step cuts an approach's zero-force region after a level step of its baseline. Of the stored cases only the AFM
#: Workshop 2018 export has one (+0.012 V within 2 samples, 39 samples in): compared with the scan off
#: (``today``), and ``test_only_the_workshop_baseline_steps`` checks that it is the only one with the scan on.
STEPPED = {"afmformats_afm-workshop-fd_single_2018-08-01.csv#0"}


def _results(scan: bool) -> dict:
    import warnings
    with warnings.catch_warnings(), pytest.MonkeyPatch.context() as mp:
        warnings.simplefilter("ignore")
        mp.setattr("afmforce.analysis.unbinding._locate_steps", lambda u, x, idx, steps, w: steps)
        # branch contactmech: the modulus fit's Gauss-Newton polish runs to convergence with step halving (was
        # two unguarded steps: stopped short of the least squares, e.g. the JPK map curve 1 6679 vs nanite's 6710
        # Pa, tests/contact/test_nanite_realfits.py); two steps, no halving, is the polish as stored
        mp.setattr("afmforce.contact.fit._GN_MAX_STEPS", 2)
        mp.setattr("afmforce.contact.fit._GN_HALVINGS", 1)
        # ... and said nothing when it stopped short (since 2026-11-29: a warning and an open interval)
        import afmforce.contact.fit as fit_module
        polish = fit_module._linear_fit
        mp.setattr(fit_module, "_linear_fit", lambda *a: (polish(*a)[0], True))
        if not scan:
            mp.setattr("afmforce.analysis.steps.contact.without_baseline_step", lambda s, run, unit: (run, None))
        return dict(M.results())


@pytest.fixture(scope="module")
def today():
    return _results(scan=False)


def test_only_the_workshop_baseline_steps():
    stepped = {key for key, r in _results(scan=True).items()
               if any("free baseline steps by" in w for w in r.get("warnings") or [])}
    assert stepped == STEPPED


def test_every_number_unchanged(today):
    assert set(today) == set(REFERENCE)
    diffs: list[str] = []
    for key, old in REFERENCE.items():
        if _bug(old):  # main raised a bare Python error here (a bug, not a refusal): fixing it is no regression
            continue
        _compare(_before_detach(_before_adhesion2(_before_short_runs(today[key], old))),
                 _before_detach(old, strip_only=True), key, diffs)
    assert not diffs, f"{len(diffs)} differences, first: " + "; ".join(diffs[:8])
