"""Each afmforce kernel is compiled once, not once per type of its callers' arguments (issue 35, item 4).

numba types a constant that compiled code passes to another compiled function as a literal
(``Literal[int](0)``, ``Literal[bool](True)``) and compiles the callee once for each such type: the
same kernel called with ``0`` from one caller and an ``int64`` variable from another was compiled
twice or three times (``_robust_line``, ``_polyfit_qr``, ``pairwise_sum``, ...: ~10 s of CPU on
an empty cache). Callers pass ``np.int64(0)``, ``np.bool_(True)`` instead, which numba types as
``int64``/``bool`` (the same values: the compiled code and its numbers do not change).
``benchmarks/kernel_signatures.py`` measures what is compiled (numba's compile events) on an
empty cache; this test keeps the rule without compiling anything. What it cannot see: a counter
that starts at a literal ``0`` and is passed after a loop may be compiled for ``Literal[int](0)``
too, depending on the order numba types the function in (``_repulsive_onset`` and
``compliance_line`` did; the integrator's counters do not): the measurement finds those.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

import afmforce
from afmforce._jitcache import kernel_source_files

PACKAGE = Path(afmforce.__file__).resolve().parent


def _is_kernel(fn: ast.FunctionDef) -> bool:
    for dec in fn.decorator_list:
        f = dec.func if isinstance(dec, ast.Call) else dec
        name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", "")
        if "jit" in name or name == "piece":
            return True
    return False


def _kernels(tree: ast.Module):
    return [n for n in tree.body if isinstance(n, ast.FunctionDef) and _is_kernel(n)]


def _is_int(node: ast.expr) -> bool:
    """A bare int or bool constant (``0``, ``-1``, ``True``)."""
    inner = node.operand if isinstance(node, ast.UnaryOp) else node
    return isinstance(inner, ast.Constant) and isinstance(inner.value, (bool, int))


def _int_names(tree: ast.Module) -> set[str]:
    """Module-level names bound to an int or bool constant (numba types such a global as a literal
    too; ``np.int64(6)`` as ``int64``)."""
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None and _is_int(node.value):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names |= {t.id for t in targets if isinstance(t, ast.Name)}
    return names


def literal_calls(root: Path = PACKAGE) -> list[str]:
    """Calls, inside afmforce's compiled functions, of afmforce's compiled functions with a bare int
    or bool constant as an argument: ``file:line caller -> call``. The files scanned are those a kernel
    may reach (:func:`afmforce._jitcache.kernel_source_files`)."""
    trees = {p: ast.parse(p.read_text(encoding="utf-8")) for p in kernel_source_files(root)}
    names = {fn.name for tree in trees.values() for fn in _kernels(tree)}
    found = []
    for path, tree in trees.items():
        constants = _int_names(tree)
        for fn in _kernels(tree):
            for call in ast.walk(fn):
                if not isinstance(call, ast.Call):
                    continue
                callee = getattr(call.func, "id", None) or getattr(call.func, "attr", None)
                if callee not in names:
                    continue
                args = list(call.args) + [k.value for k in call.keywords]
                if any(_is_int(a) or (isinstance(a, ast.Name) and a.id in constants) for a in args):
                    found.append(f"{path.relative_to(root)}:{call.lineno} {fn.name} -> {ast.unparse(call)}")
    return found


def test_no_kernel_passes_a_literal_to_a_kernel():
    assert literal_calls() == []


def test_the_scan_finds_a_literal_argument(tmp_path):
    """The scan itself: a kernel calling a kernel with ``0``, ``-1``, ``True`` or a module's int
    constant is found; with ``np.int64(0)`` it is not (a scan that finds nothing proves nothing)."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "a.py").write_text(
        "from numba import njit\n"
        "N = 6\n"
        "@njit(cache=True)\n"
        "def k(a, lo, flag):\n"
        "    return a[lo] if flag else 0.0\n"
        "@njit(cache=True)\n"
        "def bad(a):\n"
        "    return k(a, 0, True) + k(a, -1, flag=False) + k(a, N, np.bool_(True))\n"
        "@njit(cache=True)\n"
        "def good(a):\n"
        "    return k(a, np.int64(0), np.bool_(True))\n"
        "def python(a):\n"
        "    return k(a, 0, True)\n")
    found = literal_calls(pkg)
    assert len(found) == 3 and all(" bad -> " in f for f in found)


def test_numpy_scalars_compile_the_signature_python_values_do():
    """What the rule relies on: a kernel called from compiled code with ``np.int64(0)`` and
    ``np.bool_(True)`` and from Python with ``0`` and ``True`` is compiled once; with the bare
    constants from compiled code, twice (numba's literal types)."""
    from numba import njit

    def inner(a, lo, flag):
        return a[lo] if flag else -a[lo]

    a = np.arange(3.0)
    for cast, compiles in ((True, 1), (False, 2)):
        k = njit(inner)
        if cast:
            caller = njit(lambda a: k(a, np.int64(0), np.bool_(True)))
        else:
            caller = njit(lambda a: k(a, 0, True))
        assert caller(a) == 0.0 and k(a, 0, True) == 0.0
        assert len(k.signatures) == compiles, k.signatures
