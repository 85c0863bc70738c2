"""The paper's dynamic numbers (sections 2.1 and 2.3), recomputed with the dynamics engine.

Where the paper gives a number it is compared within its stated looseness
("about", "reasonable agreement"); every entry is also compared with the
independent scipy reference solves of spec section 7 (``reference``).
"""

from __future__ import annotations

import math

import numpy as np

from .. import constants as C
from ..diagnostics import inertial_lag, resonance_frequency
from .checks import PaperCheck
from .runs import FIG1_RUN, FIG5_RUN, FIG9_EXPERIMENTS, FIG9_RUN, run

__all__ = ["DYNAMIC_CHECKS", "lag_behind_static"]


def lag_behind_static(trajectory, spring_constant: float, radius: float, at: str = "separation") -> float:
    """Lag of the dynamic deflection behind the static one at the static jump point [m].

    ``at="separation"`` compares at equal separation h_J, ``at="position"`` at
    equal drive position z_J (spec section 7). Positive: the dynamic deflection
    is less attractive than the static one.
    """
    from ..dynamics import static_jump_in

    hj, zj, dj = static_jump_in(spring_constant, radius)
    tr = trajectory
    sel = tr.segment == 0
    if math.isfinite(tr.events.contact_time):
        sel &= tr.time < tr.events.contact_time
    if at == "separation":
        x = tr.separation[sel][::-1]  # increasing
        d = tr.deflection[sel][::-1]
        return float(np.interp(hj, x, d) - dj)
    x = tr.piezo_position[sel]
    return float(np.interp(zj, x, tr.deflection[sel]) - dj)


def _fig1_lag(v: float, at: str) -> float:
    return 1e9 * lag_behind_static(run(velocity=v, **FIG1_RUN), C.FIG1["spring_constant"],
                                   C.FIG1["radius"], at)


def _ev(xi: float = 0.1, v: float = 0.1e-6, **kw):
    return run(xi=xi, velocity=v, **FIG5_RUN, **kw).events


def _eq4(v: float) -> float:
    return 1e9 * float(inertial_lag(v, resonance_frequency(C.FIG1["spring_constant"], C.FIG1["mass"])))


def _fig1_checks():
    out = []
    for v, ref_h, ref_z in ((10e-6, 0.96, 1.18), (5e-6, 0.66, 0.94), (1e-6, 0.22, 0.51)):
        tag = f"{v * 1e6:g}"
        out.append(PaperCheck(
            f"fig1_dynamic_lag_{tag}", f"simulated lag behind static at h_J, {tag} um/s (vs eq 4)",
            "Fig 1, eq 4", "nm", None, ref_h, 0.0,
            lambda v=v: _fig1_lag(v, "separation"), group="dynamics", reference_tolerance=0.03,
            kind="estimate", estimate=round(_eq4(v), 3),
            note="eq 4 is an order-of-magnitude estimate ('reasonable agreement'); the simulation "
                 "is gated by the scipy reference (spec 7)"))
        out.append(PaperCheck(
            f"fig1_dynamic_lag_z_{tag}", f"simulated lag behind static at z_J, {tag} um/s",
            "Fig 1, spec 7", "nm", None, ref_z, 0.0,
            lambda v=v: _fig1_lag(v, "position"), group="dynamics", reference_tolerance=0.03))
    return out


#: Spec section 7 (independent scipy solves): (xi, v) -> hysteresis, spike, pull-off z [nm].
FIG6_REFERENCE = {(0.01, 0.1e-6): (0.045, 0.58, -183.65), (0.01, 1e-6): (0.454, 2.42, -178.0),
                  (0.1, 1e-6): (4.54, 4.64, -120.4)}


def _fig6_checks():
    out = []
    for (xi, v), (hyst, spike, pull) in FIG6_REFERENCE.items():
        tag = f"xi {xi:g} kg/s, {v * 1e6:g} um/s"
        key = f"{xi:g}_{v * 1e6:g}"
        out += [
            PaperCheck(f"fig6_hysteresis_{key}", f"outward line above inward, {tag}", "Fig 6, spec 7",
                       "nm", None, hyst, 0.0, lambda xi=xi, v=v: 1e9 * _ev(xi, v).hysteresis_offset,
                       group="dynamics", reference_tolerance=0.03),
            PaperCheck(f"fig6_spike_{key}", f"apparent-deflection spike, {tag}", "Fig 6, spec 7", "nm",
                       None, spike, 0.0, lambda xi=xi, v=v: 1e9 * _ev(xi, v).spike_height,
                       group="dynamics", reference_tolerance=0.03),
            PaperCheck(f"fig6_pull_off_{key}", f"pull-off drive position, {tag}", "Fig 6, spec 7", "nm",
                       None, pull, 0.0, lambda xi=xi, v=v: 1e9 * _ev(xi, v).pull_off_position,
                       group="dynamics", reference_tolerance=0.01),
        ]
    return out


def _spike_positive_duration() -> float:
    """Time [ms] around the spike peak during which the apparent deflection is positive (Fig 5)."""
    tr = run(xi=0.1, velocity=0.1e-6, **FIG5_RUN)
    app, t = tr.apparent_deflection, tr.time
    i = int(np.searchsorted(t, tr.events.spike_time))
    i = min(max(i, 0), t.size - 1)
    if app[i] <= 0 and i + 1 < t.size and app[i + 1] > 0:
        i += 1
    j0 = j1 = i
    while j0 > 0 and app[j0 - 1] > 0:
        j0 -= 1
    while j1 < t.size - 1 and app[j1 + 1] > 0:
        j1 += 1
    return 1e3 * float(t[j1] - t[j0] + (t[1] - t[0]))


