"""Same answers before and after a speed-up (issue 35 item 2: no number moves by more than 1e-9 relative).

    python benchmarks/bench_equal_answers.py --before main            # this tree against the rev main
    python benchmarks/bench_equal_answers.py --before HEAD~3 --rtol 1e-9 --files 'jpk*'

Every curve of every file in the shared real set (``$AFMFORCE_REAL_DATA``, default
``/work/shared/data/real``; loaded as ``afmforce analyze FILE`` loads it: no overrides), the soft
files of the per-curve benchmark (``tests/data``, with their ``meta_override.json`` entries, as
``bench_map.py --part curve`` loads them) and the virtual instrument presets (``afmforce simulate
--instrument typical|paper|ideal|liquid``, written once with this tree into a cache folder, then read
by both trees) is analysed by ``analyze(curve)``, every step with its default options, in a
subprocess of each tree (``git archive <rev> src`` unpacked in a temporary folder for ``--before``,
this checkout's ``src`` for the after side). Each result is flattened to ``path -> value``: every
result field, every step's details (the dataclasses, recursively), the warnings' text, the per-sample
arrays; an ``AfmforceError`` is recorded as its message.

The comparison prints each path whose numbers differ by more than ``--rtol`` relative (``|a - b| <=
rtol max(|a|, |b|)``, NaN equal to NaN; integers, booleans and text must be equal), the largest
relative difference seen, and exits 1 on any difference (0 when all agree).
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import math
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
REAL = Path(os.environ.get("AFMFORCE_REAL_DATA", "/work/shared/data/real"))
#: The soft files of ``bench_map.py --part curve`` (tests/analysis/make_nanite_modulus_reference.py's FILES).
BENCH_FILES = ("jpk_cellhesion_spot3.jpk-force", "afmforce-map_jpk-map2x2.h5",
               "asylum-mfp3d_ForceMetric_X60_3_x4_0100.ibw", "bruker-nanoscope_PyFMlab_Egel4_00025.spm",
               "afmformats_jpk-sr_cell1-0008.jpk-force", "ntmdt_gel-in-water.txt",
               "afmformats_afm-workshop-fd_single_2018-08-01.csv", "chiaro-txt_AEBP1_Indentation_002_thinned.txt")
#: Virtual presets: (name, simulate arguments).
VIRTUAL = (("typical-s1", ["--instrument", "typical", "--seed", "1"]),
           ("typical-s2-fast", ["--instrument", "typical", "--seed", "2", "--velocity", "4e-6"]),
           ("paper-s1", ["--instrument", "paper", "--seed", "1"]),
           ("paper-s3-slow", ["--instrument", "paper", "--seed", "3", "--velocity", "5e-7"]),
           ("ideal", ["--instrument", "ideal", "--seed", "1"]),
           ("liquid-s1", ["--instrument", "liquid", "--seed", "1"]))


def virtual_files(folder: Path) -> list[Path]:
    """The presets' raw curves (HDF5), simulated with this tree once (kept in ``folder``)."""
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, args in VIRTUAL:
        path = folder / f"{name}.h5"
        if not path.exists():
            env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
            subprocess.run([sys.executable, "-m", "afmforce.cli.main", "simulate", *args, "--raw", str(path),
                            "--out", str(folder / f"{name}-trajectory.csv"), "--no-progress", "--force"],
                           check=True, env=env, stdout=subprocess.DEVNULL)
        out.append(path)
    return out


def case_list(pattern: str, virtual_folder: Path) -> list[tuple[str, str, dict | None]]:
    """``(label, path, meta_override)`` of every file to analyse."""
    cases = []
    if REAL.is_dir():
        cases += [(f"real/{p.name}", str(p), None) for p in sorted(REAL.iterdir())
                  if p.is_file() and p.name != "README.md"]
    overrides = json.loads((ROOT / "tests" / "data" / "meta_override.json").read_text())
    cases += [(f"bench/{n}", str(ROOT / "tests" / "data" / n), overrides.get(n)) for n in BENCH_FILES]
    cases += [(f"virtual/{p.name}", str(p), None) for p in virtual_files(virtual_folder)]
    return [c for c in cases if fnmatch.fnmatch(c[0].split("/", 1)[1], pattern)]


def flatten(obj, path: str, out: dict) -> None:
    """``path -> leaf`` of a result (dataclasses, mappings, sequences and arrays descended)."""
    import dataclasses

    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            flatten(getattr(obj, f.name), f"{path}.{f.name}", out)
    elif isinstance(obj, dict):
        for k in obj:
            flatten(obj[k], f"{path}[{k!r}]", out)
    elif isinstance(obj, np.ndarray):
        out[path] = np.array(obj, copy=True)
    elif isinstance(obj, (list, tuple)):
        if all(isinstance(v, (int, float, np.number)) and not isinstance(v, bool) for v in obj) and obj:
            out[path] = np.asarray(obj, dtype=float)
        else:
            for i, v in enumerate(obj):
                flatten(v, f"{path}[{i}]", out)
    elif isinstance(obj, (bool, np.bool_)):
        out[path] = bool(obj)
    elif isinstance(obj, (int, float, np.number)):
        out[path] = obj.item() if isinstance(obj, np.number) else obj
    elif obj is None or isinstance(obj, str):
        out[path] = obj
    else:
        out[path] = repr(obj)


