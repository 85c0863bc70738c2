"""Figures of an analysed force curve.

Every function takes ``ax=None`` (a new figure is made) and returns the axes.
Figures are built with :class:`matplotlib.figure.Figure`, never pyplot, so
nothing here changes the user's backend or global state; ``fig.savefig`` uses
Agg. Units on the axes: nm, nN, V, Hz.
"""

from __future__ import annotations

import math

import numpy as np

from .._files import display_path
from .. import forces
from ..analysis.result import AnalysisResult
from ..io.curve import RawCurve

__all__ = ["plot_raw", "plot_force_separation", "plot_residuals", "plot_contact_region", "plot_compliance_region",
           "plot_spectrum", "plot_summary"]

_RUNS = ((0, "inward (approach)", "C0", "-"), (1, "outward (retract)", "C3", ":"))


def _new_ax(ax):
    if ax is not None:
        return ax
    from matplotlib.figure import Figure

    return Figure(figsize=(6, 4.5), layout="constrained").add_subplot()


def plot_raw(curve: RawCurve, ax=None, channel: str = "auto"):
    """Raw deflection signal against position (both runs), as recorded."""
    ax = _new_ax(ax)
    use_measured = curve.position_channel(channel) == "measured"
    z = curve.position(channel)
    s = np.asarray(curve.deflection_signal)
    scale, unit = (1e9, "nm") if curve.deflection_unit in ("m", "N") else (1.0, curve.deflection_unit)
    if curve.deflection_unit == "N":
        unit = "nN"
    zs, zu = (1e6, "µm") if np.ptp(z) > 20e-6 else (1e9, "nm")  # long cell curves: µm
    for seg, label, color, ls in _RUNS:
        m = np.asarray(curve.segment) == seg
        ax.plot(z[m] * zs, s[m] * scale, ls, color=color, lw=1, label=label)
    ax.set_xlabel(f"{'measured' if use_measured else 'nominal'} position z [{zu}]")
    ax.set_ylabel(f"deflection signal [{unit}]")
    ax.set_title("raw signal")
    ax.legend(fontsize="small")
    return ax


def _vdw_curve(result: AnalysisResult, h: np.ndarray):
    fit = result.details.get("vdw")
    if fit is None or not math.isfinite(fit.hamaker_radius):
        return None
    z0 = result.contact_separation if math.isfinite(result.contact_separation) and result.contact_separation > 0 \
        else 0.35e-9
    return forces.vdw_force(h, 1.0, hamaker=fit.hamaker_radius, z0=z0)


def _say(ax, text: str):
    """Write why a panel cannot be drawn, inside it."""
    import textwrap

    ax.text(0.5, 0.5, "\n".join(textwrap.wrap(text, 48)), ha="center", va="center", transform=ax.transAxes,
            fontsize="small", color="0.3")
    return ax


def _fit_ylim(ax, y: np.ndarray) -> None:
    """The y range of the samples shown, padded by 8 % (none shown: matplotlib's)."""
    if y.size:
        ylo, yhi = float(np.min(y)), float(np.max(y))
        pad = 0.08 * max(yhi - ylo, 1e-6)
        ax.set_ylim(ylo - pad, yhi + pad)


def _window(result: AnalysisResult, max_separation: float | None) -> tuple[float, float]:
    """Separation range [m] that shows the contact region and the adhesion dip."""
    h = result.separation[np.isfinite(result.separation)]
    lo = float(np.min(h)) if h.size else -1e-9
    if result.contact_kind == "soft":
        lo = -1.05 * (result.indentation if math.isfinite(result.indentation) else -lo)
    else:
        lo = min(max(lo, -5e-9), -1e-9)  # the compliance line inside the frame, not on its edge
    reach = [40e-9 if result.contact_kind != "soft" else 0.5 * abs(lo)]
    for v in (result.rupture_distance, result.adhesion_distance, result.jump_in_separation):
        if math.isfinite(v) and v > 0:
            reach.append(1.3 * v)
    hi = max(reach) if max_separation is None else max_separation
    return lo, min(hi, float(np.max(h)) if h.size else hi)


