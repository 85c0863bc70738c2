"""``afmforce analyze``: the liquid step's flags and its line under the table (docs/liquid.md)."""

from __future__ import annotations

import math

from ..constants import MEDIA
from ..forces import DOUBLE_LAYER_LAWS, GEOMETRIES
from ._analyze_options import default as _default
from ._validate import add_field, lazy_help

__all__ = ["liquid_flags", "print_liquid"]


def fmt(v: float) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.4g}"


def liquid_flags(p) -> None:
    """Short forms of the liquid step's options (docs/liquid.md): their choices from the registries
    the step's options record takes them from (``analysis.options.LiquidOptions``), their defaults
    from the record (shown when the help is printed: the record's module loads numba)."""
    g = p.add_argument_group("liquid: colloid probe, drag, drainage, DLVO fit (docs/liquid.md; with --radius)")
    lazy_help(g.add_argument("--medium", default=None, choices=("none", *MEDIA),
                             help="medium of the measurement: a liquid runs the liquid step (--option liquid.medium; "
                                  "default "), lambda: f"{_default('liquid', 'medium')})")
    add_field(g, "permittivity", help="relative permittivity (default: the medium's)")
    lazy_help(g.add_argument("--geometry", default=None, choices=tuple(sorted(GEOMETRIES)),
                             help="probe geometry of the liquid step (default "),
              lambda: f"{_default('liquid', 'geometry')})")
    lazy_help(g.add_argument("--double-layer", dest="double_layer", default=None, choices=DOUBLE_LAYER_LAWS,
                             help="double-layer law of the DLVO fit (default "),
              lambda: f"{_default('liquid', 'double_layer')})")


def print_liquid(ok) -> None:
    """One line per curve the liquid step analysed: drag, and the DLVO fit with standard errors."""
    for _, r in ok.iterrows():
        if not math.isfinite(float(r["drag_offset"])):
            continue
        drag = (f"{fmt(r['lever_drag'])} N s/m" if math.isfinite(float(r["lever_drag"]))
                else "undetermined (see the warning)")
        line = f"{r['name']}: liquid: drag offset {fmt(r['drag_offset'] * 1e9)} nm, lever drag {drag}"
        if math.isfinite(float(r["surface_potential"])):
            line += (f"; DLVO psi {fmt(r['surface_potential'] * 1e3)} +- {fmt(r['surface_potential_se'] * 1e3)} mV, "
                     f"Debye length {fmt(r['debye_length'] * 1e9)} +- {fmt(r['debye_length_se'] * 1e9)} nm, "
                     + (f"A {fmt(r['dlvo_hamaker'])} +- {fmt(r['dlvo_hamaker_se'])} J"
                        if math.isfinite(float(r["dlvo_hamaker"])) else "A undetermined (see the warning)"))
        print(line)
