"""Every answer of the default pipeline unchanged by a speed-up (issue 35 item 2): this tree against ``--before``.

    python benchmarks/bench_equal_answers_core.py --before main [--real /work/shared/data/real]

Analyses (``analyze(curve)``, default options, as ``afmforce analyze FILE`` does) every curve of every file
in the real-data folder and of virtual-instrument recordings (``afmforce simulate --instrument
typical|paper|ideal|liquid --seed 1|2 --raw``, written once by the ``--before`` tree into ``--sim``), once
with the ``--before`` revision's sources (a ``git worktree`` in a temporary folder) and once with this
tree's, and compares every field of every result (``AnalysisResult.to_dict(arrays=True)``: the steps'
values, their details, the per-sample arrays, the warnings and verdicts): numbers within ``--rtol``
(default 1e-9) relative, every text identical, an error the same error. Prints each difference and exits
with 1 when there is one.
"""

from __future__ import annotations

import argparse
import math
import os
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ("typical", "paper", "ideal", "liquid")


def dump(folders: list[Path], out: Path) -> None:
    """Every curve's answer under this process's afmforce (``PYTHONPATH``), pickled to ``out``."""
    from afmforce.analysis.pipeline import analyze
    from afmforce.io import load

    answers: dict[str, object] = {}
    files = sorted(p for f in folders for p in f.iterdir() if p.is_file() and p.name != "README.md"
                   and not p.name.startswith("err_"))
    for path in files:
        try:
            curves = load(path)
        except Exception as exc:  # noqa: BLE001 -- the same refusal is an equal answer
            answers[f"{path.name}"] = f"load error {type(exc).__name__}: {exc}"
            continue
        for i, curve in enumerate(curves):
            key = f"{path.name}[{i}]"
            try:
                answers[key] = analyze(curve).to_dict(arrays=True)
            except Exception as exc:  # noqa: BLE001
                answers[key] = f"analysis error {type(exc).__name__}: {exc}"
    out.write_bytes(pickle.dumps(answers))
    print(f"{len(answers)} answers from {len(files)} files -> {out}", file=sys.stderr)


def differences(a, b, rtol: float, where: str = ""):
    """Where ``a`` and ``b`` differ (numbers beyond ``rtol`` relative, anything else unequal)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b), key=str):
            if k not in a or k not in b:
                yield f"{where}.{k}: only in {'after' if k not in a else 'before'}"
            else:
                yield from differences(a[k], b[k], rtol, f"{where}.{k}")
    elif isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        if len(a) != len(b):
            yield f"{where}: length {len(a)} -> {len(b)}"
            return
        bad = 0
        for i, (x, y) in enumerate(zip(a, b)):
            for d in differences(x, y, rtol, f"{where}[{i}]"):
                bad += 1
                if bad <= 3:
                    yield d
        if bad > 3:
            yield f"{where}: {bad} elements differ"
    elif isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str) or isinstance(b, str) or a is None or b is None:
        if a != b or type(a) is not type(b):
            yield f"{where}: {_short(a)} -> {_short(b)}"
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
        x, y = float(a), float(b)
        if math.isnan(x) and math.isnan(y):
            return
        if not (x == y or abs(x - y) <= rtol * max(abs(x), abs(y))):
            yield f"{where}: {x!r} -> {y!r} (rel {abs(x - y) / max(abs(x), abs(y)):.3g})"
    elif a != b:
        yield f"{where}: {_short(a)} -> {_short(b)}"


def _short(v, n: int = 300) -> str:
    text = repr(v)
    return text if len(text) <= n else text[:n] + f"... ({len(text)} characters)"


def simulate(tree: Path, folder: Path) -> None:
    """The virtual-instrument recordings (written once, by ``tree``'s afmforce)."""
    folder.mkdir(parents=True, exist_ok=True)
    for preset in PRESETS:
        for seed in (1, 2):
            out = folder / f"sim_{preset}_{seed}.csv"
            if not out.exists():
                subprocess.run([sys.executable, "-m", "afmforce.cli.main", "simulate", "--instrument", preset,
                                "--seed", str(seed), "--raw", str(out), "--no-progress"], check=True,
                               stdout=subprocess.DEVNULL, env={**os.environ, "PYTHONPATH": str(tree / "src")})


def run_dump(tree: Path, folders: list[Path], out: Path) -> float:
    t = time.time()
    subprocess.run([sys.executable, __file__, "--dump", str(out), *map(str, folders)], check=True,
                   env={**os.environ, "PYTHONPATH": str(tree / "src")})
    return time.time() - t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default="main", help="git revision to compare against (default main)")
    ap.add_argument("--real", type=Path, default=Path(os.environ.get("AFMFORCE_REAL_DATA", "/work/shared/data/real")))
    ap.add_argument("--sim", type=Path, default=Path(tempfile.gettempdir()) / "afmforce-equal-sim")
    ap.add_argument("--rtol", type=float, default=1e-9)
    ap.add_argument("--keep", type=Path, help="folder for the two pickles (kept)")
    ap.add_argument("--dump", type=Path, help=argparse.SUPPRESS)
    ap.add_argument("folders", nargs="*", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.dump:
        dump(args.folders, args.dump)
        return 0
    work = args.keep or Path(tempfile.mkdtemp(prefix="afmforce-equal-"))
    work.mkdir(parents=True, exist_ok=True)
    before_pkl, after_pkl = work / "before.pkl", work / "after.pkl"
    with tempfile.TemporaryDirectory(prefix="afmforce-before-") as tmp:
        old = Path(tmp) / "tree"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(old), args.before], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            simulate(old, args.sim)
            folders = [args.real, args.sim]
            run_dump(old, folders, before_pkl)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(old)], check=False)
    run_dump(ROOT, folders, after_pkl)
    before, after = pickle.loads(before_pkl.read_bytes()), pickle.loads(after_pkl.read_bytes())
    bad = 0
    for key in sorted(set(before) ^ set(after)):   # the folder changed between the two dumps
        bad += 1
        print(f"{key}: only {'before' if key in before else 'after'} (files added or removed: run again)")
    for key in sorted(set(before) & set(after)):
        diffs = list(differences(before[key], after[key], args.rtol, key))
        bad += bool(diffs)
        for d in diffs[:10]:
            print(d)
    print(f"{len(before)} curves compared ({args.before} against this tree, rtol {args.rtol:g}): "
          f"{bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
