"""Quasi-static synthetic force curves with known truth (for tests, docs and benchmarks).

The tip follows static equilibrium on the stable branch (spec sections 1-2):
``k z2 = Fs(h)`` with ``h = z2 - z`` and eq 2 for ``Fs``. On the approach the
tip stays on the far branch until it disappears (jump into contact), on the
retract it stays in contact until that branch disappears (pull-off). The
photodiode signal is ``z2 / sensitivity`` plus offset, drift, noise and
optionally interference fringes ``I0 cos(2 pi D / P)`` with ``D = z - z2`` the
substrate-cantilever distance (constant in contact); the nominal position may
be bent by a quadratic piezo nonlinearity that differs between runs. No
dynamics: for dynamic runs use :mod:`afmforce.dynamics` and
:mod:`afmforce.instrument`.
"""

from __future__ import annotations

import math

import numpy as np

from .. import forces
from ..constants import HAMAKER, Z0
from ..errors import ParameterError
from ..io.curve import RawCurve

__all__ = ["static_separation", "static_curve", "tether_curve"]


_ROWS = 256  # substrate positions per block of the root-bracketing grid (~6 MB of float64 each)


def _bisect(g, lo, hi, n_iter=80):
    glo = g(lo)
    for _ in range(n_iter):
        mid = 0.5 * (lo + hi)
        gm = g(mid)
        left = np.sign(gm) == np.sign(glo)
        lo = np.where(left, mid, lo)
        glo = np.where(left, gm, glo)
        hi = np.where(left, hi, mid)
    return 0.5 * (lo + hi)


def static_separation(z: np.ndarray, segment: np.ndarray, *, spring_constant: float, radius: float,
                      hamaker: float = HAMAKER, z0: float = Z0) -> np.ndarray:
    """Separation h [m] of the static tip for substrate positions z [m] (approach then retract).

    Solves ``Fs(h) = k (h + z)`` on the stable branch the tip is on (see module docstring).
    """
    z = np.asarray(z, float)
    k, ar = spring_constant, hamaker * radius
    grid = np.geomspace(0.5 * z0, max(1e-6, 2 * float(np.max(np.abs(z))) + 1e-7), 3000)
    h_peak = 3 ** (1 / 6) * z0  # steepest attraction: separates contact and free branches

    def g_of(h, zz):
        return forces.vdw_force(h, 1.0, hamaker=ar, z0=z0) - k * (h + zz)

    has_free = np.empty(z.size, bool)
    has_contact = np.empty(z.size, bool)
    last = np.empty(z.size, np.intp)  # largest root's bracket
    first = np.empty(z.size, np.intp)  # smallest root's bracket
    free_cols, contact_cols = grid[None, 1:] > h_peak, grid[None, :-1] < h_peak
    for a in range(0, z.size, _ROWS):  # row blocks: memory O(_ROWS x grid), not O(n x grid)
        b = min(a + _ROWS, z.size)
        G = g_of(grid[None, :], z[a:b, None])
        change = np.signbit(G[:, :-1]) != np.signbit(G[:, 1:])
        has_free[a:b] = (change & free_cols).any(axis=1)
        has_contact[a:b] = (change & contact_cols).any(axis=1)
        last[a:b] = change.shape[1] - 1 - np.argmax(change[:, ::-1], axis=1)
        first[a:b] = np.argmax(change, axis=1)
    on_contact = []
    state = False
    for approach, free, contact in zip((np.asarray(segment) == 0).tolist(), has_free.tolist(),
                                       has_contact.tolist()):  # follow the branch: jumps only when it ends
        state = (state or not free) if approach else (state and contact)
        on_contact.append(state)
    on_contact = np.array(on_contact, bool)
    j = np.where(on_contact, first, last)
    return _bisect(lambda h: g_of(h, z), grid[j], grid[j + 1])


