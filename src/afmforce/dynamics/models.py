"""Vector fields and analytic Jacobians of the two dynamical models (compiled).

Spec sections 3 and 5; paper eqs 1 and 22-28.

Both models are first-order systems ``y' = f(t, y)`` integrated segment by
segment of a piecewise-linear drive ``z(t) = z_a + v (t - t_a)`` (see
:mod:`afmforce.dynamics.drive`), so the drive speed ``v`` is a constant inside
one call.

* **spring** (eq 1): ``y = (x, x')``, ``m x'' = -k x + Fd(h, h') + Fs(h)`` with
  ``h = x - z(t)``.
* **beam** (eqs 22-28): ``y = (q_alpha, q_beta, q_alpha', q_beta')`` with
  ``q_alpha = x`` (end deflection of the flexible beam) and
  ``q_beta = L1 theta + 3x/2``; ``m_i q_i'' = sum_j A_ij q_j + Fz dh/dq_i + Fy dy2/dq_i``,
  ``A = -T^T K T`` (spec section 5), ``Fz = Fs(h) + Fd(h, h')`` and
  ``Fy = -(xi + zeta Fz^2) y2'`` (eq 28 and the load-dependent form after it).
  As the paper says ("for technical reasons"), drainage and friction enter as
  if derived from potentials: they act through ``dh/dq`` and ``dy2/dq`` like
  the conservative surface force.
* **lever damping** (issue 23; absent in the paper, zero by default): the
  spring gets ``-c x'`` with ``c = m omega0 / Q``; the beam ``-C q'`` with the
  Rayleigh matrix ``C = alpha M + beta K`` (:mod:`.damping`), which gives
  both free modes the requested quality factors.

In a liquid (issue 25, docs/liquid.md) ``Fz`` also holds the double layer
(:func:`static_force`: weak overlap or Hogg-Healy-Fuerstenau), drainage with
Vinogradova's slip factor and the drag on the lever (:func:`drainage`); the geometry
(sphere-sphere or sphere-flat) is in the packed ``AR`` and ``CD``. The surface force laws of
:mod:`afmforce.surface_laws` (issue 31: hydration, steric brushes, capillary meniscus, ...) add
to ``Fs``: their slots follow the model's (``P_LAWS``), assigned by that registry, and
:data:`laws_force` chains their compiled kernels.

The parameters are packed into one float64 vector ``p`` (layout below) so that
the integrator can be compiled once for both models. ``p[H_GUARD]`` is the
smallest separation the force law accepts: a trial state with ``h`` below it
(for instance a Newton iterate overshooting into the substrate, where eq 2
turns attractive again) makes :func:`rhs` return ``False`` and the integrator
rejects the trial step.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.core import types as _types
from numba.extending import overload

from .. import surface_laws
from ._jit import piece
from .damping import beam_damping, spring_damping

MODEL_SPRING = 0
MODEL_BEAM = 1
MODEL_IDS = {"spring": MODEL_SPRING, "beam": MODEL_BEAM}

# --- layout of the parameter vector p -------------------------------------
AR = 0          # Hamaker constant x radius [J m]
Z0 = 1          # soft-wall length [m]
CD = 2          # drainage coefficient 6 pi eta R^2 / 4 [kg m]  (Fd = -CD h'/h)
H_GUARD = 3     # smallest admissible separation [m]
XI = 4          # friction coefficient xi [kg/s]            (beam only)
ZETA = 5        # load-dependent friction zeta [kg/(s N^2)] (beam only)
# spring
K = 6           # spring constant [N/m]
INV_M = 7       # 1/m [1/kg]
# beam
A00, A01, A10, A11 = 6, 7, 8, 9   # dynamical matrix A = -T^T K T [N/m]
INV_MA, INV_MB = 10, 11           # 1/m_alpha, 1/m_beta [1/kg]
HQA, HQB = 12, 13                 # dh/dq_alpha, dh/dq_beta [-]
YQA, YQB = 14, 15                 # dy2/dq_alpha, dy2/dq_beta [-]
TH_A, TH_B = 16, 17               # dtheta/dq_alpha, dtheta/dq_beta [rad/m]
# both models
MOBILITY = 18   # dh-direction inverse mass: 1/m (spring), hq.M^-1.hq (beam) [1/kg]
K_EFF = 19      # force-measuring spring constant k (eq 13 for the beam) [N/m]
# lever damping (issue 23): -C q' [kg/s]; spring: C00 = m omega0 / Q; 0 = undamped (paper)
C00, C01, C10, C11 = 20, 21, 22, 23
# liquids (issue 25; both models): double layer, drainage with slip, lever drag
DL_A = 24       # double layer: 2 pi R_eff (eps eps0 kappa / 2) 2 psi1 psi2 [N] (csch term)
DL_B = 25       # double layer: 2 pi R_eff (eps eps0 kappa / 2) (-/+)(psi1^2 + psi2^2) [N] (coth - 1)
DL_KAPPA = 26   # inverse Debye length kappa [1/m] (0: no double layer)
DL_EXACT = 27   # 1: Hogg-Healy-Fuerstenau terms; 0: weak overlap (csch -> 2 exp(-kappa h))
SLIP6B = 28     # 6 b, b the slip length [m] (0: no slip; Fd = -CD f*(h)/h h')
LEVER = 29      # lever drag coefficient c [N s/m] (F = -c g(h) h')
LEVER_H = 30    # lever height H [m]: g = H / (h + H); 0: g = 1
# surface force laws (issue 31): the block afmforce.surface_laws packs, its slots assigned there
P_LAWS = 31
P_SIZE = P_LAWS + surface_laws.N_SLOTS

#: Number of monitored observables returned by :func:`observe`.
N_OBS = 9
# indices into the observable vector
O_H, O_HDOT, O_DEFL, O_THETA, O_FZ, O_Y2, O_Y2DOT, O_FY, O_Z = range(N_OBS)


#: The type of the compiled calls' model id when the run uses none of the terms beyond the
#: paper's (issue 35): numba compiles the integrator, the event location and the sampling once
#: per type of their ``model`` argument, and :func:`extras` is a compile-time constant there, so
#: the paper's runs (``np.int8`` ids, :func:`kernel_model`) carry no code of the liquids, the
#: lever damping or the surface force laws, while any other integer (a plain Python ``int``:
#: int64) compiles every term, each tested at run time on its slots as before.
PLAIN = np.int8


def extras(model) -> bool:
    """Whether ``model`` (an id as the compiled calls get it) compiles the terms beyond the
    paper's: double layer, slip, lever drag, lever damping, surface force laws. In compiled
    code a constant of the argument's type (:data:`PLAIN`: False)."""
    return not isinstance(model, PLAIN)


