"""No package imports another package's private modules or names (issue 31, item 5).

A private module (``analysis/_numeric.py``) or a private name (``_DISPLAY``) is its package's
own business; what another package needs is given a public name in a public module
(``afmforce.analysis.robust_line_thin``, ``afmforce.io.parse_meta_args``, ...). Static analysis
of every import in ``src/afmforce``, lazy imports inside functions included. The top level's
base modules (``_fields``, ``_files``, ``_json``, ``_validate``, ``_cores``) are shared by every
layer by design (docs/architecture.md); their private *names* are not.
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src" / "afmforce"


def _module_name(path: Path) -> str:
    return ".".join(path.relative_to(SRC.parent).with_suffix("").parts).removesuffix(".__init__")


def _is_package(name: str) -> bool:
    return SRC.joinpath(*name.split(".")[1:]).is_dir()


def _is_module(name: str) -> bool:
    p = SRC.joinpath(*name.split(".")[1:])
    return p.is_dir() or p.with_suffix(".py").is_file()


def owners(target: str) -> list[str]:
    """The owner of each private part of the dotted ``target``: a private module belongs to its
    package; a private name to its module's package (to the module itself at the top level)."""
    parts = target.split(".")
    out = []
    for i, part in enumerate(parts[1:], 1):
        if not part.startswith("_") or part.startswith("__"):
            continue
        head = ".".join(parts[:i])
        if _is_module(f"{head}.{part}"):
            if head != "afmforce":          # a base module of the top level: shared
                out.append(head)
        elif _is_package(head):
            out.append(head)
        else:
            out.append(head if i == 2 else ".".join(parts[:i - 1]))
    return out


def imported(path: Path) -> list[tuple[int, str]]:
    """(line, dotted name) of every afmforce name an import in ``path`` reaches."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            out += [(node.lineno, f"{target}.{a.name}") for a in node.names]
    return [(line, name) for line, name in out if name.startswith("afmforce.")]


def violations() -> list[str]:
    found = []
    for path in sorted(SRC.rglob("*.py")):
        module = _module_name(path)
        for line, name in imported(path):
            for owner in owners(name):
                if module != owner and not module.startswith(owner + "."):
                    found.append(f"{path.relative_to(SRC.parent)}:{line}: {name} (private to {owner})")
    return found


def test_no_package_imports_another_package_s_private_modules_or_names():
    assert violations() == []


def test_the_rule_sees_what_it_must_refuse():
    """The owners of the forms that were in the code before issue 31 (and some that stay allowed)."""
    assert owners("afmforce.analysis._numeric.robust_line_thin") == ["afmforce.analysis"]
    assert owners("afmforce.io._meta") == ["afmforce.io"]
    assert owners("afmforce.dynamics._helper") == ["afmforce.dynamics"]
    assert owners("afmforce.analysis.maps._DISPLAY") == ["afmforce.analysis"]
    assert owners("afmforce.io.native._hdf5.safe_attr") == ["afmforce.io.native"]
    assert owners("afmforce._fields._DISPLAY") == ["afmforce._fields"]
    assert owners("afmforce.units._registry") == ["afmforce.units"]
    assert owners("afmforce._fields.QUANTITIES") == []        # a base module's public name
    assert owners("afmforce.analysis.robust_line_thin") == []
