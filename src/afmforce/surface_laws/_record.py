"""The record of one surface force law (:class:`SurfaceLaw`) and of its parameters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping

__all__ = ["LawParameter", "LawSwitch", "SurfaceLaw"]


@dataclass(frozen=True)
class LawParameter:
    """One parameter of a law: a key of :data:`afmforce._fields.QUANTITIES` and what the
    configuration and the fit need beyond its unit and range.

    Attributes
    ----------
    name : str
        Key of ``QUANTITIES`` (unit, dimension, help, valid range) and flat name of the
        simulation configuration (``afmforce simulate --<name>``).
    default : float or None
        Default [SI]; the law's :attr:`SurfaceLaw.active` is False at the defaults (the paper's
        model is unchanged unless a user asks for the law). None (a law of the model only,
        :attr:`SurfaceLaw.compiled` False): given by another parameter (the Debye length by the
        salt concentration, psi2 by psi1).
    domain : str
        What the configuration checks on construction (:mod:`afmforce.dynamics._part`); default
        ``range``: the quantity's valid range (a law's parameters are refused out of it in
        Python as on the command line).
    fit : tuple of (scale, rel_step, abs_step) or None
        The parameter can be freed in the dynamic fit (``--free NAME``): the optimiser's scale
        and the forward-difference step ``max(rel_step |x|, abs_step)`` [SI]; bounds are the
        quantity's range. None: not fitted.
    fit_window : tuple of (lower, upper) or None
        A narrower search window of the fit inside the declared range [SI] (None: the range).
    note : str
        What the fit's description adds to the quantity's help (a degeneracy, e.g.).
    """

    name: str
    default: float | None
    domain: str = "range"
    fit: tuple[float, float, float] | None = None
    fit_window: tuple[float, float] | None = None
    note: str = ""


@dataclass(frozen=True)
class LawSwitch:
    """A text parameter choosing the form of a law (the double layer's boundary condition).

    Attributes
    ----------
    name : str
        Flat name of the configuration and flag (``double_layer``, ``--double-layer``).
    choices : mapping
        Choice -> one line saying what it is (:data:`afmforce.forces.DOUBLE_LAYERS`).
    default : str
        The configuration's default (the law is off at ``off``).
    off : str
        The choice that switches the law off.
    help : str
        One line: what the choice is.
    """

    name: str
    choices: Mapping[str, str]
    default: str
    off: str
    help: str


@dataclass(frozen=True)
class SurfaceLaw:
    """A conservative surface force law F(h), added to the paper's eq 2.

    Attributes
    ----------
    name : str
        Identifier (``hydration``).
    title : str
        One line: what it is.
    parameters : tuple of LawParameter
        Its parameters (keys of ``QUANTITIES``; a key may be shared with another law).
    force : callable
        ``force(h, r_eff, values) -> (F [N], dF/dh [N/m])``: the pure, vectorised numpy law
        (``values``: parameter name -> SI value; ``r_eff``: the Derjaguin radius [m]).
    active : callable
        ``active(values) -> bool``: whether the law acts (False at the defaults).
    pack : callable or None
        ``pack(r_eff, values) -> tuple of float``: the law's slots of the packed parameter
        vector (their number is :attr:`n_slots`), read by :attr:`kernel`.
    kernel : callable or None
        ``kernel(h, p, o) -> (F, dF/dh)``: the same law for the compiled vector field, written
        in the subset of Python that numba compiles (scalars and ``math``); it reads its
        slots ``p[o], p[o + 1], ...``. The dynamics compile it (``afmforce.dynamics.models``).
    n_slots : int
        Number of floats :attr:`pack` returns.
    reach : callable
        ``reach(values) -> float`` [m]: a separation beyond which the force is negligible (the
        static solve scans out to it).
    reference : str
        The published closed form it implements.
    validity : str
        Where the closed form holds.
    example : mapping
        Parameter values at which the law acts, typical of an experiment (the registry's tests
        run every law with them; the docs quote them).
    switch : LawSwitch or None
        A text parameter choosing the law's form (None: the law has one form).

    A law of the model itself (the paper's eq 2, the double layer of issue 25) has no
    ``kernel`` and no ``pack`` (``n_slots`` 0): the compiled model computes it in its own slots
    (:mod:`afmforce.dynamics.models`) and its parameters are the configuration's own fields; its
    record declares them (defaults, domains, fit scales) and its closed form for every face that
    reads the registry (``afmforce simulate``'s flags, the fit's parameters, the docs' table,
    :func:`afmforce.analysis.surface_law_fit.fit_surface_law`).
    """

    name: str
    title: str
    parameters: tuple[LawParameter, ...]
    force: Callable[[Any, float, Mapping[str, float]], tuple[Any, Any]]
    active: Callable[[Mapping[str, float]], bool]
    pack: Callable[[float, Mapping[str, float]], tuple[float, ...]] | None
    kernel: Callable | None
    n_slots: int
    reach: Callable[[Mapping[str, float]], float]
    reference: str
    validity: str
    example: Mapping[str, Any]
    switch: LawSwitch | None = None

    @property
    def compiled(self) -> bool:
        """True for a law of the registry's slots (its own kernel); False for a law the model
        computes itself (eq 2, the double layer)."""
        return self.kernel is not None

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The keys of its parameters, in order."""
        return tuple(p.name for p in self.parameters)
