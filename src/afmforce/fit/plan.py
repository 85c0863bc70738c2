"""Experiment design for the dynamic fit (``afmforce plan``).

From the same Jacobians as the fit: for a probe (a model configuration with an
assumed friction coefficient) and candidate driving speeds and sample rates,
the Fisher information of one approach curve on (A, xi) with its own zero of
position, offset and drift profiled out (Schur complement); a design (a set of
curves) adds the information of its curves, and its predicted standard error
of xi is the square root of the xi element of the inverse. We rank single
speeds (each paired with the slowest candidate, which pins A*R) and search all
sets of ``n_curves`` speeds. Separately, the fastest speed at which the static
analysis (force = k x the smallest apparent deflection before contact, the
pull-in force) is within a chosen error of the static value; when the tip jumps and nothing holds it
back (xi = 0) that minimum is the deflection at contact after the fall, and is compared with its own slow
limit k (z_s + h_c) (:func:`compare_like_with_like`).
"""

from __future__ import annotations

import itertools
import math
import warnings
from dataclasses import asdict, dataclass
from typing import Sequence

import numpy as np

from ..constants import PLAN_SPEEDS
from ..errors import ParameterError
from .core import base_config
from .data import prepare_curves
from .model import Evaluator
from .params import PARAMETERS
from .problem import Problem
from .virtual import virtual_curves

__all__ = ["plan_experiment", "Plan", "curve_information", "static_error_scan", "fall_note", "fall_reference",
           "compare_like_with_like"]


@dataclass
class Plan:
    """Result of :func:`plan_experiment` (SI units)."""

    xi: float
    noise: float
    candidates: list          # per (speed, rate): info, sigma_xi paired with the reference
    best_design: dict         # speeds, sample_rates, sigma_xi, sigma_hamaker, detect_z
    static_scan: list         # per speed: pull-in force dynamic/static/reference, error vs the reference
    force_error: float
    fastest_static_speed: float
    notes: list

    def to_dict(self) -> dict:
        return asdict(self)

    def markdown(self) -> str:
        from ..units import format_quantity as fq

        L = [f"# Experiment plan (xi = {fq(self.xi, 'kg/s')}, noise {fq(self.noise, 'm')})", "",
             "| speed | sample rate | σ(xi) with the slowest speed | σ(xi) alone |", "|---|---|---|---|"]
        def sigma(value, none):     # an infinite sigma is no number: the row says why
            return fq(value, "kg/s") if math.isfinite(value) else none

        for c in self.candidates:
            paired = "- (the slowest itself)" if c['speed'] == self.candidates[0]['speed'] else "undetermined"
            L.append(f"| {fq(c['speed'], 'm/s')} | {fq(c['sample_rate'], 'Hz')} | "
                     f"{sigma(c['sigma_xi_paired'], paired)} | {sigma(c['sigma_xi_alone'], 'undetermined')} |")
        b = self.best_design
        L += ["", f"**Best design of {len(b['speeds'])} curves**: speeds "
              + ", ".join(fq(v, "m/s") for v in b["speeds"])
              + f"; σ(xi) = {fq(b['sigma_xi'], 'kg/s')}, σ(A)/A = {b['rel_sigma_hamaker']:.3g}; "
              f"xi/σ(xi) = {b['detect_z']:.3g} (friction detected at 95 % when > ~1.64).", "",
              "| speed | pull-in force, dynamic | " + ("slow limit k (z_s + h_c)" if any(
                  s.get("reference") == "contact" for s in self.static_scan) else "static")
              + " | error |", "|---|---|---|---|"]
        for s in self.static_scan:
            L.append(f"| {fq(s['speed'], 'm/s')} | {fq(s['force_dynamic'], 'N')} | "
                     f"{fq(s.get('force_reference', s['force_static']), 'N')} | {fq(s['error'], 'N')} |")
        L += ["", f"Fastest speed with the static analysis within {fq(self.force_error, 'N')}: "
              + (fq(self.fastest_static_speed, "m/s") if math.isfinite(self.fastest_static_speed)
                 else "none of the speeds scanned")]
        L += [""] + [f"- {n}" for n in self.notes]
        return "\n".join(L) + "\n"


