"""The docs' registry tables are the registries (style: docs tables are built from them)."""

from pathlib import Path

from afmforce.pipeline import steps_table

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_analysis_steps_table_matches_registry():
    text = (DOCS / "analysis.md").read_text()
    for r in steps_table():
        row = f"| `{r['identifier']}` | {r['name']} | {r['options']} | {r['requires']} | {r['reference']} |"
        assert row in text, f"docs/analysis.md steps table is stale for {r['identifier']!r}"