def dump(cases_file: str, out_file: str) -> None:
    """Child process: analyse every case with the ``afmforce`` on ``sys.path``; pickle the flattened results."""
    import warnings

    from afmforce.analysis.pipeline import analyze
    from afmforce.errors import AfmforceError
    from afmforce.io import load

    warnings.simplefilter("ignore")
    cases = json.loads(Path(cases_file).read_text())
    results = {}
    for label, path, override in cases:
        try:
            curves = load(path, meta_override=override) if override else load(path)
        except AfmforceError as e:
            results[label] = {"load error": f"{type(e).__name__}: {e}"}
            continue
        for i, curve in enumerate(curves):
            key = f"{label}#{i}"
            flat: dict = {}
            try:
                res = analyze(curve)
            except AfmforceError as e:
                results[key] = {"analysis error": f"{type(e).__name__}: {e}"}
                continue
            for name in ("steps_run", "deflection_unit", "position_channel", "warnings", "not_applicable",
                         "details", "values", *res.ARRAYS):
                flatten(getattr(res, name), name, flat)
            results[key] = flat
    Path(out_file).write_bytes(pickle.dumps(results))


def run_tree(src: Path, cases: list, out: Path) -> dict:
    cases_file = out.with_suffix(".cases.json")
    cases_file.write_text(json.dumps(cases))
    env = {**os.environ, "PYTHONPATH": str(src)}
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--dump", str(cases_file), str(out)], check=True,
                   env=env)
    return pickle.loads(out.read_bytes())


def rel_diff(a, b) -> float:
    """Largest relative difference of two numbers or arrays (inf: shapes, types or text differ)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.shape != b.shape or a.dtype.kind != b.dtype.kind:
            return math.inf
        if a.dtype.kind not in "fc":
            return 0.0 if np.array_equal(a, b) else math.inf
        a, b = a.astype(float), b.astype(float)
        same = (a == b) | (np.isnan(a) & np.isnan(b))
        if same.all():
            return 0.0
        with np.errstate(invalid="ignore", divide="ignore"):
            d = np.abs(a - b) / np.maximum(np.abs(a), np.abs(b))
        d[same] = 0.0
        d[~np.isfinite(d)] = math.inf
        return float(d.max())
    if isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, (int, float)) or \
            not isinstance(b, (int, float)):
        return 0.0 if (type(a) is type(b) and a == b) else math.inf
    if a == b or (math.isnan(a) and math.isnan(b)):
        return 0.0
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    return abs(a - b) / max(abs(a), abs(b))


def compare(before: dict, after: dict, rtol: float) -> int:
    bad = 0
    worst = (0.0, "")
    values = 0
    for key in sorted(before.keys() | after.keys()):
        if key not in before or key not in after:
            print(f"  {key}: only {'after' if key in after else 'before'}")
            bad += 1
            continue
        b, a = before[key], after[key]
        for path in sorted(b.keys() | a.keys()):
            if path not in b or path not in a:
                print(f"  {key} {path}: only {'after' if path in a else 'before'}")
                bad += 1
                continue
            values += 1
            d = rel_diff(b[path], a[path])
            if d > worst[0]:
                worst = (d, f"{key} {path}")
            if d > rtol:
                bad += 1
                if bad <= 60:
                    show = lambda v: (f"array{v.shape}" if isinstance(v, np.ndarray) else repr(v)[:160])  # noqa
                    print(f"  {key} {path}: rel {d:.3g}: {show(b[path])} -> {show(a[path])}")
    print(f"{len(before)} curves, {values} values compared; largest relative difference {worst[0]:.3g}"
          + (f" ({worst[1]})" if worst[1] else "") + f"; {bad} over rtol {rtol:g}")
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default="main", help="git revision to compare with (default main)")
    ap.add_argument("--rtol", type=float, default=1e-9)
    ap.add_argument("--files", default="*", help="glob on the file names (default all)")
    ap.add_argument("--virtual-folder", default=str(Path(tempfile.gettempdir()) / "afmforce-equal-answers"),
                    help="where the presets' raw curves are kept")
    ap.add_argument("--dump", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.dump:
        dump(*args.dump)
        return 0
    cases = case_list(args.files, Path(args.virtual_folder))
    sha = subprocess.run(["git", "-C", str(ROOT), "rev-parse", args.before], check=True, capture_output=True,
                         text=True).stdout.strip()
    tree = Path(args.virtual_folder) / f"tree-{sha[:12]}"  # kept: its compiled kernels' cache too
    if not (tree / "src").is_dir():
        tree.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", sha, "src"], check=True,
                                 capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        print(f"before: {args.before} ({sha[:12]}; {len(cases)} files)", flush=True)
        before = run_tree(tree / "src", cases, tmp / "before.pkl")
        print("after: this tree", flush=True)
        after = run_tree(ROOT / "src", cases, tmp / "after.pkl")
    return compare(before, after, args.rtol)


if __name__ == "__main__":
    sys.exit(main())
