"""Error control of the compiled Radau IIA integrator: error scale, embedded error
estimate, step-size controller, step bounds and the in-contact damping step.

* The error norm is the RMS of ``err / (atol + rtolv |y|)``; the velocity
  tolerance follows the model's own frequency (:func:`velocity_atol`).
* Embedded error estimate filtered through ``(I - h gamma0 J)^-1`` (so stiff
  components do not spoil it), with the improved estimate after a rejection
  (Hairer & Wanner IV.8).
* Step-size control with the predictive (Gustafsson) controller; no increase
  right after a rejection, no change below a factor 1.2 when the factors can be
  reused (RADAU5).

Compiled as described in :mod:`._radau_newton`; the scalar-only controller
functions are inlined by numba itself (``inline="always"``: nothing to compile
separately, no arrays to count references of).
"""

from __future__ import annotations

import math

from numba import njit

from ._jit import fmax, fmin, piece
from ._linalg import _rms, _solve_real
from ._radau_tableau import (E1, E2, E3, MAX_FACTOR, MU_REAL, NEWTON_MAXITER, S_NFEV,
                             W_VFAC)
from ._locate import E_IN_CONTACT, E_LAST_OUT, E_RING_AMP, E_SPIKE_CYCLES, E_SPIKE_T, E_SPIKE_WINDOW
from .models import HQA, HQB, K_EFF, contact_frequency, error_frequency, rhs, ringing_amplitude


@piece(inline=True)
def velocity_atol(model, p, drive, t, y, atol, work):
    """Absolute tolerance of the velocities at ``(t, y)``: ``atol[n-1]``, or
    ``atol[0] * work[W_VFAC] * error_frequency`` where that is smaller."""
    av = atol[y.shape[0] - 1]
    if work[W_VFAC] > 0.0:
        zt = drive.z_a + drive.v * (t - drive.t_a)
        av = fmin(av, atol[0] * work[W_VFAC] * error_frequency(model, p, zt, drive.v, y))
    return av


@piece(inline=True)
def error_scale(y, atol, av, rtolv, scale):
    """``scale = atol + rtolv |y|`` (velocities: ``av``)."""
    n = y.shape[0]
    for i in range(n):
        ai = atol[i] if i < n // 2 else av
        scale[i] = ai + abs(y[i]) * rtolv[i]


@piece(inline=True)
def _filtered_error(h, f, J, Sr, det_r, Z, err):
    """``err = (mu_r/h I - J)^-1 (f + (e . Z) / h)``: the embedded error estimate of the step
    whose stages are ``Z`` (``f`` the derivative at its start, or at ``y + err``
    for the improved estimate), filtered so stiff components do not spoil it."""
    for i in range(err.shape[0]):
        ze = (E1 * Z[0, i] + E2 * Z[1, i] + E3 * Z[2, i]) / h
        err[i] = f[i] + ze
    _solve_real(J, MU_REAL / h, Sr, det_r, err)


@piece(inline=True, cached=True)
def error_norm(h, y, fcur, J, Sr, det_r, Z, atol, av, rtolv, ytmp, err, scale):
    """Error norm of the step of size ``h`` from ``y`` whose stages are ``Z``.

    Also fills ``ytmp`` with the new state ``y + Z_3``, ``err`` with the filtered
    error and ``scale`` with the error scale over both ends of the step.
    """
    n = y.shape[0]
    for i in range(n):
        ytmp[i] = y[i] + Z[2, i]
        ai = atol[i] if i < n // 2 else av
        scale[i] = ai + fmax(abs(y[i]), abs(ytmp[i])) * rtolv[i]
    _filtered_error(h, fcur, J, Sr, det_r, Z, err)
    return _rms(err, scale)


@piece(inline=True, cached=True)
def improved_error_norm(model, p, drive, t, h, y, J, Sr, det_r, Z, err, scale, yst, fnew,
                        stats, err_norm):
    """After a rejection: the estimate again with f evaluated at ``y + err`` (Hairer &
    Wanner IV.8); ``err_norm`` unchanged if that state is inadmissible."""
    for i in range(y.shape[0]):
        yst[i] = y[i] + err[i]
    if not rhs(model, p, drive.z_a + drive.v * (t - drive.t_a), drive.v, yst, fnew):
        return err_norm
    stats[S_NFEV] += 1
    _filtered_error(h, fnew, J, Sr, det_r, Z, err)
    return _rms(err, scale)


