"""Physical constants and the paper's parameter sets.

Published values live here as module-level data with their source, and are
passed to functions as keyword arguments (pvlib style). All values are SI.

Source: Attard, Carambassis & Rutland, Langmuir 15, 553 (1999), referred to as
"the paper"; equation and figure numbers are the paper's. Decisions where the
paper is ambiguous are those of ``shared/spec/physics.md``.
"""

from __future__ import annotations

import math

#: Hamaker constant [J] (paper section 2.1, below eq 2).
HAMAKER = 5e-19
#: Soft-wall repulsion length [m] (paper section 2.1, below eq 2).
Z0 = 0.35e-9
#: Viscosity of air [Pa s] (paper, after eq 1).
ETA_AIR = 1.8e-5
#: The room temperature [K] (22 C, a laboratory), the one default of every kT when none is given or stored:
#: the thermal calibration (afmforce.calibration.thermal, ``calibrate --temperature``), the tethers'
#: worm-like-chain fits (afmforce.analysis.wlc), the simulation's capillary and steric laws
#: (``simulate/fit/plan --temperature``, the web's simulation control). Why 295 K: the paper's own
#: measurements were "in air ... at room temperature (22.7 C)" (section 3; 295.85 K), within 1 K of it, and it
#: is what every calibration has reported since issue 34 (298.15 K would move each thermal k by 1.1 %). No
#: law the paper reproduces takes a temperature (eqs 1-28: inertia, van der Waals, friction), so no paper
#: number depends on it. Tabulated material data keep the temperature they were measured at
#: (:data:`STANDARD_TEMPERATURE`).
DEFAULT_TEMPERATURE = 295.0
#: The driving speeds ``afmforce plan`` (:func:`afmforce.fit.plan.plan_experiment`) weighs when none are
#: given [m/s]: the paper's range, 0.2-20 um/s.
PLAN_SPEEDS = (0.2e-6, 0.5e-6, 1e-6, 2e-6, 5e-6, 10e-6, 20e-6)
#: The paper's room temperature [K] (section 3: 22.7 C), for reference: its figures take no temperature.
PAPER_ROOM_TEMPERATURE = 273.15 + 22.7
#: 25 C [K]: the temperature of tabulated water data (relative permittivity 78.5, surface tension 0.072 N/m,
#: molar volume 18.07 cm^3/mol), with which :func:`afmforce.forces.debye_length`'s default goes (the Debye
#: length depends on eps T, nearly constant in water from 20 to 30 C).
STANDARD_TEMPERATURE = 298.15

#: Fig 1: simple spring with a colloid probe (section 2.1).
FIG1 = dict(mass=1e-8, spring_constant=0.21, radius=100e-9, velocities=(10e-6, 5e-6, 1e-6))

#: Fig 3 geometry (section 2.2): L0, L1, L2 [m], theta0 [rad], k0 [N/m]; mu [N].
FIG3 = dict(L0=200e-6, L1=2e-6, L2=4e-6, theta0=math.radians(-15.0), k0=0.13)
FIG3_MU = 5e-9
#: Fig 4: friction proportional to load, Fy = +-lambda Fz.
FIG4_LAMBDA = 2.0

#: Figs 5-6 (section 2.3). Decision (spec section 5): B = 3.5e-13 N m^2, not the
#: printed 3.5e-12, so that k0 = 3B/L0^3 = 0.13 N/m and the resonance is 4 kHz.
FIG5 = dict(
    L0=200e-6, L1=2e-6, L2=4e-6, theta0=math.radians(-15.0), B=3.5e-13,
    m_joint=1e-10, m_base=1e-10, radius=100e-9, hamaker=HAMAKER, z0=Z0, viscosity=ETA_AIR,
    xi=0.1, velocity=0.1e-6, start=-40e-9, turn=20e-9, end=-230e-9,
)

#: Figs 9-10 theory (section 3): silicon ultralever on glass in air.
FIG9 = dict(hamaker=HAMAKER, spring_constant=0.21, radius=220e-9, jump_out=200e-9, mass=1e-9)

#: Media at 25 C (issue 25, ``--medium``): viscosity [Pa s] and relative permittivity.
#: Water: 0.890 mPa s, 78.4 (CRC Handbook); air: the paper's 1.8e-5 and 1.0006; ethanol
#: 1.074 mPa s, 24.5; n-hexadecane 3.03 mPa s, 2.05; glycerol 0.934 Pa s, 42.5 (CRC Handbook).
#: A medium that gives a ``hamaker`` carries it too (``--medium`` sets it; an explicit ``--hamaker`` wins):
#: water 1e-20 J, silica or mica surfaces across water (Israelachvili, Intermolecular and Surface
#: Forces, 3rd ed. 2011, ch. 13: 0.6-2.2e-20 J for quartz to mica across water; 0.8-1e-20 J is the
#: usual colloid-probe value), not air's 5e-19 J (the paper's, :data:`HAMAKER`), which is 50x the
#: van der Waals force and an adhesion that holds the lever in contact far into the retract.
MEDIA = {
    "water": dict(viscosity=0.890e-3, permittivity=78.4, hamaker=1e-20),
    "air": dict(viscosity=ETA_AIR, permittivity=1.0006, hamaker=HAMAKER),
    "ethanol": dict(viscosity=1.074e-3, permittivity=24.5),
    "hexadecane": dict(viscosity=3.03e-3, permittivity=2.05),
    "glycerol": dict(viscosity=0.934, permittivity=42.5),
}

#: The Sader method's preset media (``afmforce calibrate --medium``; :data:`afmforce.calibration.sader.FLUIDS`):
#: medium -> (density [kg/m^3], viscosity [Pa s]) at 25 C and 1 atm (CRC Handbook). Water's viscosity
#: is that of :data:`MEDIA`; air's is 18.49 uPa s, not the paper's round 1.8e-5 that the simulations
#: use (MEDIA["air"]): Sader's k scales as eta^a (a ~ 0.7), so the round value would bias k by 2 %.
SADER_FLUIDS: dict[str, tuple[float, float]] = {
    "air": (1.184, 1.849e-5),
    "water": (997.05, MEDIA["water"]["viscosity"]),
}
