"""Virtual multi-speed measurements written as raw text files for the fit tests.

The raw text files carry ``deflection_signal [m]`` (the virtual AFM records volts
with noise and drift; :func:`afmforce.fit.virtual_curves` calibrates them back to
metres with the known sensitivity), ``velocity`` and ``sample_rate`` in the
header, and a random zero of position and baseline offset per curve (kept in
``truth.zero_offset`` / ``truth.baseline_offset``).
"""

from __future__ import annotations

from afmforce.fit import virtual_curves
from afmforce.io.native.rawfile import write_raw

SPEEDS = (0.5e-6, 1e-6, 2e-6, 5e-6)
#: Short curves (40 nm of approach) keep a fit affordable.
DRIVE = dict(start=-30e-9, turn=10e-9, end=-230e-9)
NOISE = 0.01e-9


def make_curves(xi: float, seed: int, speeds=SPEEDS, noise: float = NOISE, spacing=0.25e-9, **kw):
    """Curves of the beam model (Fig 5 lever, R 100 nm) at ``speeds``, ``spacing`` [m] per sample."""
    kw.setdefault("sample_rates", [v / spacing for v in speeds])
    return virtual_curves(list(speeds), seed=seed, xi=xi, noise=noise, **{**DRIVE, **kw})


def write_curves(curves, directory):
    """Write ``curves`` as v1.txt, v2.txt, ... in ``directory``; returns the paths."""
    paths = []
    for i, c in enumerate(curves):
        p = directory / f"v{i + 1}.txt"
        write_raw(c, p)
        paths.append(p)
    return paths
