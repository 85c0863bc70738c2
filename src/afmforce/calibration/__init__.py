"""Calibration of the probe (issue 34; docs/calibration.md): the spring constant, resonance and
quality factor from a thermal spectrum (:mod:`.thermal`), the Sader method (:mod:`.sader`),
thermal spectra of linear lever models (:mod:`.virtual`) and thermal files on disk
(:mod:`.spectrum`: JPK ``.tnd`` and afmforce's own format).

A laws-layer package: pure functions of SI floats and arrays, plus the readers and writer of
spectrum files (which need nothing from :mod:`afmforce.io`).
"""

from .sader import (FLUIDS, GeneralConstant, SaderResult, general_constant, hydrodynamic_function,
                    sader_general, sader_rectangular)
from .spectrum import ThermalSpectrum, read_spectrum, write_spectrum
from .thermal import BOLTZMANN, BUTT_JASCHKE, DEFAULT_TEMPERATURE, ThermalFit, fit_thermal, sho_psd

__all__ = ["FLUIDS", "GeneralConstant", "SaderResult", "general_constant", "hydrodynamic_function",
           "sader_general", "sader_rectangular", "ThermalSpectrum", "read_spectrum", "write_spectrum",
           "BOLTZMANN", "BUTT_JASCHKE", "DEFAULT_TEMPERATURE", "ThermalFit", "fit_thermal", "sho_psd"]
