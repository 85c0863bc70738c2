"""van der Waals attraction with the soft-wall repulsion: the paper's eq 2, a law of the model.

Attard, Carambassis & Rutland, Langmuir 15, 553 (1999), eq 2, for two spheres of radius R::

    Fs(h) = -(A R / 12 h^2) (1 - z0^6 / 4 h^6),   Fs'(h) = (A R / 6) (h^-3 - z0^6 h^-9)

with R = 2 R_eff (:func:`afmforce.forces.vdw_force`). The compiled model computes it in its own
slots (:mod:`afmforce.dynamics.models`); this record declares its parameters once (defaults, the
fit's scales) for every face that reads the registry.
"""

from __future__ import annotations

from ..constants import FIG5
from ..forces import vdw_force, vdw_force_gradient
from ._record import LawParameter, SurfaceLaw


def _force(h, r_eff, v):
    return (vdw_force(h, 2.0 * r_eff, v["hamaker"], v["z0"]),
            vdw_force_gradient(h, 2.0 * r_eff, v["hamaker"], v["z0"]))


LAW = SurfaceLaw(
    name="van_der_waals",
    title="van der Waals attraction with a soft wall, the paper's eq 2",
    parameters=(LawParameter("hamaker", FIG5["hamaker"], "positive", fit=(1e-19, 0.01, 1e-23),
                             note="the data fix A*R: R is given"),
                LawParameter("z0", FIG5["z0"], "positive", fit=(1e-9, 0.005, 1e-13),
                             fit_window=(0.1e-9, 2e-9))),
    force=_force,
    active=lambda v: v["hamaker"] > 0.0,
    pack=None,
    kernel=None,
    n_slots=0,
    reach=lambda v: 200e-9,
    reference="Attard, Carambassis & Rutland, Langmuir 15, 553 (1999), eq 2; Israelachvili, "
              "Intermolecular and Surface Forces, 3rd ed. (2011), chapter 13",
    validity="non-retarded (h < ~10 nm); Derjaguin: R_eff >> h; the soft wall z0 stands for the "
             "contact repulsion",
    example={"hamaker": 1e-20, "z0": 0.35e-9},
)
