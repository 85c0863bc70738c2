"""Small real force curves shipped with afmforce, for runnable examples.

Every file here was recorded on a real instrument by another group and is
published under the MIT licence (or CC0) in the test data of afmformats or
PyFMlab; see ``docs/analysis.md``. They make every command of the README run
as written on a fresh install::

    afmforce analyze --example asylum-air
    afmforce analyze --example list

>>> from afmforce import datasets
>>> from afmforce.io import load
>>> curve = load(datasets.path("jpk-cell"))[0]
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..errors import ParameterError

__all__ = ["Dataset", "DATASETS", "path", "FIT_EXAMPLES", "SWEEP_EXAMPLE", "fit_example",
           "THERMAL_EXAMPLES", "thermal_example"]

_HERE = Path(__file__).resolve().parent / "data"


@dataclass(frozen=True)
class Dataset:
    """One shipped sample file.

    Attributes
    ----------
    name : str  identifier (``--example NAME``)
    filename : str  file in the package
    description : str  what it shows
    source : str  where it comes from, and its licence
    """

    name: str
    filename: str
    description: str
    source: str


#: The shipped sample files.
DATASETS: dict[str, Dataset] = {d.name: d for d in (
    Dataset("asylum-air", "asylum-mfp3d_SiN-tip_air.ibw",
            "Asylum MFP-3D, SiN tip in air: hard contact with jump-in and pull-off; k 1.1841 N/m, 44.99 nm/V, "
            "thermal resonance 23.3 kHz in the wave note",
            "afmformats tests/data fmt-igor-fd_SiN_FD_plot.ibw (CC0; afmformats is MIT)"),
    Dataset("jpk-cell", "jpk_cellhesion_spot3.jpk-force",
            "JPK CellHesion on a biological sample: soft contact, adhesion on the retract",
            "afmformats tests/data, MIT"),
    Dataset("jpk-calibration", "jpk_calibration-curve_raw-volts.jpk-force",
            "JPK calibration curve in raw volts, no sensitivity stored: the compliance slope gives it",
            "afmformats tests/data, MIT"),
    Dataset("workshop", "afm-workshop_single.csv", "AFM Workshop CSV export (force, no time base)",
            "afmformats tests/data, MIT"),
    Dataset("bruker-gel", "bruker-nanoscope_PyFMlab_Egel4_00025.spm",
            "Bruker NanoScope binary force curve on a gel (soft contact)", "DyNaMo-INSERM/PyFMlab tests, MIT"),
)}


def path(name: str) -> Path:
    """The shipped file ``name`` (see :data:`DATASETS`).

    Raises
    ------
    ParameterError
        Unknown name.
    """
    try:
        return _HERE / DATASETS[name].filename
    except KeyError:
        raise ParameterError(f"unknown example {name!r}; choose one of {', '.join(DATASETS)}") from None


#: SIMULATED curves for ``afmforce fit --example NAME`` (written by ``docs/make_datasets.py``):
#: name -> (description, files). ``speeds``: the Fig 5 beam (R 100 nm) with xi = 0.01 kg/s at
#: 0.5, 1, 2 and 5 um/s, recorded by the virtual AFM (noise 0.01 nm, random zero, offset, drift).
FIT_EXAMPLES: dict[str, tuple[str, tuple[str, ...]]] = {
    "speeds": ("SIMULATED Fig 5 beam, xi = 0.01 kg/s, at 0.5, 1, 2, 5 um/s (afmforce raw text)",
               tuple(f"fit-speed-{i}.txt" for i in range(1, 5))),
}
#: A small sweep file (``afmforce sweep --example``): 4 speeds x 3 friction coefficients.
SWEEP_EXAMPLE = _HERE / "sweep-example.toml"


def fit_example(name: str) -> list[Path]:
    """The shipped curves of :data:`FIT_EXAMPLES` ``[name]``.

    Raises
    ------
    ParameterError
        Unknown name.
    """
    try:
        return [_HERE / f for f in FIT_EXAMPLES[name][1]]
    except KeyError:
        raise ParameterError(f"`example` {name}: unknown; choose one of {', '.join(FIT_EXAMPLES)}") from None


#: Thermal spectra for ``afmforce calibrate thermal --example NAME``: name -> (description, file).
THERMAL_EXAMPLES: dict[str, tuple[str, str]] = {
    "virtual-air": ("SIMULATED spring probe in air: k = 0.2 N/m, f0 = 20 kHz, Q = 50, 295 K, 64 averages "
                    "(docs/make_datasets.py)", "thermal-virtual-air.psd"),
    "jpk-water": ("JPK NanoWizard thermal noise data, PFQNM-LC-A lever in water at 25 C; the vendor's k "
                  "45.88 mN/m, f 24.25 kHz, Q 2.05 (DyNaMo-INSERM/PyFMlab tests, MIT; 0-80 kHz)",
                  "thermal-jpk-water.tnd"),
}


def thermal_example(name: str) -> Path:
    """The shipped thermal spectrum of :data:`THERMAL_EXAMPLES` ``[name]``.

    Raises
    ------
    ParameterError
        Unknown name.
    """
    try:
        return _HERE / THERMAL_EXAMPLES[name][1]
    except KeyError:
        raise ParameterError(f"unknown thermal example {name!r}; choose one of {', '.join(THERMAL_EXAMPLES)}") from None