def static_curve(*, spring_constant: float = 0.21, radius: float = 220e-9, hamaker: float = HAMAKER,
                 z0: float = Z0, velocity: float = 0.5e-6, sample_rate: float = 2000.0, start: float = -60e-9,
                 turn: float = 30e-9, end: float | None = None, sensitivity: float = 50e-9,
                 offset: float = 0.3, drift: float = 0.0, noise: float = 0.0, fringe_amplitude: float = 0.0,
                 fringe_period: float = 320e-9, piezo_quadratic: tuple[float, float] = (0.0, 0.0),
                 seed: int | None = 0) -> RawCurve:
    """A quasi-static approach-retract curve with ground truth.

    Parameters
    ----------
    spring_constant : float  k [N/m]
    radius, hamaker, z0 : float  eq 2 parameters [m], [J], [m]
    velocity : float  driving speed, both runs [m/s]
    sample_rate : float  [Hz]
    start, turn, end : float
        Substrate positions [m] (z = 0: contact with the undeflected spring); ``end``
        defaults to 1.3 x the pull-off position plus 40 nm.
    sensitivity : float  InvOLS [m/V]
    offset : float  photodiode offset [V]
    drift : float  photodiode drift [V/s]
    noise : float  white deflection noise [m]
    fringe_amplitude, fringe_period : float  interference I0 [V] and period [m]
    piezo_quadratic : (float, float)
        Quadratic bend of the nominal position over each run (approach, retract):
        ``z_nominal = z + q (z - z_mid)^2 / half_range`` [-].
    seed : int or None  noise seed

    Returns
    -------
    RawCurve
        Volts against nominal (and exact measured) position; ``truth`` holds
        ``separation``, ``deflection``, ``position``, ``jump_in_index``,
        ``pull_off_index``, ``sensitivity``, ``hamaker_radius``.
    """
    k = spring_constant
    if end is None:
        end = -1.3 * float(abs(forces.max_attraction_force(radius, hamaker, z0))) / k - 40e-9
    step = velocity / sample_rate
    z_app = np.arange(start, turn, step)
    z_ret = np.arange(turn, end, -step)
    z = np.concatenate([z_app, z_ret])
    seg = np.concatenate([np.zeros(z_app.size, np.int8), np.ones(z_ret.size, np.int8)])
    h = static_separation(z, seg, spring_constant=k, radius=radius, hamaker=hamaker, z0=z0)
    z2 = h + z
    t = np.arange(z.size) / sample_rate
    rng = np.random.default_rng(seed)
    defl_meas = z2 + noise * rng.standard_normal(z.size)
    fringe = fringe_amplitude * np.cos(2 * math.pi * (z - z2) / fringe_period)
    volts = defl_meas / sensitivity + offset + drift * t + fringe
    z_nom = z.copy()
    for which, q in enumerate(piezo_quadratic):
        m = seg == which
        mid, half = 0.5 * (z[m].max() + z[m].min()), 0.5 * np.ptp(z[m])
        z_nom[m] = z[m] + q * (z[m] - mid) ** 2 / half
    on_contact_app = np.flatnonzero((seg == 0) & (h < 3 ** (1 / 6) * z0))
    on_contact_ret = np.flatnonzero((seg == 1) & (h < 3 ** (1 / 6) * z0))
    truth = dict(separation=h, deflection=z2, position=z, sensitivity=sensitivity,
                 hamaker_radius=hamaker * radius, spring_constant=k, fringe_period=fringe_period,
                 jump_in_index=int(on_contact_app[0] - 1) if on_contact_app.size else -1,
                 pull_off_index=int(on_contact_ret[-1]) if on_contact_ret.size else -1)
    meta = dict(spring_constant=k, sample_rate=sample_rate, velocity=velocity,
                source_file="synthetic quasi-static curve")
    return RawCurve(time=t, piezo_nominal=z_nom, piezo_measured=None if any(piezo_quadratic) else z.copy(),
                    deflection_signal=volts, segment=seg, metadata=meta, truth=truth, deflection_unit="V")


