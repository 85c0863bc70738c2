"""Short verdict lines of ``afmforce analyze`` (issue 24): at most :data:`MAX_LINE` characters,
agreeing with the table's ``dynamic`` column; the full text is in ``--verbose`` and ``--json``."""

from __future__ import annotations

import re

__all__ = ["MAX_LINE", "dynamic_label", "plain", "clip", "short_verdict"]

#: The longest line of the short verdicts and warnings (the full text: --verbose, --json).
MAX_LINE = 120


def dynamic_label(r) -> str:
    """The table's ``dynamic`` column; the short verdict starts from the same word."""
    if r["contact_kind"] == "none":
        return "-"
    if r["dynamic"]:
        return "yes"
    return "not assessed" if str(r["verdict"] or "").startswith("dynamics not assessed") else "no"


def plain(text: str) -> str:
    """``text`` without its parenthesised details (nested too), on one line."""
    prev = None
    while prev != text:
        prev, text = text, re.sub(r"\s*\([^()]*\)", "", text)
    return " ".join(text.split())


def clip(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: max(limit - 3, 1)].rstrip(" ,;:") + "..."


def short_verdict(r, limit: int = MAX_LINE) -> str:
    """One line that agrees with the table's ``dynamic`` column: why a curve is flagged dynamic, why
    its dynamics were not assessed, or the verdict's first clause (details dropped; ``limit`` chars)."""
    clauses = [c.strip() for c in plain(str(r["verdict"] or "")).split("; ") if c.strip()]
    label = dynamic_label(r)
    if not clauses:
        return ""
    if label == "yes":
        why = next((c for c in clauses if "dynamic" in c), None) or next(
            (c for c in clauses if not c.startswith(("quasi-static", "dynamics not assessed"))), clauses[0])
        text = f"flagged dynamic: {why}"
    elif label == "not assessed":
        reasons = [c.split(": ", 1)[1] for c in clauses[1:] if "not assessed: " in c]
        text = "dynamics not assessed" + (f": {', '.join(dict.fromkeys(reasons))}" if reasons else "")
    else:
        text = clauses[0]
    return clip(text, limit)