def plot_force_separation(result: AnalysisResult, ax=None, max_separation: float | None = None,
                          theory: bool = True):
    """Force against separation around contact, axes scaled to the curve.

    The window spans the indentation (soft) or the contact line (hard) and
    reaches past the adhesion dip and the last rupture; the y-limits follow the
    data inside it. The van der Waals fit (hard contacts) is drawn solid where
    the static tip is stable and dashed where it is not (``Fs' > k``, Fig 9).
    """
    ax = _new_ax(ax)
    ax.set_xlabel("separation h [nm]")
    ax.set_title(f"force vs separation ({_contact_words(result.contact_kind)})")
    h, f = result.separation, result.force
    if not np.isfinite(h).any():
        ax.set_ylabel("force [nN]")
        return _say(ax, f"no separation: {result.contact_kind_reason or 'the zero of separation was not found'}")
    if not np.isfinite(f).any():
        f, ylabel = result.deflection, "deflection [nm]"
    else:
        ylabel = "force [nN]"
    lo, hi = _window(result, max_separation)
    inside = np.isfinite(f) & (h >= lo) & (h <= hi)
    for seg, label, color, ls in _RUNS:
        m = (result.segment == seg) & inside
        ax.plot(h[m] * 1e9, f[m] * 1e9, ls, marker=".", ms=2, color=color, lw=0.7, label=label)
    if theory and result.contact_kind != "soft":
        hh = np.linspace(max(0.5e-9, lo), max(hi, 1e-9), 400)
        law = _vdw_curve(result, hh)
        if law is not None:
            k = result.spring_constant
            grad = forces.vdw_force_gradient(hh, 1.0, hamaker=result.details["vdw"].hamaker_radius)
            stable = grad < k if math.isfinite(k) else np.ones_like(hh, bool)
            ax.plot(hh[stable] * 1e9, law[stable] * 1e9, "k-", lw=1.2, label="van der Waals fit (eq 2)")
            ax.plot(hh[~stable] * 1e9, law[~stable] * 1e9, "k--", lw=0.8)
    ad = result.details.get("adhesion")
    if ad is not None and ad.found and 0 <= ad.index < h.size and math.isfinite(f[ad.index]):
        ax.plot([h[ad.index] * 1e9], [f[ad.index] * 1e9], "^", color="C1", ms=8,
                label=f"adhesion {ad.force * 1e9:.3g} nN" if math.isfinite(ad.force) else
                f"adhesion {ad.deflection * 1e9:.3g} nm")
    _mark_steps(ax, result, h, f)
    at = _rupture_separation(result, h)
    if math.isfinite(at) and lo < at < hi:
        ax.axvline(at * 1e9, color="C4", ls=":", lw=1,
                   label=f"last rupture {ad.rupture_distance * 1e9:.4g} nm")
    ji = result.details["jumps"].jump_in if "jumps" in result.details else None
    if ji is not None and ji.found and math.isfinite(ji.force_before):
        ax.plot([ji.separation * 1e9], [ji.force_before * 1e9], "v", color="C2", ms=8, label="jump-in")
    ax.axhline(0, color="0.6", lw=0.5)
    ax.axvline(0, color="0.6", lw=0.5)
    ax.set_xlim(lo * 1e9, hi * 1e9)
    _fit_ylim(ax, f[inside] * 1e9)
    ax.set_ylabel(ylabel)
    ax.legend(fontsize="small")
    return ax


def _rupture_separation(result: AnalysisResult, h: np.ndarray) -> float:
    """Where the last rupture lies on the separation axis [m] (NaN: none).

    A soft contact's ``rupture_distance`` counts along the retract's travel from where it leaves its contact,
    not as a separation (kontrkulka: 123 nm of travel, the step at h = 85 nm; drawn at h = 123 nm the line
    stood on the flat baseline): the last unbinding step's own sample where it is one, else the adhesion
    dip's separation plus the travel between them less the dip's deflection (the lever relaxed at a
    rupture). A hard contact's is a separation already."""
    ad = result.details.get("adhesion")
    r = getattr(ad, "rupture_distance", math.nan)
    if ad is None or not math.isfinite(r):
        return math.nan
    if result.contact_kind == "hard":
        return r
    for s in getattr(ad, "steps", ()):
        if abs(s.distance - r) <= 1e-12 * max(abs(r), 1e-9) and 0 <= s.index < h.size and math.isfinite(h[s.index]):
            return float(h[s.index])
    if not (0 <= ad.index < h.size and math.isfinite(h[ad.index]) and math.isfinite(ad.distance)):
        return math.nan
    return float(h[ad.index] + (r - ad.distance) - (ad.deflection if math.isfinite(ad.deflection) else 0.0))