@njit(cache=True, error_model="numpy", inline="always")
def safety_factor(n_iter):
    """Step-size safety factor: 0.9, less when Newton needed many iterations."""
    return 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)


@njit(cache=True, error_model="numpy", inline="always")
def controller(h_abs, h_abs_old, err_old, err_norm):
    """Step-size factor of the predictive (Gustafsson) controller, before safety and limits."""
    if h_abs_old > 0.0 and err_old > 0.0 and err_norm > 0.0:
        mult = h_abs / h_abs_old * (err_old / err_norm) ** 0.25
    else:
        mult = 1.0
    if err_norm > 0.0:
        return fmin(1.0, mult) * err_norm ** -0.25
    return MAX_FACTOR


@njit(cache=True, error_model="numpy", inline="always")
def next_step_factor(h_abs, h_abs_old, err_old, err_norm, safety, rejected, recompute_jac):
    """Factor for the step after an accepted one."""
    factor = fmin(MAX_FACTOR, safety * controller(h_abs, h_abs_old, err_old, err_norm))
    if rejected:                    # RADAU5: no increase right after a rejection
        factor = fmin(factor, 1.0)
    if not recompute_jac and factor < 1.2:
        factor = 1.0
    return factor


@piece(inline=True)
def max_step(model, p, drive, t, t_end, y, hmax_frac, hmax_dz):
    """Longest step from ``(t, y)``: the drive may move at most
    ``max(hmax_frac * h, hmax_dz)`` (h the separation), so no surface event is
    stepped over; a dwell (v = 0) may step to its end."""
    v = drive.v
    if v == 0.0:
        return t_end - t
    zt = drive.z_a + v * (t - drive.t_a)
    if model == 0:
        hsep = y[0] - zt
    else:
        hsep = p[HQA] * y[0] + p[HQB] * y[1] - zt
    return fmax(hmax_frac * hsep, hmax_dz) / abs(v)


@piece(inline=True)
def damping_step(model, p, drive, t, t_end, y, fcur, ev, damp_cycles, damp_kappa, h_max):
    """Shortest step of the in-contact ringing treatment at ``(t, y)`` (0: none).

    Once the probe has stayed in contact without bouncing out for ``spike_window``,
    or for ``ev[E_SPIKE_CYCLES]`` contact cycles both after contact and after the
    last spike maximum (the spike has stopped growing), where the contact stiffness ``kappa = -Fs'(h)`` exceeds
    ``damp_kappa * k`` and the ringing is below ``ev[E_RING_AMP]``: ``damp_cycles
    / omega_c`` (omega_c the contact mode), at most ``h_max`` and the rest of
    the segment. See :func:`afmforce.dynamics.radau.integrate_segment`.
    """
    if not (damp_cycles > 0.0 and ev[E_IN_CONTACT] == 1.0):
        return 0.0
    t_in = t - ev[E_LAST_OUT]
    if not t_in >= 0.0:
        return 0.0
    zt = drive.z_a + drive.v * (t - drive.t_a)
    wc, kappa = contact_frequency(model, p, zt, y)
    if t_in < ev[E_SPIKE_WINDOW]:
        # inside the spike window: resolved until the spike maximum has not grown
        # for E_SPIKE_CYCLES contact cycles (and as long after contact)
        quiet = ev[E_SPIKE_CYCLES] * 2.0 * math.pi
        if not (wc > 0.0 and t_in * wc >= quiet and (t - ev[E_SPIKE_T]) * wc >= quiet):
            return 0.0
    if kappa >= damp_kappa * p[K_EFF] and wc > 0.0 and \
            ringing_amplitude(model, p, drive.v, y, fcur, wc) <= ev[E_RING_AMP]:
        return fmin(fmin(damp_cycles / wc, h_max), t_end - t)
    return 0.0


@piece(inline=True, cached=True)
def left_hard_contact(model, p, drive, t_new, y_new, damp_kappa):
    """Whether the state ``y_new`` at ``t_new`` has left the stiff contact where damping
    steps are allowed (contact stiffness below ``damp_kappa * k``)."""
    zt = drive.z_a + drive.v * (t_new - drive.t_a)
    _, kappa = contact_frequency(model, p, zt, y_new)
    return kappa < damp_kappa * p[K_EFF]
