"""The registry of surface force laws (issue 31, item 2): every law is found from its own module,
gets its slots from the registry, and reaches the configuration, the compiled vector field, the
non-compiled reference, the static solve, ``afmforce simulate`` and the fit from its record alone.
The last test adds a law to a copy of the package by writing one module, and checks that it
works everywhere without another edit."""

import math
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from afmforce import forces as F
from afmforce import surface_laws as L
from afmforce._fields import QUANTITIES
from afmforce.dynamics import SimulationConfig
from afmforce.dynamics import models as M
from afmforce.dynamics._params import parameter_vector
from afmforce.dynamics.config import FLAT
from afmforce.dynamics.static import surface_static_force

SRC = Path(L.__file__).parent
NAMES = list(L.COMPILED)                # the laws with kernels and slots of their own
MODEL_LAWS = [n for n, law in L.LAWS.items() if not law.compiled]   # eq 2, the double layer


def test_every_module_of_the_package_is_one_registered_law_and_slots_do_not_overlap():
    modules = sorted(p.stem for p in SRC.glob("*.py") if not p.stem.startswith("_"))
    assert modules == sorted(L.LAWS) and {"hydration", "steric", "capillary"} <= set(L.COMPILED)
    assert MODEL_LAWS == ["double_layer", "van_der_waals"] and list(L.LAWS) == MODEL_LAWS + NAMES
    used = [0]                          # the block's "any law on"
    for name, law in L.COMPILED.items():
        o = L.SLOTS[name]
        used += list(range(o, o + 1 + law.n_slots))
    assert sorted(used) == list(range(L.N_SLOTS)) and M.P_SIZE == M.P_LAWS + L.N_SLOTS
    assert M.P_LAWS == M.LEVER_H + 1


@pytest.mark.parametrize("name", NAMES)
def test_record_parameters_are_declared_quantities_and_off_by_default(name):
    law = L.law(name)
    for p in law.parameters:
        spec = QUANTITIES[p.name]
        assert spec.contains(p.default), p.name
        assert spec.contains(law.example.get(p.name, p.default)), p.name
    defaults = {p.name: p.default for p in law.parameters}
    assert not law.active(defaults) and law.active({**defaults, **law.example})
    assert len(law.pack(1e-7, {**defaults, **law.example})) == law.n_slots
    assert law.reference and law.validity and law.title
    assert L.active_laws({}) == ()


@pytest.mark.parametrize("name", NAMES)
def test_parameters_reach_config_cli_and_fit_from_the_record(name):
    from afmforce.cli.main import build_parser
    from afmforce.cli.simulate import config_from_args
    from afmforce.fit.params import PARAMETERS, check_free

    law = L.law(name)
    cfg = SimulationConfig(**law.example)
    assert cfg.surface.laws == (name,)
    assert SimulationConfig.from_dict(cfg.to_dict()) == cfg
    argv = ["simulate"]
    for p in law.parameters:
        assert FLAT[p.name].part == "surface" and FLAT[p.name].spec is QUANTITIES[p.name]
        value = law.example.get(p.name, p.default)
        argv += ["--" + p.name.replace("_", "-"), repr(value)]
    args = build_parser("simulate").parse_args(argv)
    got = config_from_args(args).surface
    assert {p.name: getattr(got, p.name) for p in law.parameters} == pytest.approx(
        {p.name: law.example.get(p.name, p.default) for p in law.parameters})
    fitted = [p for p in law.parameters if p.fit is not None]
    assert fitted, f"{name}: no parameter the fit can free"
    for p in fitted:
        fp, spec = PARAMETERS[p.name], QUANTITIES[p.name]
        assert fp.lower == spec.lo and fp.unit == spec.unit and fp.upper <= spec.hi
        assert check_free([p.name], "spring") == (p.name,)
    # the web's simulate form (generated from the configuration's fields)
    from afmforce.web.schema import simulation_fields
    web = {d["name"]: d for d in simulation_fields()}
    for p in law.parameters:
        assert web[p.name]["part"] == "surface" and web[p.name]["range"] == QUANTITIES[p.name].range_text()
    # out of range: refused on construction
    for p in law.parameters:
        spec = QUANTITIES[p.name]
        if spec.hi is not None:
            with pytest.raises(Exception, match=p.name):
                SimulationConfig(**{p.name: spec.hi * 10 + 1.0})


def _on(name):
    law = L.law(name)
    return {**{p.name: p.default for p in law.parameters}, **law.example}