def tether_curve(*, tethers: tuple[tuple[float, float, float], ...] = ((120e-9, 0.4e-9, 100e-9),),
                 adhesion: float = 0.0, spring_constant: float = 0.05, sensitivity: float = 50e-9,
                 push: float = 50e-9, start: float = -300e-9, end: float = -450e-9, step: float = 0.25e-9,
                 sample_rate: float = 4000.0, noise: float = 0.0, temperature: float = 298.15,
                 seed: int | None = 0, wlc_model: str = "marko-siggia") -> RawCurve:
    """A quasi-static curve on a hard (rigid) contact that pulls worm-like-chain tethers, with its truth.

    The approach is free (zero deflection) up to contact at z = 0, then on the compliance line
    (deflection = z) up to ``push``. The retract stays on that line until the pull reaches the tip--surface
    ``adhesion`` (the deflection -adhesion/k), then leaves the surface; from there the tip, at separation
    ``h`` from the surface with the sample ``s = -z`` away, is held by the tethers still attached:
    ``h + F(h)/k = s`` with ``F`` the sum of their Marko--Siggia forces (:func:`~.tethers.wlc_force`). A
    tether lets go when ``h`` reaches its rupture extension (all attached at the surface's contact).

    Parameters
    ----------
    tethers : tuple of (contour length [m], persistence length [m], rupture extension [m])
        Rupture extensions must grow along the tuple and lie below the contour lengths.
    adhesion : float  tip--surface adhesion [N] (>= 0; 0: the tip leaves the line at zero force)
    spring_constant : float  k [N/m]
    sensitivity : float  InvOLS [m/V]
    push, start, end : float  turning point, approach start and retract end positions [m]
    step : float  position step per sample [m]
    sample_rate : float  [Hz]
    noise : float  white deflection noise [m]
    temperature : float  [K] (written to the metadata: the analysis' worm-like-chain fits read it there)
    seed : int or None  noise seed
    wlc_model : str  the chain's force law (:data:`~.wlc.WLC_MODELS`)

    Returns
    -------
    RawCurve
        Volts against position (m); ``truth`` holds ``deflection``, ``separation``, ``position``,
        ``adhesion`` [N], ``pull_off_index``, ``ruptures`` (a tuple of dicts: ``separation`` [m],
        ``position`` [m], ``force`` [N] (< 0: the pull just before the rupture), ``index`` (the last
        attached sample)).
    """
    from .tethers import wlc_force

    k = spring_constant
    ext = [float(t[2]) for t in tethers]
    if any(b <= a for a, b in zip(ext, ext[1:])) or any(t[2] >= t[0] for t in tethers) or adhesion < 0:
        raise ParameterError("tethers: rupture extensions must grow and stay below the contour lengths; adhesion >= 0")

    def pull(h: np.ndarray, first: int) -> np.ndarray:   # the tethers first.. attached: their summed force [N]
        f = np.zeros_like(h)
        for L, p, _ in tethers[first:]:
            f = f + wlc_force(np.clip(h, 0.0, None), L, p, temperature, wlc_model)
        return f

    z_app = np.arange(start, push, step)
    z_ret = np.arange(push, end, -step)
    d_app = np.clip(z_app, 0.0, None)
    s = -z_ret
    s_off = adhesion / k                               # the sample's travel beyond contact when the tip leaves
    on = s < s_off
    d_ret = np.where(on, z_ret, 0.0)
    h_ret = np.zeros_like(s)
    bounds = [s_off] + [x + float(pull(np.array([x]), m)[0]) / k for m, x in enumerate(ext)]  # s at each rupture
    if any(b <= a for a, b in zip(bounds[1:], bounds[2:])):
        raise ParameterError("tethers: a later tether breaks before an earlier one (make their ruptures farther apart)")
    for m in range(len(ext) + 1):
        lo = bounds[m] if m else s_off
        hi = bounds[m + 1] if m < len(ext) else math.inf
        sel = (s >= max(lo, s_off)) & (s < hi)
        if not sel.any():
            continue
        ss = s[sel]
        cap = ext[m] if m < len(ext) else float(ss.max())
        a, b = np.zeros_like(ss), np.minimum(ss, cap)     # h + F(h)/k - s: <= 0 at 0, >= 0 at min(s, cap)
        for _ in range(80):
            mid = 0.5 * (a + b)
            low = mid + pull(mid, m) / k < ss
            a, b = np.where(low, mid, a), np.where(low, b, mid)
        h_ret[sel] = 0.5 * (a + b)
        d_ret[sel] = -pull(h_ret[sel], m) / k
    z = np.concatenate([z_app, z_ret])
    d = np.concatenate([d_app, d_ret])
    h = np.concatenate([np.clip(-z_app, 0.0, None), h_ret])
    seg = np.concatenate([np.zeros(z_app.size, np.int8), np.ones(z_ret.size, np.int8)])
    rng = np.random.default_rng(seed)
    volts = (d + noise * rng.standard_normal(z.size)) / sensitivity
    n0 = z_app.size
    rupt = []
    for m, x in enumerate(ext):
        last = int(np.flatnonzero(s < bounds[m + 1])[-1])   # the last attached sample
        rupt.append(dict(separation=float(h_ret[last]), position=float(z_ret[last]), index=n0 + last,
                         force=-float(pull(np.array([h_ret[last]]), m)[0]), extension=x,
                         force_at_extension=-float(pull(np.array([x]), m)[0])))
    truth = dict(deflection=d, separation=h, position=z, sensitivity=sensitivity, spring_constant=k,
                 adhesion=-float(adhesion), pull_off_index=n0 + int(np.flatnonzero(on)[-1]) if on.any() else -1,
                 ruptures=tuple(rupt))
    meta = dict(spring_constant=k, sample_rate=sample_rate, velocity=step * sample_rate, temperature=temperature,
                source_file="synthetic worm-like-chain tethers on a hard contact")
    t = np.arange(z.size) / sample_rate
    return RawCurve(time=t, piezo_nominal=z, piezo_measured=z.copy(), deflection_signal=volts, segment=seg,
                    metadata=meta, truth=truth, deflection_unit="V")
