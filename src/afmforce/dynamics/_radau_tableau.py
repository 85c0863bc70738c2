"""Radau IIA (order 5) coefficients and the layout of the integrator's state arrays.

Shared by the pieces of the compiled integrator: :mod:`.radau` (the step
loop), :mod:`._radau_newton` (stage equations), :mod:`._radau_control`
(error estimate, step size) and :mod:`._sampling` (samples on the grid).
Constants only: numba compiles them into the functions.
The coefficients are those of ``scipy.integrate.Radau`` (Hairer & Wanner,
*Solving Ordinary Differential Equations II*, section IV.8).
"""

from __future__ import annotations

import math
import numpy as np

# --- work array layout (float): the integrator state kept between calls ----
W_T = 0            # current time
W_H = 1            # proposed next step size
W_H_OLD = 2        # previous accepted step size (0: none)
W_ERR_OLD = 3      # previous error norm (0: none)
W_HAS_SOL = 4      # 1 if Q/y_old/t_old/h_last hold the last step's polynomial
W_T_OLD = 5
W_H_LAST = 6
W_CUR_JAC = 7      # 1 if J was evaluated at the current state
W_HAVE_JAC = 8     # 1 if J holds any Jacobian
W_VFAC = 9         # velocity tolerance = atol * W_VFAC * error_frequency (0: atol[n-1] only)
W_SIZE = 10

# --- statistics (int) -------------------------------------------------------
S_STEPS, S_ACCEPTED, S_REJECTED, S_NFEV, S_NJEV, S_NLU, S_DAMPED, S_NEWTON_FAIL = range(8)
S_SIZE = 8

# --- factorisation record (float array `lu` of integrate_segment) ------------
LU_DET_R, LU_DET_CR, LU_DET_CI = 0, 1, 2   # determinants of the real and complex systems
LU_OK = 3                                  # 1 if the factors are valid
LU_H = 4                                   # step size they were made for
LU_SIZE = 5

NEWTON_MAXITER = 6
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0

_S6 = math.sqrt(6.0)
C1 = (4.0 - _S6) / 10.0
C2 = (4.0 + _S6) / 10.0
E1 = (-13.0 - 7.0 * _S6) / 3.0
E2 = (-13.0 + 7.0 * _S6) / 3.0
E3 = -1.0 / 3.0
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)
MU_CR = 3.0 + 0.5 * (3.0 ** (1.0 / 3.0) - 3.0 ** (2.0 / 3.0))
MU_CI = -0.5 * (3.0 ** (5.0 / 6.0) + 3.0 ** (7.0 / 6.0))
T_ = np.array([
    [0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
    [0.25021312296533332, 0.20412935229379994, -0.38294211275726192],
    [1.0, 1.0, 0.0]])
TI_ = np.array([
    [4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
    [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
    [0.50287263494578682, -2.57192694985560522, 0.59603920482822492]])
P_ = np.array([
    [13.0 / 3.0 + 7.0 * _S6 / 3.0, -23.0 / 3.0 - 22.0 * _S6 / 3.0, 10.0 / 3.0 + 5.0 * _S6],
    [13.0 / 3.0 - 7.0 * _S6 / 3.0, -23.0 / 3.0 + 22.0 * _S6 / 3.0, 10.0 / 3.0 - 5.0 * _S6],
    [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0]])
EPS = np.finfo(float).eps