@overload(extras, inline="always")
def _extras_compiled(model):
    plain = isinstance(model, _types.Integer) and model.bitwidth == 8 and model.signed
    if plain:
        return lambda model: False
    return lambda model: True


def uses_extras(p) -> bool:
    """Whether the packed vector ``p`` turns on a term beyond the paper's (the same tests as
    the compiled terms': a double layer, slip, lever drag, a surface force law, or any lever
    damping coefficient)."""
    return bool(p[DL_KAPPA] > 0.0 or p[SLIP6B] > 0.0 or p[LEVER] > 0.0 or p[P_LAWS] > 0.0
                or p[C00] != 0.0 or p[C01] != 0.0 or p[C10] != 0.0 or p[C11] != 0.0)


def kernel_model(model: int, p):
    """The model id the compiled calls get for the packed vector ``p``: ``PLAIN(model)`` when
    ``p`` uses no term beyond the paper's (:func:`uses_extras`), else the Python ``int``."""
    return int(model) if uses_extras(p) else PLAIN(model)


def state_size(model: int) -> int:
    """Number of first-order state variables of ``model``."""
    return 2 if model == MODEL_SPRING else 4


@piece()
def surface_force(h, ar, z0):
    """Fs(h) and Fs'(h) of eq 2 [N, N/m]."""
    ih2 = 1.0 / (h * h)
    r2 = z0 * z0 * ih2
    r6 = r2 * r2 * r2             # as numba compiles ``r2 ** 3`` (Python's pow rounds otherwise)
    fs = -(ar / 12.0) * ih2 * (1.0 - 0.25 * r6)
    dfs = (ar / 6.0) * ih2 / h * (1.0 - r6)
    return fs, dfs


def _no_law(h, p):
    return 0.0, 0.0


