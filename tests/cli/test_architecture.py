"""The layers of docs/architecture.md hold: static import analysis of the source.

Every ``import``/``from ... import`` in ``src/afmforce`` (at any depth, lazy
imports inside functions included) is resolved to the top-level unit it
reaches (``afmforce.analysis.steps`` -> ``analysis``); no unit may reach a unit
its layer never imports.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src" / "afmforce"
DOCS = Path(__file__).resolve().parents[2] / "docs" / "architecture.md"

LAWS = ("constants", "units", "errors", "progress", "_validate", "_fields", "limits", "_files", "_json",
        "_cores", "_jitcache", "_linalg_small", "forces", "friction", "cantilever", "statics", "diagnostics",
        "contact", "calibration", "surface_laws")
IO = ("io",)
ABOVE_DYNAMICS = ("instrument", "io", "analysis", "plotting", "sweep", "paper", "cli")

#: layer name -> (units in it, units it never imports). The docs table shows the same.
RULES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "laws": (LAWS, ("dynamics", "instrument", *IO, "analysis", "plotting", "sweep",
                    "paper", "cli")),
    "dynamics": (("dynamics",), ABOVE_DYNAMICS),
    "instrument": (("instrument",), ("dynamics", "analysis", "plotting", "sweep", "paper", "cli")),
    "io": (IO, ("dynamics", "instrument", "analysis", "plotting", "sweep", "paper", "cli")),
    "analysis": (("analysis",), ("dynamics", "instrument", "plotting", "sweep", "paper", "cli")),
    "plotting": (("plotting",), ("sweep", "paper", "cli")),
    "sweep": (("sweep",), ("paper", "cli")),
    "fit": (("fit",), ("paper", "cli")),
    "paper": (("paper",), ("sweep", "cli")),
    "web": (("web",), ("cli",)),
}


def _unit(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _is_module(unit: str) -> bool:
    return (SRC / unit).is_dir() or (SRC / f"{unit}.py").is_file()


def _module_name(path: Path) -> str:
    return ".".join(path.relative_to(SRC.parent).with_suffix("").parts).removesuffix(".__init__")


def _imported(path: Path) -> set[str]:
    """Every dotted name an import in ``path`` reaches (lazy imports included): the module
    imported and, for ``from X import a``, ``X.a`` too (a submodule when ``a`` is one)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            names |= {target} | {f"{target}.{a.name}" for a in node.names}
    return names


def imports() -> dict[str, set[tuple[str, str]]]:
    """unit -> {(imported unit, file)} for every import of another afmforce unit."""
    out: dict[str, set[tuple[str, str]]] = {}
    for path in SRC.rglob("*.py"):
        unit = _unit(_module_name(path))
        for t in _imported(path):
            if t.startswith("afmforce.") and _unit(t) and _is_module(_unit(t)) and _unit(t) != unit:
                out.setdefault(unit, set()).add((_unit(t), str(path.relative_to(SRC))))
    return out


GRAPH = imports()


def test_the_analysis_sees_imports():
    # the analysis must find known edges, else the rules below pass vacuously
    assert any(u == "dynamics" for u, _ in GRAPH["sweep"])
    assert any(u == "dynamics" for u, _ in GRAPH["cli"])
    assert any(u == "errors" for u, _ in GRAPH["forces"])


@pytest.mark.parametrize("layer", list(RULES))
def test_layer_never_imports(layer):
    units, forbidden = RULES[layer]
    bad = sorted((f, u) for unit in units for u, f in GRAPH.get(unit, ()) if u in forbidden)
    assert not bad, f"layer {layer} imports what it never may: " + ", ".join(f"{f} -> {u}" for f, u in bad)


def test_nothing_imports_the_cli():
    bad = sorted(f for unit, edges in GRAPH.items() if unit != "cli" for u, f in edges if u == "cli")
    assert not bad, f"only the command line imports afmforce.cli: {bad}"


def test_nothing_but_the_cli_imports_the_web_app():
    """afmforce.web sits at the top beside cli (afmforce serve): no library layer depends on it."""
    assert any(u == "web" for u, _ in GRAPH["cli"])          # cli/serve.py: the analysis sees the edge
    bad = sorted(f for unit, edges in GRAPH.items() if unit not in ("cli", "web") for u, f in edges if u == "web")
    assert not bad, f"only the command line imports afmforce.web: {bad}"