def _fig9_lag(v: float, fs: float) -> float:
    e = run(velocity=v, sample_rate=fs, **FIG9_RUN).events
    return 1e9 * (e.jump_in_position - e.static_jump_in_position)


def _fig9_checks():
    f = resonance_frequency(C.FIG9["spring_constant"], C.FIG9["mass"])
    out = []
    for v, fs in dict(FIG9_EXPERIMENTS).items():    # one per speed
        tag = f"{v * 1e6:g}"
        out.append(PaperCheck(
            f"fig9_jump_lag_{tag}", f"1 ug jump-in beyond the static instability, {tag} um/s",
            "Figs 9-10, eq 4", "nm", 1.0, None, 0.0, lambda v=v, fs=fs: _fig9_lag(v, fs),
            group="dynamics", kind="bound", estimate=round(1e9 * float(inertial_lag(v, f)), 3),
            reason="the paper: the 1 ug dynamics agree with the static curve at every speed, "
                   "while the measured jumps are >= 1 nm farther out; gated at < 1 nm",
            note="eq 4 estimate in the estimate column"))
    return out


DYNAMIC_CHECKS: tuple[PaperCheck, ...] = (
    *_fig1_checks(),
    PaperCheck("fig5_beta", "calibration factor from the simulated constant-compliance slope",
               "section 2.3, eq 15", "nm/rad", 1.3e5, 1.2940e5, 0.01,
               lambda: 1e9 * _ev().compliance_slope, group="dynamics",
               reason="the paper prints two digits (1.3e5)"),
    PaperCheck("fig5_offset", "outward compliance line above inward, xi = 0.1 kg/s, 0.1 um/s",
               "Fig 5", "nm", 0.5, 0.454, 0.12, lambda: 1e9 * _ev().hysteresis_offset, group="dynamics",
               reference_tolerance=0.02, reason="the paper says 'about 0.5 nm'"),
    PaperCheck("fig5_pull_off", "pull-off drive position, xi = 0.1 kg/s, 0.1 um/s", "Fig 5", "nm",
               -200.0, -178.0, 0.15,
               lambda: 1e9 * _ev().pull_off_position, group="dynamics", reference_tolerance=0.01,
               reason="the paper says 'about -|F(z0)|/k = -200 nm', with k rounded to 0.13 N/m",
               note="paper: near z = -|Fs(z0)|/k, about -200 nm (-184 nm with k = 0.1387 N/m); "
                    "friction in contact moves it to -178 nm"),
    PaperCheck("fig5_spike", "apparent-deflection spike at jump-in, xi = 0.1 kg/s, 0.1 um/s", "Fig 5",
               "nm", None, 3.19, 0.0, lambda: 1e9 * _ev().spike_height, group="dynamics",
               reference_tolerance=0.05, note="positive, as the paper reports"),
    PaperCheck("fig6_min_apparent_1e-9", "min apparent deflection before contact, xi v = 1e-9 N",
               "Fig 6A", "nm", None, -2.82, 0.0, lambda: 1e9 * _ev(0.01, 0.1e-6).min_apparent_deflection,
               group="dynamics", reference_tolerance=0.02),
    PaperCheck("fig6_min_apparent_1e-8", "min apparent deflection before contact, xi v = 1e-8 N",
               "Fig 6B", "nm", None, -1.04, 0.0, lambda: 1e9 * _ev(0.1, 0.1e-6).min_apparent_deflection,
               group="dynamics", reference_tolerance=0.02),
    PaperCheck("fig6_same_xi_v", "min apparent deflection, xi = 0.01 at 1 um/s (same xi v as above)",
               "Fig 6", "nm", None, -1.04, 0.0, lambda: 1e9 * _ev(0.01, 1e-6).min_apparent_deflection,
               group="dynamics", reference_tolerance=0.02, note="only the product xi v matters before contact"),
    PaperCheck("fig6_min_apparent_1e-7", "min apparent deflection before contact, xi v = 1e-7 N",
               "Fig 6B", "nm", None, -0.05, 0.0, lambda: 1e9 * _ev(0.1, 1e-6).min_apparent_deflection,
               group="dynamics", reference_tolerance=0.1, note="the tip creeps into contact: no jump"),
    PaperCheck("fig5_mass_x100", "min apparent deflection with both masses x100 / normal",
               "section 2.3", "", 1.0, 1.0, 0.02,
               lambda: _ev(m_joint=1e-8, m_base=1e-8).min_apparent_deflection / _ev().min_apparent_deflection,
               group="dynamics", reference_tolerance=0.02,
               reason="the paper: 'quantitatively unchanged' (gated at 2 %)",
               note="the paper's check: results unchanged when the masses are raised 100 times"),
    *_fig6_checks(),
    PaperCheck("fig5_pull_off_force", "pull-off force, xi = 0.1 kg/s, 0.1 um/s", "Fig 5, eq 2", "nN",
               None, -25.510, 0.0, lambda: 1e9 * _ev().pull_off_force, group="dynamics",
               reference_tolerance=0.002,
               note="-|Fs(z0)| = -A R / (16 z0^2) for rigid surfaces; JKR would give -19.13 nN"),
    PaperCheck("fig5_spike_positive_duration", "time the apparent deflection stays positive in the "
               "jump-in spike, xi = 0.1 kg/s, 0.1 um/s", "Fig 5 text", "ms", 0.1, None, 0.0,
               _spike_positive_duration, group="dynamics", kind="differs",
               note="the paper: 'positive for less than 0.1 ms' (in total < 1.5 ms); the model stays "
                    "positive for about 0.2 ms (100 kHz samples, +-0.01 ms), twice as long. Not "
                    "gated: the paper itself calls the spike 'rather sensitive to the model used'"),
    *_fig9_checks(),
)
