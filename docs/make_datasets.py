"""Write the SIMULATED example files of ``afmforce.datasets`` (``--example`` of ``fit`` and ``sweep``).

* ``fit-speed-1.txt`` ... ``fit-speed-4.txt``: one approach-retract curve per driving speed (0.5, 1, 2,
  5 um/s) of the paper's Fig 5 beam (R = 100 nm) with viscous friction xi = 0.01 kg/s, recorded by
  :func:`afmforce.fit.virtual_curves` (noise 0.01 nm, a random drift, zero and baseline per curve),
  in the afmforce raw text format with the velocity and sample rate in the header;
  ``afmforce fit --example speeds`` fits them (the answer: xi ~ 0.01 kg/s, friction detected).
* ``sweep-example.toml``: a small sweep file (``afmforce sweep --example``).
* ``thermal-virtual-air.psd``: the thermal spectrum of a spring probe in air (k = 0.2 N/m,
  f0 = 20 kHz, Q = 50, 295 K, 64 averages, white floor 1e-27 m^2/Hz), recorded by
  :func:`afmforce.dynamics.thermal.thermal_spectrum` (``afmforce calibrate thermal --example virtual-air``:
  the answer, k ~ 0.2 N/m).
* ``thermal-jpk-water.tnd``: a copy of ``tests/data/jpk-tnd_PFQNM-water_thermal-noise_0-80kHz.tnd``
  (real, MIT; ``afmforce calibrate thermal --example jpk-water``).

Run ``python docs/make_datasets.py`` to regenerate them.
"""

from __future__ import annotations

from pathlib import Path

from afmforce.fit import virtual_curves
from afmforce.io.native.rawfile import write_raw

OUT = Path(__file__).resolve().parents[1] / "src" / "afmforce" / "datasets" / "data"
SPEEDS = (0.5e-6, 1e-6, 2e-6, 5e-6)
XI = 0.01

SWEEP = """\
# afmforce sweep --config this-file (or: afmforce sweep --example): the paper's Fig 5 run at
# 4 speeds x 3 friction coefficients; values take units, [set] fixes the other parameters.
[grid]
velocity = "0.1um/s:10um/s:4:log"
xi = "0.001,0.01,0.1"

[set]
model = "beam"
"""


def main() -> list[Path]:
    curves = virtual_curves(list(SPEEDS), seed=24, xi=XI, noise=0.01e-9, start=-30e-9, turn=10e-9, end=-60e-9,
                            sample_rates=[v / 0.5e-9 for v in SPEEDS])
    paths = []
    for i, c in enumerate(curves):
        c = c.__class__(**{**c.__dict__, "truth": None}) if getattr(c, "truth", None) is not None else c
        path = OUT / f"fit-speed-{i + 1}.txt"
        path.unlink(missing_ok=True)
        write_raw(c, path)
        paths.append(path)
    sweep = OUT / "sweep-example.toml"
    sweep.write_text(SWEEP, encoding="utf-8")
    return paths + [sweep] + thermal_examples()


#: the virtual lever of ``thermal-virtual-air.psd``
THERMAL_PROBE = dict(spring_constant=0.2, resonance_frequency=20e3, quality_factor=50.0)


def thermal_examples() -> list[Path]:
    import math
    import shutil

    from afmforce.calibration import write_spectrum
    from afmforce.dynamics.parts import SpringProbe
    from afmforce.constants import DEFAULT_TEMPERATURE
    from afmforce.dynamics.thermal import thermal_spectrum

    k, f0, q = (THERMAL_PROBE[n] for n in ("spring_constant", "resonance_frequency", "quality_factor"))
    probe = SpringProbe(spring_constant=k, mass=k / (2 * math.pi * f0) ** 2, quality_factor=q)
    spectrum = thermal_spectrum(probe, temperature=DEFAULT_TEMPERATURE, averages=64, white=1e-27, seed=34, medium="air")
    out = [write_spectrum(OUT / "thermal-virtual-air.psd", spectrum)]
    src = Path(__file__).resolve().parents[1] / "tests" / "data" / "jpk-tnd_PFQNM-water_thermal-noise_0-80kHz.tnd"
    shutil.copyfile(src, OUT / "thermal-jpk-water.tnd")
    return out + [OUT / "thermal-jpk-water.tnd"]


if __name__ == "__main__":
    for p in main():
        print(p, p.stat().st_size)