def check_plan_size(base, speeds: Sequence[float], sample_rates: Sequence[float], n_curves: int) -> None:
    """Refuse a design too large to weigh before any curve is simulated (:func:`afmforce.limits.check_design`):
    the speeds, the curves, the designs and the samples of all candidate curves (approach and retract)."""
    from .._fields import check
    from ..limits import check_design

    for v, rate in zip(speeds, sample_rates):
        check("velocity", v)
        check("sample_rate", rate)
    d = base.drive
    samples = sum(rate * ((d.turn - d.start) + (d.turn - d.end)) / v for v, rate in zip(speeds, sample_rates))
    check_design(len(speeds), n_curves, samples)


def _prepare_planned(raws, speeds: Sequence[float], drive: dict):
    """The fit's preparation of the plan's model curves; a model curve that never reaches the
    surface is the design's (a speed too fast for the drive: friction and inertia delay the
    jump-in past the turn), said in the plan's words, not as a measured file's missing contact."""
    from ..errors import AnalysisError

    names = [f"speed {i + 1}" for i in range(len(raws))]
    try:
        return prepare_curves(raws, names, soft="warn")   # the model's own rigid curves: a weak attraction is no soft sample
    except AnalysisError as exc:
        name, _, rest = str(exc).partition(": ")
        if name not in names or not rest.startswith("no contact reached"):
            raise
        v = speeds[names.index(name)]
        raise ParameterError(
            f"at {v * 1e6:.4g} um/s the model's approach from {drive['start'] * 1e9:.4g} nm to "
            f"{drive['turn'] * 1e9:.4g} nm ends before the tip reaches the surface (the lever lags "
            "the piezo: friction, drainage and inertia delay the jump-in at this speed), so the plan "
            "has no curve to assess there: give a later turn (`turn`) or slower speeds") from None


def curve_information(base, speeds: Sequence[float], sample_rates: Sequence[float],
                      noise: float, free=("hamaker", "xi")) -> list[np.ndarray]:
    """Fisher information on ``free`` [SI] of one noiseless curve per speed (nuisances profiled)."""
    cfg = base.to_dict()
    drive = {k: cfg[k] for k in ("start", "turn", "end")}
    model_fields = {k: v for k, v in cfg.items()
                    if k not in ("velocity", "sample_rate", "start", "turn", "end", "retract_velocity",
                                 "turn_force", "turn_deflection", "dwell")}
    raws = virtual_curves(list(speeds), sample_rates=list(sample_rates), noise=0.0, drift_rms=0.0,
                          zero_offsets=[0.0] * len(speeds), baseline_offsets=[0.0] * len(speeds),
                          **model_fields, **drive)
    fcs = _prepare_planned(raws, speeds, drive)
    for c in fcs:
        c.sigma = noise
    prob = Problem(Evaluator(fcs, base, "dynamic", True), tuple(free))
    x = prob.pack({n: getattr(base, n) for n in free}, [0.0] * len(fcs))
    J = prob.jacobian(x) / prob.scale()          # per SI unit
    sizes = [int(c.mask.sum()) for c in fcs]
    offs = np.concatenate([[0], np.cumsum(sizes)])
    g = len(free)
    infos = []
    for i in range(len(fcs)):
        Ji = J[offs[i]:offs[i + 1]][:, list(range(g)) + [g + i]]
        F = Ji.T @ Ji
        A, b, c = F[:g, :g], F[:g, g:], F[g:, g:]
        infos.append(A - b @ np.linalg.pinv(c) @ b.T)
    return infos


def _sigma(info: np.ndarray) -> np.ndarray:
    try:
        return np.sqrt(np.clip(np.diag(np.linalg.inv(info)), 0, None))
    except np.linalg.LinAlgError:
        return np.full(info.shape[0], math.inf)


def static_error_scan(base, speeds: Sequence[float], sample_rates: Sequence[float]) -> list[dict]:
    """Pull-in force k*min(apparent deflection before contact) of the dynamic model vs static."""
    from ..dynamics import DynamicsWarning, simulate
    from ..dynamics.static import surface_jump_in

    k = base.force_constant
    f_static = k * surface_jump_in(k, base.surface)[2]     # geometry and double layer (issue 25)
    out = []
    for v, fs in zip(speeds, sample_rates):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DynamicsWarning)
            tr = simulate(base.replace(velocity=v, sample_rate=fs))
        # the smallest apparent deflection before contact, located on the dense output
        # (independent of the sample rate)
        e = tr.events
        f_dyn = k * float(e.min_apparent_deflection)
        # where a tip that jumps reaches it: at contact, after its fall from the instability, when its
        # deflection is z_contact + h_c (h = z2 - z = h_c): the fall, not the pull-in (see fall_note)
        at_contact = bool(e.jumped) and abs(e.min_apparent_deflection_position - e.contact_position) <= FALL_Z_TOL
        out.append({"speed": float(v), "sample_rate": float(fs), "force_dynamic": f_dyn,
                    "force_static": f_static, "force_reference": f_static, "reference": "pull_in",
                    "error": abs(f_dyn - f_static),
                    "minimum_at_contact": at_contact,
                    "force_at_contact": k * (float(e.contact_position) + base.contact_separation)})
    return out


