"""``afmforce analyze``: the tethers' lines under the table (docs/analysis.md, "Tethers on a hard contact")."""

from __future__ import annotations

from ._verdicts import MAX_LINE

__all__ = ["print_tethers"]


def print_tethers(ok, verbose: bool = False) -> None:
    """One line per tether of each curve: its rupture, worm-like-chain fit (L_c, l_p with standard errors, or
    undetermined and why) and loading rate; the reasons clipped to the verdicts' width unless ``verbose``."""
    if "tether_fits" not in ok:
        return
    for _, r in ok.iterrows():
        text = r["tether_fits"]
        if not isinstance(text, str) or not text:
            continue
        for line in text.split(" | "):
            line = f"{r['name']}: {line}"
            print(line if verbose or len(line) <= MAX_LINE + 60 else line[: MAX_LINE + 57].rstrip(" ,;:(") + "...")