def _add_law(total, kernel, o):
    """``total`` followed by one law: its kernel adds (F, F') when its switch ``p[o]`` is on."""
    def add(h, p):
        fs, dfs = total(h, p)
        if p[o] > 0.0:
            f, df = kernel(h, p, o + 1)
            fs += f
            dfs += df
        return fs, dfs
    return add


def _laws_chain():
    """One compiled function adding every law of :data:`afmforce.surface_laws.COMPILED` to (F, F'):
    a chain of pieces, one per law, each with its kernel and its slot (no code generation; the
    pieces are inlined into the cached entry point, whose cache the sources' digest guards)."""
    total = piece(inline=True, python=True)(_no_law)
    names = list(surface_laws.COMPILED)
    for name in names:
        kernel = piece(inline=True, python=True)(surface_laws.COMPILED[name].kernel)
        # the last link is not forced inline: static_force stays small (LLVM inlines it into
        # rhs and jac as before) and calls the chain only when a law is on
        total = piece(inline=name != names[-1], python=True)(
            _add_law(total, kernel, P_LAWS + surface_laws.SLOTS[name]))
    return total


#: ``laws_force(h, p) -> (F, F')`` of every law that is on (its switch), summed.
laws_force = _laws_chain()


@piece()
def static_force(model, h, p):
    """Static normal force and its gradient: eq 2, the double layer and the surface force laws of
    :mod:`afmforce.surface_laws` (:data:`laws_force`) [N, N/m]; eq 2 alone where ``model`` has
    no extras (:func:`extras`)."""
    fs, dfs = surface_force(h, p[AR], p[Z0])
    if not extras(model):
        return fs, dfs
    kappa = p[DL_KAPPA]
    if kappa > 0.0:
        x = kappa * h
        e1 = math.exp(-x)
        if p[DL_EXACT] > 0.0:
            q = -math.expm1(-2.0 * x)
            cs = 2.0 * e1 / q                 # csch x
            cm = cs * e1                      # coth x - 1
            fs += p[DL_A] * cs + p[DL_B] * cm
            dfs -= kappa * (p[DL_A] * cs * (cm + 1.0) + p[DL_B] * cs * cs)
        else:
            w = p[DL_A] * 2.0 * e1
            fs += w
            dfs -= kappa * w
    if p[P_LAWS] > 0.0:                      # any surface force law on (issue 31)
        fl, dfl = laws_force(h, p)
        fs += fl
        dfs += dfl
    return fs, dfs


@piece()
def drainage(model, h, hd, p):
    """Drainage (with slip) and lever drag: (F [N], dF/dh [N/m], dF/dh' [N s/m]).

    ``F = -CD phi(h) h' - c g(h) h'`` with ``phi = f*(h)/h`` (Vinogradova 1995; 1/h
    without slip, computed exactly as before issue 25) and ``g = H/(h + H)`` (or 1).
    """
    cd = p[CD]
    if not extras(model):                # the paper's eq 3 (as the no-slip branch below)
        return -cd * hd / h, cd * hd / (h * h), -cd / h
    b6 = p[SLIP6B]
    if b6 > 0.0:
        u = b6 / h
        if u < 1e-3:
            phi = (1.0 - u / 3.0 + u * u / 6.0 - 0.1 * u * u * u) / h
            dphi = -(1.0 - 2.0 * u / 3.0 + 0.5 * u * u - 0.4 * u * u * u) / (h * h)
        else:
            l1 = math.log1p(u)
            phi = ((1.0 + 1.0 / u) * l1 - 1.0) * 2.0 / b6
            dphi = -(2.0 / (u * h * h)) * (1.0 - l1 / u)
        f = -cd * phi * hd
        dfh = -cd * dphi * hd
        dfv = -cd * phi
    else:
        f = -cd * hd / h
        dfh = cd * hd / (h * h)
        dfv = -cd / h
    c = p[LEVER]
    if c > 0.0:
        H = p[LEVER_H]
        if H > 0.0:
            g = H / (h + H)
            dg = -g / (h + H)
        else:
            g = 1.0
            dg = 0.0
        f -= c * g * hd
        dfh -= c * dg * hd
        dfv -= c * g
    return f, dfh, dfv


