"""The static HTML export of a sweep (``results.html``, issue 31 item 5: it replaces ``explore``).

The page embeds the sweep's rows: read back from the file, they equal the result's table
(and the closed forms of the swept functions); the page needs no network and no external
script; a value that is not finite is ``null``; text cannot close the page's script.
"""

from __future__ import annotations

import json
import math
import re

import pytest
import sweep_funcs as f

from afmforce.sweep import build_spec, run_sweep
from afmforce.sweep.page import sweep_payload, write_page


def _embedded(path) -> dict:
    html = path.read_text(encoding="utf-8")
    m = re.search(r"const DATA = (\{.*?\});\n", html, re.S)
    assert m, "no embedded data"
    return json.loads(m.group(1))


@pytest.fixture
def result():
    spec = build_spec(["x=1:4:4", "y=0.5,2"])
    return run_sweep(f.fragile, spec, executor="serial", chunk_size=3)   # x == 3 raises


def test_the_page_embeds_every_run_of_the_table(result, tmp_path):
    paths = result.write(tmp_path, {"x": "m", "product": "m"})
    assert paths["html"] == tmp_path / "results.html"
    data = _embedded(paths["html"])
    assert data["parameters"] == ["x", "y"] and data["n_runs"] == 8 and data["n_failed"] == 2
    assert data["units"]["x"] == "m" and data["units"]["sum"] == ""
    cols = data["columns"]
    assert len(data["rows"]) == 8
    for row in data["rows"]:
        x, y = row[cols.index("x")], row[cols.index("y")]
        if x == 3:       # the failed runs: no outputs (null), the error kept as text
            assert row[cols.index("product")] is None and "cannot handle x = 3" in row[cols.index("error")]
        else:
            assert row[cols.index("product")] == x * y and row[cols.index("sum")] == x + y
            assert row[cols.index("error")] is None
    assert data["fixed"] == []


def test_the_page_is_self_contained_and_its_script_stays_closed(tmp_path):
    spec = build_spec(["x=1,2"], sets=["y=1", "note=</script><b>"])
    result = run_sweep(f.counted, spec, executor="serial")     # note: not an argument, each run fails
    html = write_page(result, tmp_path / "p.html", title="a <sweep>").read_text(encoding="utf-8")
    data = _embedded(tmp_path / "p.html")
    assert ["note", "</script><b>", ""] in data["fixed"] and data["n_failed"] == 2
    assert "<script src" not in html and "<link" not in html
    assert "http://" not in html.replace("http://www.w3.org/2000/svg", "") and "https://" not in html
    assert html.count("</script>") == 1                    # the setting's text is escaped
    assert "<title>a &lt;sweep&gt;</title>" in html


def test_the_payload_is_the_table_with_nan_as_null(result):
    payload = sweep_payload(result, max_rows=3)
    assert payload["n_runs"] == 8 and len(payload["rows"]) == 3
    table = result.table.head(3)
    for row, (_, expected) in zip(payload["rows"], table.iterrows()):
        for name, value in zip(payload["columns"], row):
            want = expected[name]
            if isinstance(want, float) and math.isnan(want):
                assert value is None
            else:
                assert value == want
    json.dumps(payload, allow_nan=False)                   # JSON as it stands
