"""The record of one surface force law (:class:`SurfaceLaw`) and of its parameters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping

__all__ = ["LawParameter", "SurfaceLaw"]


@dataclass(frozen=True)
class LawParameter:
    """One parameter of a law: a key of :data:`afmforce._fields.QUANTITIES` and what the
    configuration and the fit need beyond its unit and range.

    Attributes
    ----------
    name : str
        Key of ``QUANTITIES`` (unit, dimension, help, valid range) and flat name of the
        simulation configuration (``afmforce simulate --<name>``).
    default : float
        Default [SI]; the law's :attr:`SurfaceLaw.active` is False at the defaults (the paper's
        model is unchanged unless a user asks for the law).
    domain : str
        What the configuration checks on construction (:mod:`afmforce.dynamics._part`); default
        ``range``: the quantity's valid range (a law's parameters are refused out of it in
        Python as on the command line).
    fit : tuple of (scale, rel_step, abs_step) or None
        The parameter can be freed in the dynamic fit (``--free NAME``): the optimiser's scale
        and the forward-difference step ``max(rel_step |x|, abs_step)`` [SI]; bounds are the
        quantity's range. None: not fitted.
    """

    name: str
    default: float
    domain: str = "range"
    fit: tuple[float, float, float] | None = None


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
    pack : callable
        ``pack(r_eff, values) -> tuple of float``: the law's slots of the packed parameter
        vector (their number is :attr:`n_slots`), read by :attr:`kernel`.
    kernel : callable
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
    """

    name: str
    title: str
    parameters: tuple[LawParameter, ...]
    force: Callable[[Any, float, Mapping[str, float]], tuple[Any, Any]]
    active: Callable[[Mapping[str, float]], bool]
    pack: Callable[[float, Mapping[str, float]], tuple[float, ...]]
    kernel: Callable
    n_slots: int
    reach: Callable[[Mapping[str, float]], float]
    reference: str
    validity: str
    example: Mapping[str, float]

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The keys of its parameters, in order."""
        return tuple(p.name for p in self.parameters)
