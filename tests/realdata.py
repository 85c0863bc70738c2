"""Where the tests find the real instrument files of ``shared/data/real`` (beside the
repository): there, or their byte-identical copies in ``tests/data`` (some under a name
that says the instrument), so that a checkout without the shared folder still tests them.
Only files too large for ``tests/data`` (the 0.6-1 MB JPK files, the 2 MB Bruker force volume, the
HeLa JPK map, the 5.5 MB Nanosurf map) are skipped without it."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
DATA = TESTS / "data"
#: The shared folder beside the repository, or where ``AFMFORCE_REAL_DATA`` points (a worktree elsewhere).
SHARED = Path(os.environ.get("AFMFORCE_REAL_DATA") or TESTS.parents[1] / "shared" / "data" / "real")

#: shared name -> name of its byte-identical copy in tests/data, where they differ
COPIES = {
    "ForceMetric_X60_3_x4_0100.ibw": "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw",
    "PyFMlab_20200904_Egel4-Z1.0_00025.spm": "bruker-nanoscope_PyFMlab_Egel4_00025.spm",
}


def real_path(name: str) -> Path | None:
    """The shared real file ``name``, or its copy in tests/data; None when neither exists."""
    for path in (SHARED / name, DATA / COPIES.get(name, name)):
        if path.is_file():
            return path
    return None


def real_file(name: str) -> Path:
    """:func:`real_path`, skipping the calling test when the file is in neither place."""
    path = real_path(name)
    if path is None:
        pytest.skip(f"{name} is neither in {SHARED} nor in tests/data (too large to copy)")
    return path


def wave_note(path) -> dict[str, str]:
    """An Igor binary wave's note as ``{Key: value}`` (its ``Key:value`` lines, the first of each key),
    read with igor2, not afmforce: the header values a test checks afmforce's numbers against."""
    from igor2 import binarywave

    note = binarywave.load(str(path))["wave"]["note"].decode("latin-1")
    out: dict[str, str] = {}
    for line in note.replace("\n", "\r").split("\r"):
        key, sep, value = line.partition(":")
        if sep and key not in out:
            out[key] = value.strip()
    return out


def nanite_hertz_para(force, z, radius: float, spring_constant: float, segment=None, time=None) -> float:
    """nanite's Young's modulus [Pa] of one approach-retract curve given as arrays, the reference fit of the
    real-file tests: its preprocessing (tip position, force offset, ``fit_line_polynomial`` contact point) and
    a Hertz paraboloid (Poisson 0.5) on the approach. ``force`` [N] and ``z`` [m] (the piezo, towards the
    sample positive) hold the approach, then the retract, of equal halves (the approach one sample shorter
    when odd), unless ``segment`` (False/0 on the approach) and ``time`` [s] are given. Skips the test without
    nanite (the bench extra)."""
    return nanite_fit(force, z, "hertz_para", spring_constant, radius=radius, nu=0.5, segment=segment,
                      time=time)["E"]


def nanite_fit(force, z, model_key: str, spring_constant: float, *, radius: float | None = None,
               alpha_deg: float | None = None, nu: float = 0.5, segment=None, time=None,
               contact_point: float | None = None, modulus: float | None = None) -> dict:
    """nanite's fit of the indentation model ``model_key`` (``hertz_para``, ``sneddon_spher_approx``,
    ``hertz_cone``, ``hertz_pyr3s``) on one approach-retract curve given as arrays, with its preprocessing as
    :func:`nanite_hertz_para` (tip position, force offset, ``fit_line_polynomial`` contact point).

    ``radius`` [m] for the sphere laws, ``alpha_deg`` [deg] (half cone angle, or a pyramid's face angle, as
    nanite takes it) for the others; ``contact_point`` [m] (nanite's tip position, negative into the sample)
    and ``modulus`` [Pa] seed the fit instead of nanite's own initial guesses. Returns ``E`` [Pa], ``contact_point`` [m],
    ``baseline`` [N], ``ssr`` (its sum of squared residuals [N^2]), and the approach nanite fitted: ``tip`` [m] (nanite's tip position; afmforce's tip depth
    is minus it) and ``force`` [N]. Skips the test without nanite."""
    import warnings

    import numpy as np

    nanite = pytest.importorskip("nanite")
    force, z = np.asarray(force, float), np.asarray(z, float)
    half = force.size // 2
    if segment is None:
        segment = np.r_[np.zeros(half, bool), np.ones(force.size - half, bool)]
    if time is None:
        time, duration = np.arange(force.size) * 1e-3, 1.0
    else:
        time = np.asarray(time, float) - float(time[0])
        duration = float(time[-1])
    md = {"spring constant": spring_constant, "sensitivity": 1.0, "path": "x", "enum": 0,
          "imaging mode": "force-distance", "duration": duration, "point count": force.size}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idnt = nanite.Indentation(data={"force": force, "height (measured)": -z,
                                        "segment": np.asarray(segment).astype(bool), "time": time},
                                  metadata=md)
        idnt.apply_preprocessing(["compute_tip_position", "correct_force_offset", "correct_tip_offset"],
                                 options={"correct_tip_offset": {"method": "fit_line_polynomial"}})
        p = idnt.get_initial_fit_parameters(model_key=model_key)
        if "R" in p:
            p["R"].set(value=radius)
        if "alpha" in p:
            p["alpha"].set(value=alpha_deg)
        p["nu"].set(value=nu)
        if contact_point is not None:
            p["contact_point"].set(value=contact_point)
        if modulus is not None:
            p["E"].set(value=modulus)
        idnt.fit_model(model_key=model_key, params_initial=p, weight_cp=0, range_x=(0, 0),
                       range_type="absolute", segment="approach")
    pf = idnt.fit_properties["params_fitted"]
    app = ~np.asarray(idnt.data["segment"]).astype(bool)
    tip, f = np.asarray(idnt.data["tip position"])[app], np.asarray(idnt.data["force"])[app]
    fn = nanite.model.models_available[model_key].model
    ssr = float(np.sum((fn(pf, tip) - f) ** 2))
    return {"E": float(pf["E"].value), "contact_point": float(pf["contact_point"].value),
            "baseline": float(pf["baseline"].value), "ssr": ssr, "tip": tip, "force": f}


def bruker_synthetic_header() -> tuple[float, float]:
    """(InvOLS [m/V], k [N/m]) of ``tests/data/bruker-nanoscope_synthetic.txt`` from its header lines, by
    regular expression (independent of afmforce's reader)."""
    import re

    text = (DATA / "bruker-nanoscope_synthetic.txt").read_text()
    sens = float(re.search(r"\\@Sens\. DeflSens: V ([\d.]+) nm/V", text).group(1)) * 1e-9
    k = float(re.search(r"\\Spring Constant: ([\d.]+)", text).group(1))
    return sens, k