@pytest.mark.parametrize("name", NAMES)
def test_compiled_force_and_jacobian_are_the_records_law(name):
    law = L.law(name)
    cfg = SimulationConfig(model="spring", spring_constant=0.5, mass=1e-11, radius=20e-9,
                           geometry="sphere-flat", hamaker=1e-20, viscosity=0.0, **law.example)
    s, p = cfg.surface, parameter_vector(cfg)
    assert p[M.P_LAWS + L.SLOTS[name]] == 1.0 == p[M.P_LAWS]
    for h in (0.6e-9, 1.0e-9, 2.3e-9, 4e-9, 15e-9):
        y, out = np.array([h, -1e-6]), np.empty(2)
        assert M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, y, out)
        fl, dfl = law.force(h, s.radius_eff, _on(name))
        want = float(F.vdw_force(h, 2 * s.radius, s.hamaker, s.z0)) + float(fl)
        assert out[1] == pytest.approx((-0.5 * h + want) / 1e-11, rel=1e-11, abs=1e-3)
        J = np.empty((2, 2))
        assert M.jac(M.MODEL_SPRING, p, 0.0, 0.0, y, J)
        dvdw = float(F.vdw_force_gradient(h, 2 * s.radius, s.hamaker, s.z0))
        assert J[1, 0] == pytest.approx((-0.5 + dvdw + float(dfl)) / 1e-11, rel=1e-10)
        # the record's derivative is the derivative of its force (central differences)
        d = 1e-6 * h
        num = (float(law.force(h + d, s.radius_eff, _on(name))[0])
               - float(law.force(h - d, s.radius_eff, _on(name))[0])) / (2 * d)
        assert float(dfl) == pytest.approx(num, rel=1e-6, abs=1e-9 * abs(float(fl)) / h)
        # the static solve sees the same force
        fs, dfs = surface_static_force(s, h)
        assert float(fs) == pytest.approx(want, rel=1e-12)


def test_laws_off_leave_the_papers_parameter_vector_as_it_was():
    p = parameter_vector(SimulationConfig())
    assert p.size == M.P_SIZE and np.all(p[M.P_LAWS:] == 0.0)
    assert SimulationConfig().surface.eq2_only


_PROBE_LAW = '''
"""A law written by a test: F = 2 pi R_eff P0 lambda (lambda / (h + lambda))^2 (its own module only)."""
import math

import numpy as np

from ._record import LawParameter, SurfaceLaw


def _force(h, r, v):
    h = np.asarray(h, dtype=float)
    a, lam = 2 * math.pi * r * v["hydration_pressure"] * v["hydration_length"], v["hydration_length"]
    return a * (lam / (h + lam)) ** 2, -2 * a * lam**2 / (h + lam) ** 3


def _kernel(h, p, o):
    u = p[o + 1] / (h + p[o + 1])
    return p[o] * u * u, -2.0 * p[o] * u * u / (h + p[o + 1])


LAW = SurfaceLaw(
    name="zz_probe", title="test law",
    parameters=(LawParameter("hydration_pressure", 0.0, fit=(1e8, 0.02, 1e4)),
                LawParameter("hydration_length", 0.3e-9, fit=(3e-10, 0.01, 1e-13))),
    force=_force, active=lambda v: v["hydration_pressure"] > 0.0,
    pack=lambda r, v: (2 * math.pi * r * v["hydration_pressure"] * v["hydration_length"],
                       v["hydration_length"]),
    kernel=_kernel, n_slots=2, reach=lambda v: 100 * v["hydration_length"],
    reference="a test", validity="a test", example={"hydration_pressure": 1e7})
'''

_PROBE_RUN = '''
import json, numpy as np
from afmforce import surface_laws as L
from afmforce.dynamics import SimulationConfig, models as M
from afmforce.dynamics._params import parameter_vector
from afmforce.dynamics.static import surface_static_force
from afmforce.cli.main import build_parser
from afmforce.cli.simulate import config_from_args
from afmforce.fit.params import PARAMETERS
args = build_parser("simulate").parse_args(["simulate", "--model", "spring", "--radius", "20nm",
                                           "--hydration-pressure", "1e7Pa"])
cfg = config_from_args(args)
p = parameter_vector(cfg)
h = np.array([0.8e-9, 1.5e-9, 3e-9])
Y = np.column_stack([h, np.zeros(3)])
fz = M.observe_array(M.MODEL_SPRING, p, np.zeros(3), np.zeros(3), Y)[:, M.O_FZ]
print(json.dumps({"laws": list(L.COMPILED), "active": list(cfg.surface.laws), "fz": fz.tolist(),
                  "static": surface_static_force(cfg.surface, h)[0].tolist(),
                  "fit": "hydration_pressure" in PARAMETERS, "slots": L.SLOTS}))
'''