def test_docs_table_states_the_rules():
    text = DOCS.read_text(encoding="utf-8")
    for layer, (_, forbidden) in RULES.items():
        row = re.search(rf"^\| \*\*{layer}\*\* \|.*\| (.*) \|$", text, re.M)
        assert row, f"docs/architecture.md has no row for layer {layer}"
        stated = {s.strip(" `") for s in row.group(1).split(",")}
        assert stated == set(forbidden), f"docs/architecture.md: {layer} never imports {sorted(forbidden)}"


#: Top-level modules (not packages): the laws and base modules only (issue 11, item 4).
TOP_LEVEL = set(LAWS) | {"__init__"}


def test_top_level_holds_the_laws_and_packages():
    """The raw format lives in afmforce.io (io/curve.py, io/native/); no stray modules at the top."""
    modules = {p.stem for p in SRC.glob("*.py")}
    assert modules <= TOP_LEVEL, f"top-level modules outside the laws: {sorted(modules - TOP_LEVEL)}"
    for name in ("raw", "rawfile", "rawmap", "_rawcommon", "_rawhdf5"):
        assert not (SRC / f"{name}.py").exists()
    assert (SRC / "io" / "curve.py").is_file() and (SRC / "io" / "native" / "rawfile.py").is_file()


def _module_edges() -> tuple[dict[str, set[str]], dict[str, Path]]:
    mods = {_module_name(p): p for p in SRC.rglob("*.py")}
    edges = {m: {n for n in _imported(p) if n in mods and n != m} for m, p in mods.items()}
    return edges, mods


def test_no_two_modules_import_each_other():
    """Import cycles between modules (lazy imports included) are broken: e.g. paper.numbers and
    paper.numbers_dynamic share paper.checks, fit.core and fit.uncertainty share fit.problem."""
    edges, mods = _module_edges()
    assert "afmforce.paper.checks" in edges["afmforce.paper.numbers_dynamic"]   # the analysis sees edges
    pairs = sorted({tuple(sorted((a, b))) for a in edges for b in edges[a]
                    if a in edges.get(b, ()) and mods[a].name != "__init__.py" and mods[b].name != "__init__.py"})
    assert not pairs, f"modules that import each other: {pairs}"


def test_no_pyplot_state_in_library_code():
    """Figures are matplotlib.figure.Figure objects: no global pyplot state anywhere."""
    bad = []
    for path in SRC.rglob("*.py"):
        rel = str(path.relative_to(SRC))
        if re.search(r"matplotlib\.pyplot|import pyplot", path.read_text(encoding="utf-8")):
            bad.append(rel)
    assert not bad, f"pyplot used in: {bad}"
    assert (SRC / "plotting" / "__init__.py").is_file()


def test_each_class_name_is_defined_once():
    # issue 11.5: there were two BatchResults (analysis.batch and sweep.results) for two different
    # things; a public class name now means one thing, defined in one module
    where: dict[str, list[str]] = {}
    for path in SRC.rglob("*.py"):
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                where.setdefault(node.name, []).append(_module_name(path))
    assert len(where) > 50  # the walk sees the package
    twice = {name: mods for name, mods in where.items() if len(mods) > 1}
    assert not twice, twice


def test_many_runs_live_in_the_sweep_package_one_module_per_concept():
    # docs/architecture.md, "Many runs": the chunk runner, the parameter sweep, the batch of items
    # and the analysis of many files each have one module; the old homes are gone
    import importlib

    sweep = SRC / "sweep"
    for name in ("chunks", "parametric", "batch", "files", "results"):
        assert (sweep / f"{name}.py").is_file(), name
    for gone in ("analysis/batch.py", "analysis/mapping.py", "sweep/analysis.py", "sweep/engine.py"):
        assert not (SRC / gone).exists(), gone
    assert "Many runs" in DOCS.read_text(encoding="utf-8")
    mod = importlib.import_module("afmforce.sweep")
    assert mod.run_batch.__module__ == "afmforce.sweep.batch"
    assert mod.run_sweep.__module__ == "afmforce.sweep.parametric"
    assert mod.flatten.__module__ == "afmforce.sweep.chunks"