#: How close [m] to the contact position the smallest apparent deflection must lie to be the contact's.
FALL_Z_TOL = 1e-12


def fall_reference(base) -> float:
    """The quasi-static limit [N] of the dynamic pull-in force when the tip jumps and nothing holds it back:
    k (z_s + h_c), the deflection at contact after the fall from the static instability (z_s, eq 2 on the
    surface, :func:`afmforce.dynamics.static.surface_jump_in`) to contact (h_c)."""
    from ..dynamics.static import surface_jump_in

    z_s = surface_jump_in(base.force_constant, base.surface)[1]
    return base.force_constant * (z_s + base.contact_separation)


def compare_like_with_like(base, scan: list[dict]) -> list[dict]:
    """The scan's rows with their error against the same quantity's slow limit.

    With friction the smallest apparent deflection before contact is held back before contact, and its
    slow limit is the static pull-in k d_s (``reference = "pull_in"``, rows unchanged). When every row's
    minimum lies at contact (the tip jumps and nothing holds it back: xi = 0) the dynamic number is the
    deflection at contact after the fall, whose slow limit is k (z_s + h_c) (:func:`fall_reference`), not
    k d_s: the jump-in is a static instability, not an artefact of speed. The error is then measured against
    k (z_s + h_c) (``reference = "contact"``), so that slow speeds are within the static error and the error
    goes to 0 as the speed falls; ``force_static`` stays the static pull-in k d_s."""
    if not scan or not all(r.get("minimum_at_contact") for r in scan):
        return scan
    f_ref = fall_reference(base)
    return [{**r, "force_reference": f_ref, "reference": "contact", "error": abs(r["force_dynamic"] - f_ref)}
            for r in scan]


def fall_note(base, scan: list[dict]) -> str | None:
    """What the dynamic pull-in force is when the tip jumps and nothing holds it back (every row's minimum
    reached at contact): the deflection at contact after the tip's fall from the static instability
    (h_s) to contact (h_c), k (z_contact + h_c), 2.5 x the static pull-in for the Fig 5 lever at any speed
    (k (z_s + h_c) in the quasi-static limit). Without friction that fall is the static instability, not an
    effect of speed nor of the lever's ringing (a quality factor of 30 changes it by < 1 %: 0.05 % at
    0.2 um/s, 0.5 % at 20 um/s); a recorded curve samples the fall (tens of microseconds) rarely, so its
    static analysis reads the deflection before the jump. The error column then compares with k (z_s + h_c)
    (:func:`compare_like_with_like`). None when some row's minimum lies before contact
    (friction holds the tilt back)."""
    from ..dynamics.static import surface_jump_in
    from ..units import format_quantity as fq

    rows = [r for r in scan if r.get("minimum_at_contact")]
    if not rows or len(rows) < len(scan):
        return None
    k = base.force_constant
    h_s, z_s, d_s = surface_jump_in(k, base.surface)[:3]
    hc = base.contact_separation
    slow = rows[0]
    return (f"every dynamic pull-in force above is the deflection at contact, k (z_contact + h_c), reached after "
            f"the tip's fall from the instability (h_s = {fq(h_s, 'm')}) to contact (h_c = {fq(hc, 'm')}): "
            f"{fq(slow['force_dynamic'], 'N')} at {fq(slow['speed'], 'm/s')}, "
            f"{fq(k * (z_s + hc), 'N')} in the quasi-static limit, {(z_s + hc) / d_s:.3g} x the static pull-in "
            f"(the deflection at the instability). With xi = {base.xi:g} kg/s nothing holds the tip back: the fall "
            "is the static instability, not a dynamic effect of speed nor the lever's ringing, so the error "
            "column compares each row with the same quantity's slow limit k (z_s + h_c), not with k d_s; a "
            "recorded curve rarely samples the fall (tens of microseconds), and its static analysis reads the "
            "deflection before the jump")