@pytest.mark.slow
def test_a_new_law_needs_its_own_module_only(tmp_path):
    """Copy the package, write one module into surface_laws/, and run it from the command line's
    flags through the compiled vector field: no other file is edited."""
    import json

    import afmforce

    root = tmp_path / "src"
    shutil.copytree(Path(afmforce.__file__).parent, root / "afmforce",
                    ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    (root / "afmforce" / "surface_laws" / "zz_probe.py").write_text(textwrap.dedent(_PROBE_LAW))
    env = {**os.environ, "PYTHONPATH": str(root), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    out = subprocess.run([sys.executable, "-c", _PROBE_RUN], capture_output=True, text=True,
                         env=env, cwd=tmp_path, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["laws"] == sorted(got["laws"]) and "zz_probe" in got["laws"]
    assert got["active"] == ["hydration", "zz_probe"] and got["fit"]
    assert got["slots"]["zz_probe"] == L.N_SLOTS            # after the three laws (sorted names)
    h = np.array([0.8e-9, 1.5e-9, 3e-9])
    r, lam, p0 = 20e-9, 0.3e-9, 1e7
    a = 2 * math.pi * (r / 2) * p0 * lam                            # sphere-sphere: R_eff = R/2
    cfg = SimulationConfig(model="spring", radius=r, hydration_pressure=p0)
    base = np.asarray(surface_static_force(cfg.surface, h)[0])       # eq 2 + hydration, here
    want = base + a * (lam / (h + lam)) ** 2                          # + the new law
    np.testing.assert_allclose(got["fz"], want, rtol=1e-12)
    np.testing.assert_allclose(got["static"], want, rtol=1e-12)


# --- the laws the model computes itself: eq 2 and the double layer (declared by records too) ---
def test_model_laws_declare_the_configurations_fields():
    """The configuration's eq-2 and double-layer fields take default and domain from the records;
    the double layer's choice is the record's switch (Python, the command line, the web form)."""
    import dataclasses

    from afmforce.cli.main import build_parser
    from afmforce.dynamics.parts import Surface
    from afmforce.web.schema import simulation_fields

    fields = {f.name: f for f in dataclasses.fields(Surface)}
    web = {d["name"]: d for d in simulation_fields()}
    parser = build_parser("simulate")._subparsers._group_actions[0].choices["simulate"]
    flags = {a.dest: a for a in parser._actions}
    for name in MODEL_LAWS:
        law = L.law(name)
        for p in law.parameters:
            f = fields[p.name]
            assert f.default == p.default and f.metadata["domain"] == p.domain, p.name
            assert f.metadata["unit"] == QUANTITIES[p.name].unit and FLAT[p.name].part == "surface"
            assert flags[p.name].option_strings == ["--" + p.name.replace("_", "-")]
            assert web[p.name]["range"] == QUANTITIES[p.name].range_text()
            assert p.name not in L.PARAMETERS               # not a generated (compiled-law) field
        assert law.reference and law.validity and law.title and law.n_slots == 0 and law.pack is None
    sw = L.law("double_layer").switch
    assert tuple(fields[sw.name].metadata["choices"]) == tuple(sw.choices) == tuple(F.DOUBLE_LAYERS)
    assert fields[sw.name].default == sw.default == sw.off == "none"
    assert tuple(flags[sw.name].choices) == tuple(sw.choices)
    assert not SimulationConfig().surface.liquid                  # off at the defaults


def test_model_laws_fit_parameters_come_from_the_records():
    from afmforce.fit.params import LAW_PARAMETERS, PARAMETERS

    for name in MODEL_LAWS:
        for p in L.law(name).parameters:
            if p.fit is None:
                assert p.name not in PARAMETERS
                continue
            fp, spec = PARAMETERS[p.name], QUANTITIES[p.name]
            assert (fp.scale, fp.rel_step, fp.abs_step) == p.fit and fp.unit == spec.unit
            lo, hi = p.fit_window or (spec.lo, spec.hi)
            assert (fp.lower, fp.upper) == (lo, hi) and name in fp.meaning
            assert p.name not in LAW_PARAMETERS
    assert set(PARAMETERS) >= {"hamaker", "z0", "surface_potential", "debye_length"}


@pytest.mark.parametrize("name", ["van_der_waals", "double_layer"])
def test_model_laws_force_is_the_models(name):
    """The record's closed form is what the model computes: the static solve (numpy) and the
    compiled vector field, on a colloid probe (R_eff = R) with the law's example values."""
    law = L.law(name)
    values = {**{p.name: p.default for p in law.parameters}, **law.example}
    vdw_off = {} if name == "van_der_waals" else {"hamaker": 1e-22}
    cfg = SimulationConfig(model="spring", spring_constant=0.5, mass=1e-11, radius=1e-6, geometry="sphere-flat",
                           viscosity=0.0, **{**law.example, **vdw_off})
    s, p = cfg.surface, parameter_vector(cfg)
    assert s.radius_eff == pytest.approx(1e-6, rel=1e-15)
    for h in (0.8e-9, 3e-9, 12e-9):
        fl, dfl = law.force(h, s.radius_eff, values)
        other = 0.0 if name == "van_der_waals" else float(F.vdw_force(h, 2e-6, 1e-22, s.z0))
        fs, dfs = surface_static_force(s, h)
        assert float(fs) == pytest.approx(float(fl) + other, rel=1e-12)
        y, out = np.array([h, -1e-6]), np.empty(2)
        assert M.rhs(M.MODEL_SPRING, p, 0.0, 0.0, y, out)
        assert out[1] == pytest.approx((-0.5 * h + float(fl) + other) / 1e-11, rel=1e-9, abs=1e-3)
        d = 1e-6 * h                         # the record's derivative is its force's
        num = (float(law.force(h + d, s.radius_eff, values)[0])
               - float(law.force(h - d, s.radius_eff, values)[0])) / (2 * d)
        assert float(dfl) == pytest.approx(num, rel=1e-6)

