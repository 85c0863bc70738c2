"""The paper, reproduced: its recomputable numbers (and, later, its figures).

Attard, Carambassis & Rutland, Langmuir 15, 553 (1999).
"""

from .numbers import CHECKS, CheckResult, PaperCheck, all_checks, evaluate_checks

__all__ = ["CHECKS", "PaperCheck", "CheckResult", "all_checks", "evaluate_checks"]
