"""The docs' registry tables are the registries (style: docs tables are built from them)."""

from pathlib import Path

import pytest

from afmforce.pipeline import steps_table

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_analysis_steps_table_matches_registry():
    text = (DOCS / "analysis.md").read_text()
    for r in steps_table():
        row = f"| `{r['identifier']}` | {r['name']} | {r['options']} | {r['requires']} | {r['reference']} |"
        assert row in text, f"docs/analysis.md steps table is stale for {r['identifier']!r}"


def test_readme_raw_text_example_reads(tmp_path):
    # the README's afmforce raw text example is a valid file, read into SI
    import re

    from afmforce.rawfile import read_raw

    readme = (DOCS.parent / "README.md").read_text()
    block = re.search(r"```text\n(# format: afmforce-raw.*?)```", readme, re.S).group(1)
    path = tmp_path / "example.txt"
    path.write_text(block)
    curve = read_raw(path)
    assert list(curve.time) == pytest.approx([0.0, 0.5e-3], rel=1e-12)
    assert curve.piezo_nominal[0] == pytest.approx(-500e-9, rel=1e-12)
    assert abs(curve.metadata["sensitivity"] - 45e-9) < 1e-20
    assert curve.deflection_unit == "V"