def _mark_steps(ax, result: AnalysisResult, h: np.ndarray, f: np.ndarray) -> None:
    """Unbinding steps of the adhesion step: a marker just after each (the force after the bond let go); the
    tethers' ruptures (hard contacts) apart: a cross at the pull before each, and each worm-like-chain fit."""
    ad = result.details.get("adhesion")
    tethers = [t for t in getattr(ad, "tethers", ()) if t.tether]
    rupt = {t.index for t in tethers}
    steps = [s.index for s in getattr(ad, "steps", ()) if s.index not in rupt and 0 <= s.index < h.size
             and math.isfinite(h[s.index] * f[s.index])]
    if steps:
        ax.plot(h[steps] * 1e9, f[steps] * 1e9, "s", mfc="none", color="C4", ms=7,
                label=f"{len(steps)} unbinding step{'s' if len(steps) > 1 else ''}")
    _mark_tethers(ax, result, tethers, h, f)


def _mark_tethers(ax, result: AnalysisResult, tethers, h: np.ndarray, f: np.ndarray) -> None:
    """Each tether's rupture (a cross at its separation and pull) and its worm-like-chain fit (a solid line over
    the rise fitted; an undetermined fit is not drawn)."""
    forces = math.isfinite(result.spring_constant) and np.isfinite(result.force).any()
    pts = [(t.separation, t.force if forces else f[t.index]) for t in tethers if 0 <= t.index < h.size]
    if not pts:
        return
    xs, ys = zip(*pts)
    ax.plot(np.array(xs) * 1e9, np.array(ys) * 1e9, "X", color="C2", ms=8, mec="k", mew=0.5, zorder=5,
            label=f"{len(pts)} tether rupture{'s' if len(pts) > 1 else ''}")
    drawn = []
    for m, t in enumerate(tethers):
        fit = t.wlc
        if not forces or fit is None or not (0 <= t.fit_start < h.size) or not fit.determined:
            continue
        a = max(float(h[t.fit_start]), 0.0)
        hh = np.linspace(a, t.separation, 200)
        pull = fit.force(hh)
        if fit.parallel:   # the later chains pulled with it (analysis.tethers.fit_tethers)
            pull = pull + sum(q.wlc.chain(hh) for q in tethers[m + 1:] if q.wlc is not None and q.wlc.determined)
        ax.plot(hh * 1e9, -pull * 1e9, "-", color="k", lw=1.1, zorder=4,
                label=None if drawn else "worm-like-chain fits")
        drawn.append(fit.contour_length)
    if drawn:
        ax.text(0.99, 0.98, "WLC fits: L_c " + ", ".join(f"{v * 1e9:.3g}" for v in drawn) + " nm", transform=ax.transAxes,
                ha="right", va="top", fontsize="x-small", color="k")


def plot_contact_region(result: AnalysisResult, ax=None, width: float = 0.25):
    """Soft contacts: force against indentation around the contact point, enlarged.

    The window spans ``width`` of the indentation before the contact point (at least the candidate
    range of equally good contact points, shaded) and up to twice that into the sample (at most
    the whole indentation); the approach is drawn with the
    retract, the contact point as a vertical line at zero indentation.
    """
    ax = _new_ax(ax)
    ax.set_xlabel("indentation [nm]")
    ax.set_title("contact region, enlarged")
    cp = result.details.get("contact_point")
    h, f = result.separation, result.force
    ylabel = "force [nN]"
    if not np.isfinite(f).any():
        f, ylabel = result.deflection, "deflection [nm]"
    ax.set_ylabel(ylabel)
    if cp is None or not math.isfinite(cp.position) or not np.isfinite(h).any():
        return _say(ax, "no contact point: nothing to enlarge")
    ind = -h  # indentation: positive into the sample
    depth = result.indentation if math.isfinite(result.indentation) and result.indentation > 0 else float(
        np.nanmax(ind))
    lo_c, hi_c = cp.position_low - cp.position, cp.position_high - cp.position  # candidate range, in z
    half = max(width * depth, 1.2 * max(abs(lo_c), abs(hi_c), 0.0), 5e-9)
    top = max(half, min(depth, 2 * half))  # into the sample: far enough to see the contact stiffen
    inside = np.isfinite(f) & (ind >= -half) & (ind <= top)
    for seg, label, color, ls in _RUNS:
        m = (result.segment == seg) & inside
        ax.plot(ind[m] * 1e9, f[m] * 1e9, ls, marker=".", ms=2, color=color, lw=0.7, label=label)
    if math.isfinite(lo_c) and math.isfinite(hi_c) and hi_c > lo_c:
        ax.axvspan(lo_c * 1e9, hi_c * 1e9, color="0.85", zorder=0, label="contact points as good (2 sigma)")
    ax.axvline(0, color="k", lw=0.8, label=f"contact point (z = {cp.position * 1e6:.4g} µm)")
    ax.axhline(0, color="0.6", lw=0.5)
    ax.set_xlim(-half * 1e9, top * 1e9)
    _fit_ylim(ax, f[inside] * 1e9)
    ax.legend(fontsize="small")
    return ax