def plan_experiment(model="beam", *, xi: float | None = None, noise: float = 0.05e-9,
                    speeds: Sequence[float] = PLAN_SPEEDS,
                    sample_rates: Sequence[float] | None = None, points_per_nm: float = 2.0,
                    n_curves: int = 4, force_error: float | None = None, **fields) -> Plan:
    """Which speeds and sample rates determine xi best; the fastest static-safe speed.

    Parameters
    ----------
    model : str, SimulationConfig or dict
        The probe (``afmforce simulate`` defaults); its ``xi`` is the friction
        to determine, unless ``xi`` is given.
    xi : float, optional
        Friction coefficient assumed [kg/s].
    noise : float
        Deflection noise rms [m].
    speeds : sequence of float
        Candidate speeds [m/s].
    sample_rates : sequence of float, optional
        Candidate sample rate of each speed [Hz]; default ``points_per_nm x v``.
    n_curves : int
        Curves in a design (speeds may repeat).
    force_error : float, optional
        Allowed error of the static pull-in force [N]; default 10 % of the reference it is compared with
        (the static pull-in k d_s; k (z_s + h_c) when every scan row's minimum lies at contact, xi = 0).
    **fields
        Other SimulationConfig fields (drive range: start, turn).
    """
    from .._fields import check

    check("deflection_noise", noise)            # the declared ranges, before any work
    check("force_error", force_error)
    base = base_config(model, **fields)
    if xi is not None:
        base = base.replace(xi=xi)
    if base.model != "beam":
        raise ParameterError("plan designs the friction measurement: use the beam model "
                             "(the spring model has no friction)")
    if noise <= 0 or n_curves < 2 or len(set(speeds)) < 2:
        raise ParameterError("plan needs noise > 0 [m], n_curves >= 2 and >= 2 different candidate speeds "
                             "(xi cannot be determined from curves at one driving speed)")
    speeds = sorted(float(v) for v in speeds)
    rates = list(sample_rates) if sample_rates is not None else [
        points_per_nm * v * 1e9 for v in speeds]
    if len(rates) != len(speeds):
        raise ParameterError(f"{len(rates)} sample rates for {len(speeds)} speeds")
    check_plan_size(base, speeds, rates, n_curves)
    infos = curve_information(base, speeds, rates, noise)
    cands = []
    for v, fs, F in zip(speeds, rates, infos):
        cands.append({"speed": v, "sample_rate": float(fs),
                      "sigma_xi_paired": float(_sigma(F + infos[0])[1]) if v != speeds[0] else math.inf,
                      "sigma_xi_alone": float(_sigma(F)[1])})
    best = None
    for combo in itertools.combinations_with_replacement(range(len(speeds)), n_curves):
        if len({speeds[i] for i in combo}) < 2:      # one speed leaves xi undetermined
            continue
        s = _sigma(sum(infos[i] for i in combo))
        if best is None or s[1] < best[0][1]:
            best = (s, combo)
    s, combo = best
    design = {"speeds": [speeds[i] for i in combo], "sample_rates": [float(rates[i]) for i in combo],
              "sigma_xi": float(s[1]), "sigma_hamaker": float(s[0]),
              "rel_sigma_hamaker": float(s[0] / base.hamaker),
              "detect_z": float(base.xi / s[1]) if s[1] > 0 else math.inf}
    scan = compare_like_with_like(base, static_error_scan(base, speeds, rates))
    tol = force_error if force_error is not None else 0.1 * abs(scan[0]["force_reference"])
    ok = [r["speed"] for r in scan if r["error"] <= tol]
    fastest = max(ok) if ok else math.nan
    notes = [
        "sigma(xi) from the Fisher information of noiseless model curves (Cramer-Rao bound; the "
        "zero of position, offset and drift of every curve profiled out); real intervals also "
        "depend on the model being right",
        "one speed alone leaves xi and A*R strongly correlated (column 'alone'); the slowest "
        "speed pins A*R",
        f"static scan: xi = {base.xi:g} kg/s; the static pull-in force is k x the static "
        "jump-in deflection",
    ]
    fall = fall_note(base, scan)
    if fall:
        notes.append(fall)
    if ok and fastest < max(r["speed"] for r in scan) and any(
            r["error"] <= tol for r in scan if r["speed"] > fastest):
        notes.append("the force error is not monotonic in speed over the scan; check the table")
    return Plan(xi=base.xi, noise=noise, candidates=cands, best_design=design, static_scan=scan,
                force_error=float(tol), fastest_static_speed=float(fastest), notes=notes)
