"""The registry of analysis steps (issue 31, items 3 and 7): each step is declared once, by its record
in its own module; the pipeline, the result's fields and units, the printed summary, the batch
summary's columns, the map quantities, ``afmforce analyze --steps``/``--option`` and the web's step
list come from the records. The last test writes a new step as ONE module (in a temporary folder,
registered with the public ``register_step``) and finds it on every face without another edit."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
from dataclasses import fields

import pytest

from afmforce.analysis import registry as R
from afmforce.analysis.maps import MAP_QUANTITIES
from afmforce.analysis.options import OPTIONS, VdwOptions
from afmforce.analysis.pipeline import STEPS, resolve_steps
from afmforce.analysis.result import SUMMARY_FIELDS, AnalysisResult
from afmforce.sweep.summary import SUMMARY_COLUMNS, SUMMARY_UNITS

#: The summary table's float columns before the registry (sweep/summary._FLOATS, hand-kept): the
#: registry's ``column`` fields must give the same columns.
OLD_COLUMNS = {
    "sensitivity_used", "sensitivity", "sensitivity_fit", "spring_constant", "adhesion_force", "adhesion_distance",
    "adhesion_noise", "adhesion_significance", "adhesion_baseline_spread", "adhesion_return_distance", "rupture_distance", "unbinding_steps", "tethers", "tether_force", "tether_contour_length", "tether_contour_length_se",
    "tether_persistence_length", "tether_persistence_length_se", "tether_loading_rate", "indentation", "force_gradient", "resonance_frequency",
    "shift", "contact_separation", "jump_in_separation", "jump_in_force", "jump_in_deflection", "pull_off_force",
    "pull_off_position", "jump_out_distance", "surface_energy", "radius", "hamaker_radius", "hamaker_radius_se",
    "hamaker", "hamaker_se", "oscillation_frequency", "velocity", "inertia_parameter", "youngs_modulus",
    "youngs_modulus_se", "youngs_modulus_low", "youngs_modulus_high", "contact_point", "work_of_adhesion",
    "work_of_adhesion_se", "position_x", "position_y", "drag_offset", "lever_drag", "surface_potential",
    "surface_potential_se", "debye_length", "debye_length_se", "dlvo_hamaker", "dlvo_hamaker_se",
    "barrier_force", "barrier_jump_distance",
    "friction_offset_bound", "friction_force_bound", "viscous_friction_bound", "load_friction_bound",
    "shift_drift", "rupture_distance_drift"}


def test_every_step_is_declared_once_with_its_options_and_fields():
    assert list(STEPS) == list(R.order()) and len(STEPS) == 19
    seen = set()
    for name, step in STEPS.items():
        assert step.identifier == name and step.options is OPTIONS[name] and step.options.step == name
        for req in (*step.requires, *step.after):  # every step runs after what it needs or follows
            assert list(STEPS).index(req) < list(STEPS).index(name), (name, req)
        for f in step.fields:
            assert f.name not in seen, f.name
            seen.add(f.name)
            if f.summary or f.column:  # a number shown or tabulated states its unit
                assert f.unit is not None and isinstance(f.default, (int, float)), f.name
            if f.summary:
                assert f.label, f.name
        if step.fields:
            assert step.collect is not None, name


def test_units_summary_columns_and_maps_come_from_the_records():
    declared = R.result_fields()
    numeric = {n for n, f in declared.items() if f.unit is not None}
    assert set(AnalysisResult.UNITS) == numeric | set(AnalysisResult.ARRAYS) - {"segment"}
    assert {n: AnalysisResult.UNITS[n] for n in numeric} == {n: declared[n].unit for n in numeric}
    assert [a for a, _, _ in SUMMARY_FIELDS] == [n for n, f in declared.items() if f.summary]
    floats = {c for c, kind in SUMMARY_COLUMNS.items() if kind == "float"}
    assert floats - {"map_width", "map_height"} - {c for c in floats if c.startswith("oscillation_a")
                                                   or c.startswith("oscillation_r")} == OLD_COLUMNS
    assert all(SUMMARY_UNITS[n] == declared[n].unit for n in OLD_COLUMNS if n in declared)
    for name, label, unit in SUMMARY_FIELDS:
        if name in SUMMARY_COLUMNS:
            assert MAP_QUANTITIES[name].column == name and MAP_QUANTITIES[name].unit == unit
        else:   # a map is drawn from the summary table: no column, no map (before: an empty choice)
            assert name not in MAP_QUANTITIES
    # the named map quantities point to declared columns: the summary table's or the fast map's
    from afmforce.sweep.map_fast import PIXEL_COLUMNS

    assert all(q.column in SUMMARY_COLUMNS or q.column in PIXEL_COLUMNS for q in MAP_QUANTITIES.values())


def test_the_result_reads_its_fields_from_the_values_and_refuses_undeclared_ones():
    res = AnalysisResult("x", ("force",), "V", "nominal", spring_constant=0.2, calibration_source="fit",
                         sensitivity=50e-9, sensitivity_fit=60e-9)
    assert res.spring_constant == 0.2 and math.isnan(res.hamaker) and res.verdict == "" and res.unbinding_steps == 0
    assert res.sensitivity_used == 60e-9                     # computed from the fields it depends on
    d = res.to_dict()
    assert set(d) >= set(R.result_fields()) and d["sensitivity_used"] == 60e-9 and d["hamaker"] is None
    with pytest.raises(TypeError, match="hamaker_typo"):
        AnalysisResult("x", (), "V", "nominal", hamaker_typo=1.0)
    with pytest.raises(AttributeError):
        res.not_a_field
    import pickle

    again = pickle.loads(pickle.dumps(res))
    assert again.spring_constant == 0.2 and again.values == res.values


def test_registration_refuses_what_would_break_the_pipeline():
    step = STEPS["vdw"]
    with pytest.raises(TypeError, match="registered already"):
        R.register_step(step)
    from dataclasses import replace

    with pytest.raises(TypeError, match="unregistered"):
        R.register_step(replace(step, identifier="vdw2", requires=("nope",)))
    with pytest.raises(TypeError, match="options record"):
        R.register_step(replace(step, identifier="vdw2"))   # VdwOptions is the vdw step's
    assert VdwOptions.step == "vdw" and "vdw2" not in STEPS


def test_asking_for_a_step_adds_its_requirements_in_the_registry_order():
    assert resolve_steps(["diagnosis"]) == [s for s in STEPS if s in {
        "contact", "drift", "compliance", "calibration", "kind", "zero", "force", "jumps", "adhesion", "vdw",
        "friction", "diagnosis"}]


_TOY_STEP = '''
"""A step written by a test, in its own module only: the largest force of the approach, scaled."""
from dataclasses import dataclass

import numpy as np

from afmforce.analysis.options import StepOptions, option_field
from afmforce.analysis.registry import AnalysisStep, ResultField, register_step


@dataclass(frozen=True)
class PeakOptions(StepOptions):
    step = "zz_peak"
    scale: float = option_field(1.0, "dimensionless", "", "factor on the peak force", lo=0.0, hi=10.0,
                                lo_open=True)


@dataclass(frozen=True)
class PeakResult:
    peak_force: float


def peak(st, o):
    return st.update("zz_peak", PeakResult(float(np.max(st.force[st.approach.index])) * o.scale))


register_step(AnalysisStep(
    "zz_peak", "Largest force on the approach (a test's step)", peak, PeakOptions, requires=("force",),
    channels=("force",), reference="a test",
    fields=(ResultField("zz_peak_force", "N", "peak force of the approach", summary=True, column=True),),
    collect=lambda st: {"zz_peak_force": st.details["zz_peak"].peak_force}))
'''

_TOY_RUN = '''
import contextlib, io, json, math
import numpy as np
import zz_peak_step  # the new step's module: its only registration
from afmforce.analysis.maps import MAP_QUANTITIES
from afmforce.analysis.pipeline import STEPS, analyze
from afmforce.analysis.options import OPTIONS
from afmforce.analysis.options_text import parse_option
from afmforce.analysis.result import AnalysisResult, SUMMARY_FIELDS
from afmforce.analysis.synthetic import static_curve
from afmforce.sweep.summary import SUMMARY_COLUMNS, SUMMARY_UNITS, summary_row
from afmforce.cli.main import main

curve = static_curve(noise=0.05e-9, drift=0.01, seed=11)
res = analyze(curve, steps=["zz_peak"], options=[OPTIONS["zz_peak"](scale=2.0)])
row = summary_row(res, curve, file="c", index=0, name="c")
approach = res.force[res.segment == 0]
buf = io.StringIO()
with contextlib.redirect_stdout(buf):
    try:
        main(["analyze", "--help"])
    except SystemExit:
        pass
help_text = buf.getvalue()
out = io.StringIO()
with contextlib.redirect_stdout(out):
    code = main(["analyze", "--example", "asylum-air", "--steps", "zz_peak", "--option", "zz_peak.scale=3",
                 "--json"])
cli = json.loads(out.getvalue())
from fastapi.testclient import TestClient
from afmforce.web import Settings, create_app
import sys
from pathlib import Path
with TestClient(create_app(Settings(data=Path(sys.argv[1]), spare_job=False)), base_url="http://127.0.0.1") as client:
    schema = client.get("/api/schema").json()
    web = client.post("/api/analyze", data={"example": "asylum-air", "step": "zz_peak",
                                            "option": "zz_peak.scale=3"}).json()
print(json.dumps({
    "steps": list(STEPS), "steps_run": list(res.steps_run), "value": res.zz_peak_force,
    "independent": float(np.max(approach)) * 2.0, "json": json.loads(res.to_json())["zz_peak_force"],
    "unit": AnalysisResult.UNITS["zz_peak_force"], "json_unit": json.loads(res.to_json())["units"]["zz_peak_force"],
    "summary": [r for r in SUMMARY_FIELDS if r[0] == "zz_peak_force"], "row": row["zz_peak_force"],
    "column": SUMMARY_COLUMNS.get("zz_peak_force"), "column_unit": SUMMARY_UNITS.get("zz_peak_force"),
    "map": MAP_QUANTITIES["zz_peak_force"].unit, "option": list(parse_option("zz_peak.scale=2.5")),
    "help": "zz_peak" in " ".join(help_text.split()), "cli_code": code,
    "cli": [[r.get("steps_run"), r.get("zz_peak_force"), r.get("spring_constant")] for r in cli["results"].values()],
    "web_steps": [s["identifier"] for s in schema["steps"]], "web_options": [o["name"] for o in
                                                                            schema["analysis"]["zz_peak"]],
    "web": [[r.get("steps_run"), r.get("zz_peak_force"), r.get("spring_constant")] for r in web["results"].values()],
}))
'''


def test_a_new_step_needs_its_own_module_only(tmp_path):
    """Write a step as one module outside the package, import it, and find it everywhere."""
    (tmp_path / "zz_peak_step.py").write_text(textwrap.dedent(_TOY_STEP))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", _TOY_RUN, str(tmp_path / "web")], capture_output=True, text=True,
                         env=env, cwd=tmp_path, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["steps"][-1] == "zz_peak" and "zz_peak" not in STEPS          # only in that process
    assert got["steps_run"] == ["contact", "drift", "compliance", "calibration", "force", "zz_peak"]
    assert got["value"] == pytest.approx(got["independent"], rel=1e-12) and got["value"] > 0
    assert got["json"] == pytest.approx(got["value"], rel=1e-12)
    assert got["unit"] == got["json_unit"] == got["column_unit"] == got["map"] == "N"
    assert got["summary"] == [["zz_peak_force", "peak force of the approach", "N"]]
    assert got["row"] == pytest.approx(got["value"], rel=1e-12) and got["column"] == "float"
    assert got["option"] == ["zz_peak", "scale", 2.5]
    assert got["help"] and got["cli_code"] == 0
    assert got["web_steps"] == got["steps"] and got["web_options"] == ["scale"]
    for face in ("cli", "web"):   # the same file, the same step and option, by both faces
        (steps_run, value, k), = got[face]
        assert steps_run == got["steps_run"] and value > 0
    assert got["cli"] == got["web"]
    # the force behind it: 3 x the approach's largest force, from the file's own spring constant
    assert got["cli"][0][2] > 0


def test_the_web_checks_the_steps_it_is_sent_against_the_registry():
    pytest.importorskip("fastapi")
    from afmforce.web.analysis import parse_steps
    from afmforce.web.schema import analysis_steps
    from afmforce.web.validate import FieldError

    assert [s["identifier"] for s in analysis_steps()] == list(STEPS)
    assert parse_steps([]) is None and parse_steps(["vdw", " jumps "]) == ("vdw", "jumps")
    with pytest.raises(FieldError, match="unknown analysis step 'vwd'; choose from smooth, contact") as err:
        parse_steps(["vdw", "vwd"])
    assert err.value.field == "step[1]"


_SHIPPED_STEP = '''
"""The ``zz_valley`` step (a test's): the deepest force of the retract, scaled."""
from dataclasses import dataclass

import numpy as np

from ..options import StepOptions, option_field
from ..registry import AnalysisStep, ResultField


@dataclass(frozen=True)
class ValleyOptions(StepOptions):
    step = "zz_valley"
    scale: float = option_field(1.0, "dimensionless", "", "factor on the valley force", lo=0.0, hi=10.0,
                                lo_open=True)


@dataclass(frozen=True)
class ValleyResult:
    valley_force: float


def valley(st, o):
    return st.update("zz_valley", ValleyResult(float(np.min(st.force[st.retract.index])) * o.scale))


VALLEY = AnalysisStep(
    "zz_valley", "Deepest force of the retract (a test's step)", valley, ValleyOptions, requires=("force",),
    channels=("force",), reference="a test",
    fields=(ResultField("zz_valley_force", "N", "valley force of the retract", summary=True, column=True),),
    collect=lambda st: {"zz_valley_force": st.details["zz_valley"].valley_force})
'''

_SHIPPED_RUN = '''
import contextlib, io, json
import numpy as np
from afmforce.analysis.options_text import options_markdown, parse_option
option = parse_option("zz_valley.scale=2.5")     # first: the registry is not loaded yet
from afmforce.analysis.maps import MAP_QUANTITIES
from afmforce.analysis.pipeline import STEPS, analyze
from afmforce.analysis.options import OPTIONS
from afmforce.analysis.result import AnalysisResult, SUMMARY_FIELDS
from afmforce.analysis.synthetic import static_curve
from afmforce.sweep.summary import SUMMARY_COLUMNS, summary_row
from afmforce.web.schema import analysis_options, analysis_steps
from afmforce.cli.main import main

curve = static_curve(noise=0.05e-9, drift=0.01, seed=11)
res = analyze(curve, steps=["zz_valley"], options=[OPTIONS["zz_valley"](scale=2.0)])
buf = io.StringIO()
with contextlib.redirect_stdout(buf):
    try:
        main(["analyze", "--help"])
    except SystemExit:
        pass
print(json.dumps({
    "option": list(option), "steps": list(STEPS), "steps_run": list(res.steps_run), "value": res.zz_valley_force,
    "independent": float(np.min(res.force[res.segment == 1])) * 2.0,
    "json": json.loads(res.to_json())["zz_valley_force"], "unit": AnalysisResult.UNITS["zz_valley_force"],
    "summary": [r for r in SUMMARY_FIELDS if r[0] == "zz_valley_force"],
    "row": summary_row(res, curve, file="c", index=0, name="c")["zz_valley_force"],
    "column": SUMMARY_COLUMNS.get("zz_valley_force"), "map": MAP_QUANTITIES["zz_valley_force"].unit,
    "help": " ".join(buf.getvalue().split()).count("zz_valley"), "docs": "`zz_valley.scale`" in options_markdown(),
    "web_steps": [s["identifier"] for s in analysis_steps()], "web_options": list(analysis_options()["zz_valley"]
                                                                                   [0].values())[:1],
}))
'''


def test_a_new_step_shipped_in_the_package_is_one_module_in_steps(tmp_path):
    """Copy the package, write one module into analysis/steps/ (its options record, function and record;
    no list edited, no registration call), and find the step on every face. The compiled kernels run as
    plain Python (NUMBA_DISABLE_JIT: the copy would compile them again)."""
    import shutil
    from pathlib import Path

    import afmforce

    root = tmp_path / "src"
    shutil.copytree(Path(afmforce.__file__).parent, root / "afmforce",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    (root / "afmforce" / "analysis" / "steps" / "zz_valley.py").write_text(textwrap.dedent(_SHIPPED_STEP))
    env = {**os.environ, "PYTHONPATH": str(root), "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run([sys.executable, "-c", _SHIPPED_RUN], capture_output=True, text=True, env=env,
                         cwd=tmp_path, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["option"] == ["zz_valley", "scale", 2.5]
    assert got["steps"] == [*STEPS, "zz_valley"]                       # after the built-ins, in their order
    assert got["steps_run"] == ["contact", "drift", "compliance", "calibration", "force", "zz_valley"]
    assert got["value"] == pytest.approx(got["independent"], rel=1e-12) and got["value"] < 0
    assert got["json"] == pytest.approx(got["value"], rel=1e-12) and got["row"] == pytest.approx(got["value"])
    assert got["unit"] == got["map"] == "N" and got["column"] == "float"
    assert got["summary"] == [["zz_valley_force", "valley force of the retract", "N"]]
    assert got["help"] >= 2 and got["docs"]                            # --steps and --option help; docs table
    assert got["web_steps"] == got["steps"] and got["web_options"] == ["scale"]


def test_a_step_runs_after_the_steps_it_follows_and_checks_its_channels():
    """``after`` moves a step behind one registered later; ``channels`` are checked before it runs."""
    from dataclasses import dataclass, replace

    from afmforce.analysis.options import StepOptions
    from afmforce.analysis.state import prepare
    from afmforce.analysis.synthetic import static_curve
    from afmforce.errors import AnalysisError

    @dataclass(frozen=True)
    class FirstOptions(StepOptions):
        step = "zz_first"

    @dataclass(frozen=True)
    class SecondOptions(StepOptions):
        step = "zz_second"

    def note(st, o):
        return st.update(o.step, {"seen": sorted(k for k in st.details if k.startswith("zz_"))})

    first = R.AnalysisStep("zz_first", "first", note, FirstOptions, requires=("force",), after=("zz_second",))
    second = R.AnalysisStep("zz_second", "second", note, SecondOptions, requires=("zero",))
    try:
        R.register_step(first)
        R.register_step(second)
        assert list(STEPS)[-2:] == ["zz_second", "zz_first"]          # registered first, runs second
        from afmforce.analysis.pipeline import analyze

        res = analyze(static_curve(noise=0.05e-9, drift=0.01, seed=11), steps=["zz_first", "zz_second"])
        assert res.steps_run[-2:] == ("zz_second", "zz_first") and res.details["zz_first"]["seen"] == ["zz_second"]
    finally:
        for name in ("zz_first", "zz_second"):
            if name in STEPS:
                R.unregister_step(name)
            OPTIONS.pop(name, None)
    assert "zz_first" not in STEPS and "zz_first" not in OPTIONS
    st = prepare(static_curve(noise=0.05e-9, drift=0.01, seed=11))
    with pytest.raises(AnalysisError, match="step 'jumps' needs separation"):
        STEPS["jumps"].run(st, STEPS["jumps"].options())
    R.register_step(replace(first, requires=("force",)))
    try:
        with pytest.raises(TypeError, match="cycle"):
            R.register_step(replace(second, after=("zz_first",)))    # each after the other: refused
        assert list(STEPS)[-1] == "zz_first" and "zz_second" not in STEPS
    finally:
        R.unregister_step("zz_first")
        OPTIONS.pop("zz_first", None)
        OPTIONS.pop("zz_second", None)
    assert list(STEPS)[-1] == "liquid"