@piece(python=True)
def rhs(model, p, zd, vd, y, out):
    """Evaluate ``out = f(t, y)`` at drive position ``zd`` and speed ``vd``.

    Returns ``False`` (and leaves ``out`` undefined) when the separation is
    below ``p[H_GUARD]``: the trial state is inadmissible.
    """
    if model == MODEL_SPRING:
        x = y[0]
        xd = y[1]
        h = x - zd
        if not h > p[H_GUARD]:
            return False
        hd = xd - vd
        fs, _ = static_force(model, h, p)
        fd, _, _ = drainage(model, h, hd, p)
        fz = fs + fd
        out[0] = xd
        g = -p[K] * x + fz
        if extras(model):
            g -= p[C00] * xd
        out[1] = p[INV_M] * g
        return True
    qa = y[0]
    qb = y[1]
    va = y[2]
    vb = y[3]
    hqa = p[HQA]
    hqb = p[HQB]
    yqa = p[YQA]
    yqb = p[YQB]
    h = hqa * qa + hqb * qb - zd
    if not h > p[H_GUARD]:
        return False
    hd = hqa * va + hqb * vb - vd
    fs, _ = static_force(model, h, p)
    fd, _, _ = drainage(model, h, hd, p)
    fz = fs + fd
    yd = yqa * va + yqb * vb
    fy = -(p[XI] + p[ZETA] * fz * fz) * yd
    out[0] = va
    out[1] = vb
    ga = p[A00] * qa + p[A01] * qb + fz * hqa + fy * yqa
    gb = p[A10] * qa + p[A11] * qb + fz * hqb + fy * yqb
    if extras(model):                     # lever damping -C q'
        ga -= p[C00] * va + p[C01] * vb
        gb -= p[C10] * va + p[C11] * vb
    out[2] = p[INV_MA] * ga
    out[3] = p[INV_MB] * gb
    return True


@piece(python=True)
def jac(model, p, zd, vd, y, J):
    """Analytic Jacobian ``J = df/dy`` (same arguments as :func:`rhs`)."""
    if model == MODEL_SPRING:
        h = y[0] - zd
        if not h > p[H_GUARD]:
            return False
        hd = y[1] - vd
        _, dfs = static_force(model, h, p)
        _, dfh, dfv = drainage(model, h, hd, p)
        im = p[INV_M]
        J[0, 0] = 0.0
        J[0, 1] = 1.0
        J[1, 0] = im * (-p[K] + dfs + dfh)
        j11 = im * dfv
        if extras(model):
            j11 -= im * p[C00]
        J[1, 1] = j11
        return True
    qa = y[0]
    qb = y[1]
    va = y[2]
    vb = y[3]
    hqa = p[HQA]
    hqb = p[HQB]
    yqa = p[YQA]
    yqb = p[YQB]
    h = hqa * qa + hqb * qb - zd
    if not h > p[H_GUARD]:
        return False
    hd = hqa * va + hqb * vb - vd
    fs, dfs = static_force(model, h, p)
    fd, dfh, dfv = drainage(model, h, hd, p)
    fz = fs + fd
    dfz_dh = dfs + dfh                    # dFz/dh
    dfz_dhd = dfv                         # dFz/dh'
    yd = yqa * va + yqb * vb
    xi_eff = p[XI] + p[ZETA] * fz * fz
    dfy_dfz = -2.0 * p[ZETA] * fz * yd    # dFy/dFz
    ima = p[INV_MA]
    imb = p[INV_MB]
    for i in range(4):
        J[0, i] = 0.0
        J[1, i] = 0.0
    J[0, 2] = 1.0
    J[1, 3] = 1.0
    # d(generalised force_i)/dq_j = A_ij + (hq_i + yq_i dFy/dFz) dFz/dh hq_j
    ga = hqa + yqa * dfy_dfz
    gb = hqb + yqb * dfy_dfz
    J[2, 0] = ima * (p[A00] + ga * dfz_dh * hqa)
    J[2, 1] = ima * (p[A01] + ga * dfz_dh * hqb)
    J[3, 0] = imb * (p[A10] + gb * dfz_dh * hqa)
    J[3, 1] = imb * (p[A11] + gb * dfz_dh * hqb)
    # velocities: through Fd (hq_j dFz/dh') and friction (-xi_eff yq_j)
    # and the lever damping -C q'
    j22 = ga * dfz_dhd * hqa - xi_eff * yqa * yqa
    j23 = ga * dfz_dhd * hqb - xi_eff * yqa * yqb
    j32 = gb * dfz_dhd * hqa - xi_eff * yqb * yqa
    j33 = gb * dfz_dhd * hqb - xi_eff * yqb * yqb
    if extras(model):
        j22 -= p[C00]
        j23 -= p[C01]
        j32 -= p[C10]
        j33 -= p[C11]
    J[2, 2] = ima * j22
    J[2, 3] = ima * j23
    J[3, 2] = imb * j32
    J[3, 3] = imb * j33
    return True


