"""The check record of the paper report: what an entry is, what gates it, its result.

:mod:`afmforce.paper.numbers` (static) and :mod:`afmforce.paper.numbers_dynamic`
(simulations) hold the entries; both import this module and not each other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

__all__ = ["PaperCheck", "CheckResult", "KINDS", "MAX_TOLERANCE"]

#: Entry kinds and what gates them (see the module docstring).
KINDS = {
    "check": "the paper's value within the stated tolerance, and our reference",
    "bound": "the paper's upper bound",
    "reference": "our independent reference (closed form or scipy solve)",
    "estimate": "shown as the paper's estimate vs our simulation; gated by our reference only",
    "differs": "not reproduced; shown with the reason, not gated",
}
#: Largest relative tolerance against a paper value (issue 12): looser is no check.
MAX_TOLERANCE = 0.25


@dataclass(frozen=True)
class PaperCheck:
    """One recomputable number of the paper.

    Attributes
    ----------
    key : str
        Identifier.
    quantity : str
        What it is, in words.
    source : str
        Equation / figure / section of the paper.
    unit : str
        Display unit of ``paper``, ``reference`` and the computed value.
    paper : float or None
        Value printed in the paper (None where the paper gives none).
    reference : float
        Our closed-form value from the spec (independent computation).
    tolerance : float
        Relative tolerance of the paper's value (its rounding or "about").
    compute : callable
        ``compute() -> float`` in the display unit, through the library.
    note : str
        Decision or remark (spec section 4.2 / 5).
    group : str
        "statics", "forces", "inertia" or "dynamics".
    reference_tolerance : float
        Relative tolerance against ``reference``.
    kind : str
        One of :data:`KINDS`; default "check" with a paper value, else "reference".
    reason : str
        Why ``tolerance`` (the paper's rounding, "about", ...); required for
        "check" and "bound".
    estimate : float or None
        The paper's estimate (kind "estimate"), in ``unit``.
    """

    key: str
    quantity: str
    source: str
    unit: str
    paper: float | None
    reference: float | None
    tolerance: float
    compute: Callable[[], float]
    note: str = ""
    group: str = "statics"
    reference_tolerance: float = 1e-3
    kind: str = ""
    reason: str = ""
    estimate: float | None = None

    @property
    def gate(self) -> str:
        """The entry's kind, resolved ("check" with a paper value, else "reference")."""
        if self.kind:
            return self.kind
        return "check" if self.paper is not None else "reference"


@dataclass(frozen=True)
class CheckResult:
    """A :class:`PaperCheck` evaluated: ours beside the paper's."""

    key: str
    quantity: str
    source: str
    unit: str
    paper: float | None
    reference: float
    ours: float
    relative_difference: float | None
    tolerance: float
    passed: bool | None
    note: str
    group: str
    kind: str = "check"
    reason: str = ""
    estimate: float | None = None
    reference_tolerance: float = 1e-3

    @property
    def gated(self) -> bool:
        """True when the entry passes or fails (``passed`` is not None)."""
        return self.passed is not None

    def to_dict(self) -> dict:
        return dict(self.__dict__, gated=self.gated)