def plot_compliance_region(result: AnalysisResult, ax=None, fraction: float = 0.15):
    """Hard contacts without a van der Waals fit: force (or deflection) against position near the turning
    point (three times the positions of the compliance lines, h < 2 nm, else the last ``fraction`` of the
    position range; at least 40 samples), both runs: the contact lines enlarged, whose slopes calibrate
    the deflection."""
    ax = _new_ax(ax)
    ax.set_title("contact region, enlarged")
    z, f = result.position, result.force
    ylabel = "force [nN]"
    if not np.isfinite(f).any():
        f, ylabel = result.deflection, "deflection [nm]"
    ax.set_ylabel(ylabel)
    ax.set_xlabel("position z [nm]")
    runs = np.isfinite(f) & np.isfinite(z) & ((result.segment == 0) | (result.segment == 1))
    if runs.sum() < 4:
        return _say(ax, "no contact region to enlarge")
    zr = z[runs]
    top = float(np.max(zr))
    h = result.separation
    touching = runs & np.isfinite(h) & (h < 2e-9)  # on the compliance lines
    width = top - float(np.min(z[touching])) if touching.any() else fraction * float(np.ptp(zr))
    lo = min(top - 3 * width, float(np.sort(zr)[-min(40, zr.size)]))
    for seg, label, color, ls in _RUNS:
        m = runs & (result.segment == seg) & (z >= lo)
        ax.plot(z[m] * 1e9, f[m] * 1e9, ls, marker=".", ms=3, color=color, lw=0.7, label=label)
    ax.axhline(0, color="0.6", lw=0.5)
    ax.legend(fontsize="small")
    return ax


def plot_residuals(result: AnalysisResult, ax=None):
    """Residual of the van der Waals fit on the approach before the jump."""
    ax = _new_ax(ax)
    fit = result.details.get("vdw")
    ax.set_xlabel("separation h [nm]")
    ax.set_ylabel("force - fit [pN]")
    ax.set_title("fit residuals")
    if fit is None or not hasattr(fit, "hamaker_radius") or not math.isfinite(fit.hamaker_radius):
        why = result.not_applicable.get("vdw") or (f"no van der Waals fit: {fit.status}" if fit is not None and
                                                   hasattr(fit, "status") else "the vdw step did not run")
        return _say(ax, why)
    h, f = result.separation, result.force
    m = (result.segment == 0) & (h >= fit.separation_min) & (h <= fit.separation_max)
    ji = result.details["jumps"].jump_in
    if ji.found:
        m &= np.arange(h.size) <= ji.index
    model = _vdw_curve(result, h[m]) + fit.force_offset + fit.force_slope * (
        h[m] - 0.5 * (fit.separation_min + fit.separation_max))
    ax.plot(h[m] * 1e9, (f[m] - model) * 1e12, ".", ms=3, color="C0")
    ax.axhline(0, color="k", lw=0.8)
    return ax