@piece(inline=True)
def observables(model, p, zd, vd, y0, y1, y2, y3):
    """The observables of the state ``(y0, y1, y2, y3)`` (the spring's: ``(y0, y1)``, the
    others ignored) as a tuple in the order of the ``O_*`` indices (see :func:`observe`).

    Scalars in, scalars out: the sampled-column pass writes them straight into its rows
    (through a state array, LLVM reloaded ``p`` after every store: 1.4x the pass's time).
    """
    if model == MODEL_SPRING:
        defl = y0
        hd = y1 - vd
        theta = 0.0
        y2p = 0.0
        y2d = 0.0
    else:
        defl = p[HQA] * y0 + p[HQB] * y1
        hd = p[HQA] * y2 + p[HQB] * y3 - vd
        theta = p[TH_A] * y0 + p[TH_B] * y1
        y2p = p[YQA] * y0 + p[YQB] * y1
        y2d = p[YQA] * y2 + p[YQB] * y3
    h = defl - zd
    fs, _ = static_force(model, h, p)
    fd, _, _ = drainage(model, h, hd, p)
    fz = fs + fd
    fy = 0.0 if model == MODEL_SPRING else -(p[XI] + p[ZETA] * fz * fz) * y2d
    return h, hd, defl, theta, fz, y2p, y2d, fy, zd


@piece()
def observe(model, p, zd, vd, y, o):
    """Fill ``o`` with the observables of state ``y`` (indices ``O_*``).

    separation h, dh/dt, deflection z2, angle theta (0 for the spring),
    normal force Fz, lateral position y2, dy2/dt, friction force Fy, drive z.
    Does not guard h: call only on accepted states. (:func:`observables` computes them.)
    """
    if model == MODEL_SPRING:
        r = observables(model, p, zd, vd, y[0], y[1], 0.0, 0.0)
    else:
        r = observables(model, p, zd, vd, y[0], y[1], y[2], y[3])
    o[O_H], o[O_HDOT], o[O_DEFL], o[O_THETA], o[O_FZ], o[O_Y2], o[O_Y2DOT], o[O_FY], \
        o[O_Z] = r


@piece()
def contact_frequency(model, p, zd, y):
    """Angular frequency of the contact mode, ``sqrt((k - Fs'(h)) * mobility)`` [rad/s].

    Also returns the contact stiffness ``kappa = -Fs'(h)`` [N/m] (positive in
    the repulsive wall, zero at the strongest attraction h = z0).
    """
    if model == MODEL_SPRING:
        h = y[0] - zd
    else:
        h = p[HQA] * y[0] + p[HQB] * y[1] - zd
    _, dfs = static_force(model, h, p)
    kappa = -dfs
    w2 = (kappa + p[K_EFF]) * p[MOBILITY]
    return math.sqrt(w2) if w2 > 0.0 else 0.0, kappa


@piece()
def error_frequency(model, p, zd, vd, y):
    """Rate converting velocity errors into position errors [1/s] (error control).

    A velocity error ``dv`` in a mode of angular frequency ``w`` is an
    amplitude error ``dv / w``. The integrator's velocity tolerance is
    ``atol * VELOCITY_TOLERANCE_FACTOR`` times ``w = sqrt((k + max(kappa, 0)) mobility)``
    (the free mode out of contact, the contact mode in contact; kappa =
    -Fs'(h)), so a slow bounce is never under-resolved. Load-dependent
    friction scales the factor down per run
    (:func:`afmforce.dynamics.simulate.load_friction_controls`).
    """
    if model == MODEL_SPRING:
        h = y[0] - zd
        hd = y[1] - vd
    else:
        h = p[HQA] * y[0] + p[HQB] * y[1] - zd
        hd = p[HQA] * y[2] + p[HQB] * y[3] - vd
    fs, dfs = static_force(model, h, p)
    kappa = -dfs if dfs < 0.0 else 0.0
    w = math.sqrt((kappa + p[K_EFF]) * p[MOBILITY])
    return w


