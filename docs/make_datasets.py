"""Write the SIMULATED example files of ``afmforce.datasets`` (``--example`` of ``fit`` and ``sweep``).

* ``fit-speed-1.txt`` ... ``fit-speed-4.txt``: one approach-retract curve per driving speed (0.5, 1, 2,
  5 um/s) of the paper's Fig 5 beam (R = 100 nm) with viscous friction xi = 0.01 kg/s, recorded by
  :func:`afmforce.fit.virtual_curves` (noise 0.01 nm, a random drift, zero and baseline per curve),
  in the afmforce raw text format with the velocity and sample rate in the header;
  ``afmforce fit --example speeds`` fits them (the answer: xi ~ 0.01 kg/s, friction detected).
* ``sweep-example.toml``: a small sweep file (``afmforce sweep --example``).

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
    return paths + [sweep]


if __name__ == "__main__":
    for p in main():
        print(p, p.stat().st_size)
