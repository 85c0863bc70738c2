"""Registries of the dynamics' user choices: friction laws (``--friction``) and in-contact
ringing treatments (``--ringing``). Plain Python records; the compiled force laws that use
them are in :mod:`afmforce.dynamics.models`."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["FrictionLaw", "FRICTION_LAWS", "RingingTreatment", "RINGING"]


# --- friction registry ------------------------------------------------------
@dataclass(frozen=True)
class FrictionLaw:
    """One lateral friction law on the probe tip (beam model only).

    Attributes
    ----------
    key : str
        Identifier used by ``SimulationConfig.friction`` and ``--friction``.
    name : str
        Human-readable name.
    formula : str
        The law, with its source.
    parameters : tuple of str
        Config fields it uses (``xi`` [kg/s], ``zeta`` [kg/(s N^2)]).
    """

    key: str
    name: str
    formula: str
    parameters: tuple[str, ...]

    def coefficients(self, xi: float, zeta: float) -> tuple[float, float]:
        """(xi, zeta) as used by the compiled force law ``Fy = -(xi + zeta Fz^2) y2'``."""
        return (xi if "xi" in self.parameters else 0.0,
                zeta if "zeta" in self.parameters else 0.0)


#: Friction laws selectable with ``friction=`` / ``--friction``.
FRICTION_LAWS: dict[str, FrictionLaw] = {
    law.key: law
    for law in (
        FrictionLaw("none", "no friction", "Fy = 0", ()),
        FrictionLaw("viscous", "viscous (Newtonian)", "Fy = -xi dy2/dt  (eq 28)", ("xi",)),
        FrictionLaw("load", "viscous, load dependent",
                    "Fy = -(xi + zeta Fz^2) dy2/dt  (paper, after eq 28)", ("xi", "zeta")),
    )
}


@dataclass(frozen=True)
class RingingTreatment:
    """How the nearly undamped in-contact mode is integrated (see docs/dynamics.md).

    Attributes
    ----------
    key, name, description : str
    damp_cycles : float
        0: resolve the ringing under normal error control; > 0: in contact
        (after the jump-in transient) take steps of at least
        ``damp_cycles / omega_c`` so that Radau's L-stability damps it.
    """

    key: str
    name: str
    description: str
    damp_cycles: float


#: In-contact ringing treatments selectable with ``ringing=`` / ``--ringing``.
RINGING: dict[str, RingingTreatment] = {
    r.key: r
    for r in (
        RingingTreatment(
            "damp", "damped numerically",
            "after the jump-in transient (resolved until the spike has not grown for 30 "
            "contact cycles, at most spike_window after contact) the contact mode is "
            "damped by L-stable Radau steps of >= 50/omega_c; the quasi-static contact "
            "is followed exactly", 50.0),
        RingingTreatment(
            "resolve", "resolved",
            "the contact mode is followed under normal error control until it decays below "
            "the tolerance (costly: ~1e7 steps per simulated second while it rings)", 0.0),
    )
}