@piece()
def ringing_amplitude(model, p, vd, y, f, wc):
    """Amplitude of the contact mode [m]: ``sqrt((h'/wc)^2 + (h''/wc^2)^2)``.

    In a quasi-static contact h' and h'' vanish; what remains is the ringing
    (h'' from the state derivative ``f``).
    """
    if model == MODEL_SPRING:
        hd = y[1] - vd
        hdd = f[1]
    else:
        hd = p[HQA] * y[2] + p[HQB] * y[3] - vd
        hdd = p[HQA] * f[2] + p[HQB] * f[3]
    a1 = hd / wc
    a2 = hdd / (wc * wc)
    return math.sqrt(a1 * a1 + a2 * a2)


@njit(cache=True, error_model="numpy")
def observe_array(model, p, zd, vd, Y):
    """:func:`observe` for every row of ``Y`` (drive ``zd``, ``vd`` per row)."""
    n = Y.shape[0]
    out = np.empty((n, N_OBS))
    for i in range(n):
        observe(model, p, zd[i], vd[i], Y[i], out[i])
    return out


def pack_spring(*, spring_constant, mass, radius, hamaker, z0, viscosity, h_guard,
                quality_factor=None) -> np.ndarray:
    """Parameter vector of the simple-spring model (eq 1; lever damping of issue 23)."""
    p = np.zeros(P_SIZE)
    p[AR] = hamaker * radius
    p[Z0] = z0
    p[CD] = 6.0 * math.pi * viscosity * radius**2 / 4.0
    p[H_GUARD] = h_guard
    p[K] = spring_constant
    p[INV_M] = 1.0 / mass
    p[MOBILITY] = 1.0 / mass
    p[K_EFF] = spring_constant
    p[C00] = spring_damping(spring_constant, mass, quality_factor)
    return p


def beam_matrices(cantilever, m_joint: float, m_base: float):
    """Dynamical matrix ``A = -T^T K T`` and the masses (m_alpha, m_beta) (spec section 5).

    ``m_alpha = m_joint + m_base/4``, ``m_beta = m_base/3``.
    """
    L1 = cantilever.L1
    T = np.array([[1.0, 0.0], [-1.5 / L1, 1.0 / L1]])
    A = -T.T @ cantilever.beam_stiffness @ T
    return A, (m_joint + m_base / 4.0, m_base / 3.0)


def beam_couplings(cantilever):
    """(dh/dq, dy2/dq, dtheta/dq) as 2-vectors (eqs 24-27)."""
    c, s = math.cos(cantilever.theta0), math.sin(cantilever.theta0)
    a, b, L1 = cantilever.a, cantilever.b, cantilever.L1
    hq = np.array([c - 1.5 * a / L1, a / L1])
    yq = np.array([s - 1.5 * b / L1, b / L1])
    tq = np.array([-1.5 / L1, 1.0 / L1])
    return hq, yq, tq


def pack_beam(cantilever, *, m_joint, m_base, radius, hamaker, z0, viscosity, xi, zeta,
              h_guard, quality_factor=None, quality_factor_2=None) -> np.ndarray:
    """Parameter vector of the inclined-beam model (eqs 22-28; lever damping of issue 23)."""
    A, (ma, mb) = beam_matrices(cantilever, m_joint, m_base)
    hq, yq, tq = beam_couplings(cantilever)
    p = np.zeros(P_SIZE)
    p[AR] = hamaker * radius
    p[Z0] = z0
    p[CD] = 6.0 * math.pi * viscosity * radius**2 / 4.0
    p[H_GUARD] = h_guard
    p[XI] = xi
    p[ZETA] = zeta
    p[A00], p[A01], p[A10], p[A11] = A[0, 0], A[0, 1], A[1, 0], A[1, 1]
    p[INV_MA], p[INV_MB] = 1.0 / ma, 1.0 / mb
    p[HQA], p[HQB] = hq
    p[YQA], p[YQB] = yq
    p[TH_A], p[TH_B] = tq
    p[MOBILITY] = hq[0] ** 2 / ma + hq[1] ** 2 / mb
    p[K_EFF] = cantilever.spring_constant
    C = beam_damping(A, (ma, mb), quality_factor, quality_factor_2)
    p[C00], p[C01], p[C10], p[C11] = C[0, 0], C[0, 1], C[1, 0], C[1, 1]
    return p
