"""Registry of instrument presets: ``ideal``, ``typical``, ``paper``, ``liquid``.

Each entry says where its numbers come from. Values are SI.

``paper`` -- the Park Scientific Autoprobe of the paper's section 3
--------------------------------------------------------------------
Piezo (Scanmaster tube, Fig 7A). The paper reports one number: the nominal
position shifts the inward constant-compliance line by about 1.5 um from the
outward one at 17 um/s, and the fringes show nonlinearity and a comparable
shift of the runs. It does not separate rate-independent hysteresis from
rate-dependent effects; **decision**: a Prandtl-Ishlinskii loop of 15 % of
the slope spread over 1.5 um (typical of tube scanners, and enough to space
the fringes unevenly) and creep weights ``c = (0.55, 0.10)`` with relaxation
times ``(0.1, 1) s``. On the paper's protocol (:data:`PAPER_FIG7_PROTOCOL`:
at rest in contact, drive out 4 um and back at 17 um/s, constant compliance
over the last 0.3 um; the travel is our assumption) the inward
constant-compliance line then lies 1.5 um beyond the outward one in nominal
position (mean horizontal distance between deflections of 50 and 250 nm;
0.84 um at 6.6 um/s, 0.13 um at 0.4 um/s). The large, fast creep weight is
an effective description of the paper's rate dependence, not a measured
property of the Scanmaster.

Position detector (Figs 7B-C, 8): backlash ``b(v) = 37.3 nm (v / 10 um/s)^0.817``,
the least-squares fit of the paper's +57, +33, +27 and ~0 nm at 17, 8.4,
6.6 and 0.4 um/s (:data:`~afmforce.instrument.detector.PAPER_BACKLASH`);
digitisation step 5 nm (see :mod:`~afmforce.instrument.detector`).

Photodiode: laser diode 670 nm at normal incidence (fringe period 335 nm).
**Decisions** (the paper gives no values): sensitivity 20 nm/V and
saturation at +-7.5 V (+-150 nm), so that, as in Fig 7, the signal saturates
at the top of constant compliance and at the bottom of a 200 nm pull-off
(the paper's jump-out distance); fringe amplitude 1.5 nm-equivalent
(75 mV) and white noise 0.3 nm-equivalent (15 mV), so the fringes are clear
but noisy as in the Fig 7 inset; offset 0.2 V; drift slopes of rms
0.25 V/s (5 nm/s); a 16-bit ADC over +-10 V (0.3 mV, 6 pm).

``typical`` -- a present-day AFM without closed-loop z control
--------------------------------------------------------------
Piezo hysteresis 10 % over 1 um, creep 5 % at 0.5 s; a position sensor
without backlash, 0.1 nm step and 0.05 nm noise; photodiode 50 nm/V, +-9.5 V,
weak fringes (0.4 nm-equivalent), 0.05 nm white and 0.05 nm 1/f noise,
drift 1 nm/s rms; 16-bit ADC over +-10 V.

``liquid`` -- a colloid probe in water (issue 25; docs/liquid.md)
-----------------------------------------------------------------
A closed-loop scanner (no hysteresis or creep: the position sensor reads the true position
with a 0.05 nm step and 0.05 nm noise), a photodiode of 30 nm/V whose response is curved,
``(d + d^2/L)/s`` with L = 3 um (3 % at 100 nm; Attard 2012, "non-linear compliance"), no
fringes (the laser is reflected through water onto a rough colloid-probe substrate), white
noise 0.03 nm and 1/f noise 0.03 nm, drift 0.3 nm/s rms; 16-bit ADC over +-10 V. The drag
on the lever (the "virtual deflection" that separates approach and retract far from the
surface) is physics, not instrument: it is in the trajectory (``lever_drag``).

``ideal`` -- no artefacts: the raw curve reproduces the trajectory exactly
(nominal = measured = true position, the signal is the apparent deflection
in metres, the trajectory's time grid).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..errors import ParameterError
from .acquisition import Acquisition
from .detector import PositionDetector
from .instrument import Instrument
from .noise import Drift, Noise
from .photodiode import Photodiode
from .piezo import Piezo

__all__ = ["Preset", "PRESETS", "get_preset", "PAPER_FIG7_PROTOCOL", "PAPER_PIEZO_SHIFT"]

#: The protocol on which the ``paper`` piezo is calibrated (Fig 7: "the measurement commences
#: with the surfaces in contact, first driving out ... then immediately reversing").
#: travel and compliance (drive in contact) [m] are our assumptions; velocity [m/s] is the paper's.
PAPER_FIG7_PROTOCOL = dict(velocity=17e-6, travel=4e-6, compliance=0.3e-6)
#: Paper section 3.1: "the ~1.5 um shift in Figure 7A" [m].
PAPER_PIEZO_SHIFT = 1.5e-6


@dataclass(frozen=True)
class Preset:
    """One registry entry.

    Attributes
    ----------
    name : str
        Identifier (``--instrument NAME``).
    description : str
        One line for the docs and ``--help``.
    factory : callable
        Builds the :class:`Instrument`.
    source : str
        Where the numbers come from.
    """

    name: str
    description: str
    factory: Callable[[], Instrument]
    source: str


def _ideal() -> Instrument:
    return Instrument(name="ideal")


def _typical() -> Instrument:
    s = 50e-9  # m/V
    return Instrument(
        name="typical",
        piezo=Piezo(hysteresis=0.10, hysteresis_span=1e-6, n_plays=10,
                    creep_amplitudes=(0.05,), creep_times=(0.5,)),
        detector=PositionDetector(step=0.1e-9, noise=0.05e-9),
        photodiode=Photodiode(sensitivity=s, offset=0.1, saturation=9.5,
                              interference_amplitude=0.4e-9 / s, wavelength=670e-9),
        drift=Drift(rate_rms=1e-9 / s),
        noise=Noise(white=0.05e-9 / s, pink=0.05e-9 / s),
        acquisition=Acquisition(adc_bits=16, adc_range=10.0),
    )


def _paper() -> Instrument:
    s = 20e-9  # m/V
    return Instrument(
        name="paper",
        piezo=Piezo(hysteresis=0.15, hysteresis_span=1.5e-6, n_plays=10,
                    creep_amplitudes=(0.55, 0.10), creep_times=(0.1, 1.0)),
        detector=PositionDetector(backlash=37.3e-9, backlash_speed=10e-6, backlash_exponent=0.817,
                                  step=5e-9),
        photodiode=Photodiode(sensitivity=s, offset=0.2, saturation=7.5,
                              interference_amplitude=1.5e-9 / s, wavelength=670e-9, incidence_angle=0.0),
        drift=Drift(rate_rms=5e-9 / s),
        noise=Noise(white=0.3e-9 / s),
        acquisition=Acquisition(adc_bits=16, adc_range=10.0),
    )


def _liquid() -> Instrument:
    s = 30e-9  # m/V
    return Instrument(
        name="liquid",
        detector=PositionDetector(step=0.05e-9, noise=0.05e-9),
        photodiode=Photodiode(sensitivity=s, offset=0.1, saturation=9.5, nonlinearity_length=3e-6),
        drift=Drift(rate_rms=0.3e-9 / s),
        noise=Noise(white=0.03e-9 / s, pink=0.03e-9 / s),
        acquisition=Acquisition(adc_bits=16, adc_range=10.0),
    )


#: The presets, by name.
PRESETS: dict[str, Preset] = {p.name: p for p in (
    Preset("ideal", "no artefacts: the raw curve is the trajectory", _ideal, "definition"),
    Preset("typical", "present-day AFM: mild piezo hysteresis and creep, position sensor, weak fringes",
           _typical, "typical instrument specifications (see afmforce.instrument.presets)"),
    Preset("paper", "the paper's Park Autoprobe: 1.5 um piezo shift at 17 um/s, detector backlash, "
           "5 nm steps, fringes, saturation", _paper,
           "Attard, Carambassis & Rutland, Langmuir 15, 553 (1999), section 3.1, Figs 7-8"),
    Preset("liquid", "colloid probe in water: closed-loop scanner, curved (quadratic) photodiode "
           "response, drift, noise; the lever drag is in the trajectory", _liquid,
           "Attard, arXiv 1212.3019 (2012); Zhu, Attard & Neto, Langmuir 27, 6701 (2011)"),
)}


def get_preset(name: str) -> Instrument:
    """The instrument of a registered preset.

    Raises
    ------
    ParameterError
        For an unknown name (the message lists the valid ones).
    """
    try:
        return PRESETS[name].factory()
    except KeyError:
        raise ParameterError(f"unknown instrument preset {name!r}; choose one of {', '.join(PRESETS)}") from None