def plot_spectrum(result: AnalysisResult, ax=None):
    """Power spectrum of the post-contact residual (oscillations, section 3.2)."""
    ax = _new_ax(ax)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("power [nm$^2$]")
    ax.set_title("post-contact spectrum")
    osc = result.details.get("oscillation")
    if not np.all(np.isfinite(result.time)) or (osc is not None and math.isnan(osc.approach.nyquist)
                                                and math.isnan(osc.retract.nyquist)):
        return _say(ax, "no time base in the file: no spectrum")
    if result.contact_kind == "none":
        return _say(ax, "no contact reached: no post-contact spectrum")
    for seg, label, color, _ in _RUNS:
        m = (result.segment == seg) & (result.separation < 1e-9)
        if m.sum() < 32 or not np.all(np.isfinite(result.time[m])):
            continue
        t, d, z = result.time[m], result.deflection[m], result.position[m]
        resid = d - np.polyval(np.polyfit(z, d, 1), z)
        dt = float(np.median(np.diff(t)))
        spec = np.abs(np.fft.rfft((resid - resid.mean()) * np.hanning(resid.size))) ** 2
        freq = np.fft.rfftfreq(resid.size, dt)
        ax.semilogy(freq[1:], spec[1:] * 1e18 + 1e-30, color=color, lw=0.8, label=label)
    if osc is not None:
        what = "none"
        if osc.origin != "none":
            for peak in (osc.approach, osc.retract):
                ax.axvline(peak.frequency, color="k", ls="--", lw=0.8)
            freq = math.fsum(p.frequency for p in (osc.approach, osc.retract)) / 2  # the table's number
            what = f"{freq:.4g} Hz, {osc.origin} origin" if osc.origin == "undetermined" else f"{freq:.4g} Hz, {osc.origin}"
        ax.set_title(f"post-contact spectrum (oscillation: {what})", fontsize="medium")
    if ax.lines:
        ax.legend(fontsize="small")
    else:
        _say(ax, "fewer than 32 samples in contact: no spectrum")
    return ax


def plot_summary(result: AnalysisResult, curve: RawCurve | None = None, fig=None):
    """Four panels: raw signal, force vs separation with fit and theory, the van der Waals residuals (hard
    contacts with a fit) or the contact region enlarged (soft contacts, hard ones without a fit), spectrum."""
    if fig is None:
        from matplotlib.figure import Figure

        fig = Figure(figsize=(11, 8), layout="constrained")
    axes = fig.subplots(2, 2)
    if curve is not None:
        plot_raw(curve, axes[0, 0])
        if math.isfinite(result.sensitivity_used):  # the table's "sens. used": the one the forces were computed with
            src = "fit: the compliance slope" if result.calibration_source == "fit" else "the file's or given"
            axes[0, 0].set_title(f"raw signal (sensitivity used {result.sensitivity_used * 1e9:.4g} nm/V, {src})",
                                 fontsize="medium")
    else:
        ax = axes[0, 0]
        for seg, label, color, ls in _RUNS:
            m = result.segment == seg
            ax.plot(result.position[m] * 1e9, result.deflection[m] * 1e9, ls, color=color, label=label)
        ax.set_xlabel("position [nm]")
        ax.set_ylabel("deflection [nm]")
        ax.legend(fontsize="small")
    plot_force_separation(result, axes[0, 1])
    fit = result.details.get("vdw")
    liquid = result.details.get("liquid")
    if liquid is not None and liquid.fit_force.size:  # a colloid probe in a liquid: the DLVO fit (issue 25)
        from .liquid import plot_liquid

        plot_liquid(result, axes[1, 0])
    elif "indentation" in result.details:  # a soft contact's modulus fit: force vs indentation (issue 26)
        from .indentation import plot_indentation

        plot_indentation(result, axes[1, 0])
    elif result.contact_kind == "soft":
        plot_contact_region(result, axes[1, 0])
    elif fit is None or not math.isfinite(getattr(fit, "hamaker_radius", math.nan)):
        plot_compliance_region(result, axes[1, 0])  # no fit to show residuals of
    else:
        plot_residuals(result, axes[1, 0])
    plot_spectrum(result, axes[1, 1])
    name = display_path(result.source.rsplit("/", 1)[-1]) if result.source else "force curve"
    adh = (f"adhesion {result.adhesion_force * 1e9:.3g} nN" if math.isfinite(result.adhesion_force)
           else "no adhesion above the noise")
    ad = result.details.get("adhesion")
    if not math.isfinite(result.adhesion_force) and ad is not None and ad.found and math.isfinite(ad.deflection):
        adh = f"adhesion {ad.deflection * 1e9:.3g} nm of deflection (no spring constant)"  # as the marker says
    fig.suptitle(f"{name}: {_contact_words(result.contact_kind)}; {adh}; friction {result.friction or '-'}"
                 f"{'; DYNAMIC' if result.dynamic else ''}", fontsize="medium")
    return fig


def _contact_words(kind: str | None) -> str:
    """``hard contact``, ``soft contact``; ``no contact`` (not "none contact"), ``contact unknown``."""
    return {"none": "no contact", None: "contact unknown", "": "contact unknown"}.get(kind, f"{kind} contact")
