"""Mutation campaign over every reader of :func:`afmforce.io.load` (broken-file robustness).

Every real file of ``tests/data`` (its top level and ``corpus/``) and of the shared real folder
(``AFMFORCE_REAL_DATA``, default ``/work/shared/data/real``), each content once, is damaged in seeded,
reproducible ways:

* truncated at ~20 points (first bytes, mid-header, the header's end, the data start, 1/8 .. 7/8,
  the last bytes);
* bits flipped, bytes zeroed or replaced in the header;
* numeric header fields (spring constant, sensitivity, sizes, offsets, point counts, rates,
  scales: text ``key ... number`` lines, also inside a zip's ``.properties`` members) set to
  0, -1, NaN, 1e308, 2147483647;
* binary header words (ints and doubles in the first 1 KiB) set to 0, -1, 2^31-1, NaN, 1e308;
* zip members truncated (JPK archives);
* the file under every other format's ending;

plus, per ending: an empty file, 4 KiB of random bytes, and a directory named like a file.

Each mutated file is loaded by a worker process under ``RLIMIT_AS`` (2 GiB) and a per-call wall
limit (20 s); a worker that overruns is killed and the case recorded as a hang. A case is a
defect when load raises anything but an :class:`~afmforce.errors.AfmforceError` (or a non-one-line,
file-less message), hangs, crashes the worker, modifies its input, or returns a curve with a
non-finite column or a metadata value outside afmforce's declared range (``_fields.QUANTITIES``:
k, sensitivity, sample rate, velocity, ...). Refusals that only wrap a foreign exception (the
generic "could not read it: ... (IndexError: ...)") are counted apart, by the foreign type.

Run::

    PYTHONPATH=src python benchmarks/fuzz_readers.py --out /tmp/fuzz.json [--workers 2] [--limit N]

and read the summary it prints (and the JSON: every case with its outcome).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import random
import re
import select
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
from collections import Counter, defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
REAL = Path(os.environ.get("AFMFORCE_REAL_DATA") or "/work/shared/data/real")
MEM_LIMIT = 2 << 30          # [bytes] address space of a worker
CALL_LIMIT = 20.0            # [s] wall time of one load
ENDINGS = (".txt", ".csv", ".tsv", ".ibw", ".jpk-force", ".jpk-force-map", ".jpk-qi-data", ".spm", ".000",
           ".h5", ".tab", ".nid", ".ardf", ".curves", ".tiff")
BAD_VALUES = (b"0", b"-1", b"nan", b"1e308", b"2147483647")
#: words of a header line whose number is worth damaging
FIELD = re.compile(rb"(?i)(spring|sens|invols|defl|points|samps|length|offset|size|count|rate|freq|scale|"
                   rb"multiplier|lines|bytes|num|velocity|speed|ramp|k \(|conversion|factor|nchannel|elements)")
NUMBER = re.compile(rb"(?<![A-Za-z_])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


# ----------------------------------------------------------------------------------- inputs
def corpus_files() -> list[Path]:
    """Every readable real file, each content once (tests/data first: their names say the instrument)."""
    from afmforce.io import is_supported

    seen, out = set(), []
    for folder in (DATA, DATA / "corpus", REAL):
        if not folder.is_dir():
            continue
        for p in sorted(folder.iterdir()):
            if not p.is_file() or not is_supported(p) or p.name.startswith(("make_", "README")):
                continue
            digest = hashlib.sha1(p.read_bytes()).hexdigest()
            if digest not in seen:
                seen.add(digest)
                out.append(p)
    return out


def header_end(data: bytes) -> int:
    """Where a file's header plausibly ends (a marker, else the first 4 KiB or a tenth)."""
    for mark in (b"\\*File list end", b"*File list end", b"#!", b"[Data]", b"# data", b"\n\n"):
        i = data.find(mark)
        if 0 < i < len(data) - 1:
            return i
    return min(4096, max(1, len(data) // 10))


def data_start(data: bytes) -> int:
    m = re.search(rb"\\Data offset: (\d+)", data[:200000])
    if m and int(m.group(1)) < len(data):
        return int(m.group(1))
    return min(len(data) - 1, header_end(data) + 64)


def truncations(data: bytes) -> list[tuple[str, bytes]]:
    n = len(data)
    h, d = header_end(data), data_start(data)
    points = {1, 8, 64, 512, h // 2, h, h + 1, d, d + 7, n - 1, n - 2, n - 16, n - 1000}
    points |= {n * k // 8 for k in range(1, 8)}
    return [(f"truncate@{p}", data[:p]) for p in sorted(points) if 0 < p < n]


def header_damage(data: bytes, rng: random.Random, count: int = 10) -> list[tuple[str, bytes]]:
    h = max(64, min(len(data), header_end(data)))
    out = []
    for j in range(count):
        b = bytearray(data)
        what = ("flip", "zero", "random")[j % 3]
        i = rng.randrange(h)
        if what == "flip":
            for _ in range(rng.randint(1, 4)):
                k = rng.randrange(h)
                b[k] ^= 1 << rng.randrange(8)
        elif what == "zero":
            k = rng.randint(1, 16)
            b[i:i + k] = b"\0" * len(b[i:i + k])
        else:
            k = rng.randint(1, 16)
            b[i:i + k] = bytes(rng.randrange(256) for _ in range(len(b[i:i + k])))
        out.append((f"header-{what}@{i}", bytes(b)))
    return out


def field_sites(data: bytes, limit: int = 2_000_000) -> list[tuple[int, int, bytes]]:
    """(start, end, line) of numbers on header lines that name a field worth damaging."""
    region = data[:limit]
    sites = []
    for line in re.finditer(rb"[^\r\n]{1,400}", region):
        text = line.group(0)
        if sum(32 <= c < 127 or c == 9 for c in text) < 0.9 * len(text) or not FIELD.search(text):
            continue
        for m in NUMBER.finditer(text):
            sites.append((line.start() + m.start(), line.start() + m.end(), text[:60]))
    return sites


def field_damage(data: bytes, rng: random.Random, count: int = 16) -> list[tuple[str, bytes]]:
    """Numbers of header fields replaced by BAD_VALUES; in a binary file (NUL bytes in its first 64 KiB)
    the edit keeps the length (padded with spaces, 2^31-1 as 9s), so offsets stay right and the
    reader meets the value, not a shifted layout."""
    sites = field_sites(data)
    binary = b"\0" in data[:65536]
    out = []
    for _ in range(min(count, len(sites))):
        s, e, line = sites[rng.randrange(len(sites))]
        v = BAD_VALUES[rng.randrange(len(BAD_VALUES))]
        if binary:
            if len(v) > e - s:
                v = {b"1e308": b"9" * (e - s), b"2147483647": b"9" * (e - s)}.get(v, v[:e - s])
            v = v.ljust(e - s)
        out.append((f"field {line.decode('latin-1')!r}->{v.decode()}", data[:s] + v + data[e:]))
    return out


def binary_damage(data: bytes, rng: random.Random, count: int = 8) -> list[tuple[str, bytes]]:
    words = (struct.pack("<i", 0), struct.pack("<i", -1), struct.pack("<i", 2**31 - 1), struct.pack("<I", 2**31),
             struct.pack("<d", float("nan")), struct.pack("<d", 1e308), struct.pack(">i", 2**31 - 1),
             struct.pack("<q", -1))
    top = min(len(data) - 8, 1024)
    out = []
    for j in range(count if top > 8 else 0):
        i = rng.randrange(0, top) & ~3
        w = words[j % len(words)]
        out.append((f"word@{i}={w.hex()}", data[:i] + w + data[i + len(w):]))
    return out


def zip_damage(path: Path, rng: random.Random, count: int = 16) -> list[tuple[str, bytes]]:
    """Damaged members of a zip archive (numbers in .properties, truncated members), re-zipped."""
    try:
        zf = zipfile.ZipFile(path)
        infos = zf.infolist()
        members = {i.filename: zf.read(i) for i in infos if not i.is_dir()}
    except Exception:
        return []
    props = [n for n in members if n.endswith(".properties")]
    datas = [n for n in members if not n.endswith(".properties")]
    out = []

    def rezip(name: str, new: bytes) -> bytes:
        import io
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
            for info in infos:
                if info.is_dir():
                    continue
                z.writestr(info.filename, new if info.filename == name else members[info.filename])
        return buf.getvalue()

    for j in range(count):
        if j % 4 == 3 and datas:
            name = datas[rng.randrange(len(datas))]
            raw = members[name]
            cut = rng.randrange(max(1, len(raw)))
            out.append((f"zip {name} truncated@{cut}", rezip(name, raw[:cut])))
            continue
        if not props:
            continue
        name = props[rng.randrange(len(props))]
        raw = members[name]
        sites = field_sites(raw)
        if not sites:
            continue
        s, e, line = sites[rng.randrange(len(sites))]
        v = BAD_VALUES[rng.randrange(len(BAD_VALUES))]
        out.append((f"zip {name} {line.decode('latin-1')!r}->{v.decode()}", rezip(name, raw[:s] + v + raw[e:])))
    return out


def mutations(path: Path, seed: int) -> list[tuple[str, str, bytes]]:
    """(kind, detail, bytes, ending) of one file."""
    data = path.read_bytes()
    rng = random.Random(seed)
    suffix = "".join(path.suffixes[-1:]) if not path.name.endswith(".f.curves") else ".curves"
    if path.name.lower().endswith((".jpk-force-map", ".jpk-qi-data", ".jpk-qi-series")):
        suffix = "." + path.name.split(".")[-1]
    out = [("original", "as is", data, suffix)]
    out += [("truncate", d, b, suffix) for d, b in truncations(data)]
    out += [("header", d, b, suffix) for d, b in header_damage(data, rng)]
    out += [("field", d, b, suffix) for d, b in field_damage(data, rng)]
    if data[:4] not in (b"PK\x03\x04",) and data[:2] in (b"\x05\x00", b"\x00\x05", b"II", b"MM") or \
            data[:4] in (b"ARDF", b"\x89HDF"):
        out += [("binary", d, b, suffix) for d, b in binary_damage(data, rng)]
    if data[:4] == b"PK\x03\x04":
        out += [("zip", d, b, suffix) for d, b in zip_damage(path, rng)]
    out += [("ending", f"as {e}", data, e) for e in ENDINGS if e != suffix.lower()]
    return out


# ----------------------------------------------------------------------------------- worker
def _plausibility(curves) -> list[str]:
    import numpy as np

    from afmforce._fields import QUANTITIES

    problems = []
    for i, c in enumerate(curves):
        for name in ("time", "piezo_nominal", "piezo_measured", "deflection_signal"):
            col = getattr(c, name)
            if col is not None and not np.isfinite(np.asarray(col, float)).all():
                problems.append(f"curve {i}: {name} not finite")
        for key, value in (c.metadata or {}).items():
            spec = QUANTITIES.get(key)
            if spec is None or value is None or isinstance(value, (str, bool)):
                continue
            try:
                v = float(value)
            except (TypeError, ValueError):
                continue
            if not (np.isfinite(v) and spec.contains(v)):
                problems.append(f"curve {i}: {key} = {value!r} outside {spec.range_text()}")
        f = np.asarray(c.deflection_signal, float)
        if f.size and np.isfinite(f).all() and np.ptp(f) == 0:
            problems.append(f"curve {i}: constant deflection ({f[0]!r} {c.deflection_unit})")
    return problems[:4]


def _one(path: str) -> dict:
    from afmforce.errors import AfmforceError
    from afmforce.io import load

    p = Path(path)
    before = (hashlib.sha1(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns) if p.is_file() else None
    t0 = time.process_time()
    rec: dict = {}
    try:
        curves = load(p)
    except AfmforceError as exc:
        msg = str(exc)
        rec = {"outcome": "refused", "type": type(exc).__name__, "message": msg[:300]}
        ctx = exc.__context__
        if ctx is not None and not isinstance(ctx, AfmforceError) and "could not read it" in msg:
            rec["wrapped"] = type(ctx).__name__
        if "\n" in msg.strip():
            rec["multiline"] = True
        if p.name not in msg:
            rec["nameless"] = True
    except BaseException as exc:  # noqa: BLE001  the defect being hunted
        rec = {"outcome": "defect", "type": type(exc).__name__, "message": str(exc)[:300]}
    else:
        rec = {"outcome": "loaded", "curves": len(curves), "samples": sum(len(c) for c in curves),
               "problems": _plausibility(curves),
               "flagged": any("truncat" in k for c in curves for k in (c.metadata or {}))}
    rec["cpu"] = round(time.process_time() - t0, 3)
    after = (hashlib.sha1(p.read_bytes()).hexdigest(), p.stat().st_mtime_ns) if p.is_file() else None
    if before != after:
        rec["modified"] = True
    return rec


def worker() -> None:
    import resource
    import warnings

    warnings.simplefilter("ignore")
    resource.setrlimit(resource.RLIMIT_AS, (MEM_LIMIT, MEM_LIMIT))
    import afmforce.io  # noqa: F401  warm imports
    for line in sys.stdin:
        job = json.loads(line)
        try:
            rec = _one(job["path"])
        except BaseException as exc:  # noqa: BLE001
            rec = {"outcome": "defect", "type": "worker:" + type(exc).__name__, "message": str(exc)[:300]}
        sys.stdout.write(json.dumps(rec) + "\n")
        sys.stdout.flush()


class Worker:
    def __init__(self) -> None:
        src = os.environ.get("AFMFORCE_FUZZ_SRC") or str(ROOT / "src")   # another tree: a before/after comparison
        env = dict(os.environ, PYTHONPATH=src + os.pathsep + os.environ.get("PYTHONPATH", ""))
        self.proc = subprocess.Popen([sys.executable, __file__, "--worker"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env, text=True,
                                     bufsize=1)

    def run(self, path: str) -> dict:
        self.proc.stdin.write(json.dumps({"path": path}) + "\n")
        self.proc.stdin.flush()
        ready, _, _ = select.select([self.proc.stdout], [], [], CALL_LIMIT)
        if not ready:
            self.kill()
            return {"outcome": "defect", "type": "hang", "message": f"no answer in {CALL_LIMIT:g} s"}
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            self.proc = None
            return {"outcome": "defect", "type": "crash", "message": f"worker died (exit {code})"}
        return json.loads(line)

    def kill(self) -> None:
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
            self.proc = None


def campaign(args) -> dict:
    files = corpus_files()
    if args.only:
        files = [f for f in files if re.search(args.only, f.name)]
    work = Path(tempfile.mkdtemp(prefix="afmforce-fuzz-"))
    cases = []
    for f in files:
        for kind, detail, blob, ending in mutations(f, seed=sum(f.name.encode())):
            cases.append((f.name, kind, detail, blob, ending))
    rng = random.Random(7)
    extras = []
    for e in ENDINGS:
        extras.append(("<none>", "empty", f"empty{e}", b"", e))
        extras.append(("<none>", "random", f"random{e}", bytes(rng.randrange(256) for _ in range(4096)), e))
        extras.append(("<none>", "directory", f"dir{e}", None, e))
    cases = extras + cases
    if args.limit:
        step = max(1, len(cases) // args.limit)
        cases = cases[::step]
    print(f"{len(files)} files, {len(cases)} cases", flush=True)
    workers = [Worker() for _ in range(args.workers)]
    results = []
    t0 = time.time()

    def submit(w: int, i: int):
        name, kind, detail, blob, ending = cases[i]
        d = work / f"w{w}"
        shutil.rmtree(d, ignore_errors=True)
        d.mkdir()
        target = d / (Path(name).stem.split(".")[0][:40] + "_m" + ending)
        if blob is None:
            target.mkdir()
        else:
            target.write_bytes(blob)
        return target

    # simple round-robin: each worker takes the next case (the select in Worker.run blocks one at a time,
    # so with 2 workers run them from two threads)
    import threading

    lock = threading.Lock()
    it = iter(range(len(cases)))

    def loop(w: int) -> None:
        while True:
            with lock:
                i = next(it, None)
            if i is None:
                return
            target = submit(w, i)
            if workers[w].proc is None:
                workers[w] = Worker()
            rec = workers[w].run(str(target))
            name, kind, detail, _, ending = cases[i]
            rec.update(file=name, kind=kind, detail=detail, ending=ending)
            with lock:
                results.append(rec)
                if len(results) % 200 == 0:
                    print(f"{len(results)}/{len(cases)} in {time.time() - t0:.0f} s (load {os.getloadavg()[0]:.1f})",
                          flush=True)

    threads = [threading.Thread(target=loop, args=(w,)) for w in range(args.workers)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for w in workers:
        if w.proc is not None:
            w.proc.stdin.close()
            w.kill()
    shutil.rmtree(work, ignore_errors=True)
    return {"files": [f.name for f in files], "cases": results}


def defect_class(rec: dict) -> str | None:
    """The defect class of one case (None: handled as afmforce promises)."""
    if rec.get("modified"):
        return "input modified"
    if rec["outcome"] == "defect":
        return f"raised {rec['type']}"
    if rec["outcome"] == "refused":
        if rec.get("multiline"):
            return "multi-line message"
        if rec.get("nameless") and rec["kind"] != "directory":
            return "message without the file name"
        return None
    if rec.get("short"):
        return "truncated file loaded short, nothing says so"
    if rec["outcome"] == "loaded" and rec["problems"]:
        return "implausible: " + re.sub(r"curve \d+: (\w+).*", r"\1", rec["problems"][0])
    return None


def _short_loads(cases: list[dict]) -> None:
    """Mark truncations that loaded fewer samples than the whole file, with nothing saying so."""
    whole = {c["file"]: c.get("samples") for c in cases if c["kind"] == "original" and c["outcome"] == "loaded"}
    for c in cases:
        if c["kind"] == "truncate" and c["outcome"] == "loaded" and not c.get("flagged") and \
                whole.get(c["file"]) and c["samples"] < whole[c["file"]]:
            c["short"] = f"{c['samples']} of {whole[c['file']]} samples"


def summary(result: dict) -> str:
    cases = result["cases"]
    _short_loads(cases)
    lines = [f"{len(result['files'])} files, {len(cases)} mutations"]
    lines.append("outcomes: " + ", ".join(f"{k} {v}" for k, v in Counter(c["outcome"] for c in cases).items()))
    classes = defaultdict(list)
    for c in cases:
        k = defect_class(c)
        if k:
            classes[k].append(c)
    lines.append(f"defects: {sum(map(len, classes.values()))}")
    for k, v in sorted(classes.items(), key=lambda kv: -len(kv[1])):
        ex = v[0]
        lines.append(f"  {len(v):5d} {k}: e.g. {ex['file']} {ex['detail'][:70]} -> {ex.get('message', ex.get('short') or ex.get('problems'))!s:.160}")
    wrapped = defaultdict(list)
    for c in cases:
        if c.get("wrapped"):
            wrapped[c["wrapped"]].append(c)
    lines.append(f"generic refusals wrapping a foreign exception: {sum(map(len, wrapped.values()))}")
    for k, v in sorted(wrapped.items(), key=lambda kv: -len(kv[1])):
        readers = Counter(re.search(r"\('([\w-]+)'", c["message"]).group(1) if re.search(r"\('([\w-]+)'", c["message"])
                          else "?" for c in v)
        lines.append(f"  {len(v):5d} {k} ({dict(readers.most_common(4))}): e.g. {v[0]['file']} {v[0]['detail'][:60]}")
    slow = sorted(cases, key=lambda c: -c.get("cpu", 0))[:3]
    lines.append("slowest CPU: " + "; ".join(f"{c['file']} {c['detail'][:40]} {c.get('cpu')} s" for c in slow))
    return "\n".join(lines)


def cli_sample(count: int, good: Path) -> list[str]:
    """``afmforce analyze`` on ``count`` mutated files (one per reader where possible), each alone and all in
    one folder with ``good``: every failure one line naming its file, no traceback, non-zero exit; the
    batch writes ``good``'s results. Returns the problems found (empty: as promised)."""
    rng = random.Random(11)
    picked: dict[str, tuple] = {}
    for f in corpus_files():
        if f.stat().st_size > 300_000:
            continue
        for case in mutations(f, seed=sum(f.name.encode())):
            if case[0] in ("truncate", "field", "zip", "header") and rng.random() < 0.05:
                picked.setdefault(f.suffix.lower(), (f.name, *case))
    cases = list(picked.values())[:count]
    work = Path(tempfile.mkdtemp(prefix="afmforce-fuzz-cli-"))
    folder = work / "batch"
    folder.mkdir()
    shutil.copy(good, folder / good.name)
    env = dict(os.environ, PYTHONPATH=os.environ.get("AFMFORCE_FUZZ_SRC") or str(ROOT / "src"))
    problems = []
    refused = 0

    def analyze(target: Path, out: Path) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "afmforce.cli.main", "analyze", str(target), "--out", str(out)],
                              capture_output=True, text=True, env=env, timeout=600)

    for i, (name, kind, detail, blob, ending) in enumerate(cases):
        target = folder / f"m{i}_{Path(name).stem[:20]}{ending}"
        target.write_bytes(blob)
        run = analyze(target, work / f"out{i}")
        failed = [ln for ln in run.stderr.splitlines() if ln.startswith("failed:")]
        if "Traceback" in run.stderr:
            problems.append(f"{name} {detail}: traceback")
        if run.returncode == 0 and not failed:
            continue                 # the mutation left a readable file
        refused += 1
        if run.returncode == 0 or len(failed) != 1 or target.name not in failed[0]:
            problems.append(f"{name} {detail}: exit {run.returncode}, {len(failed)} failure line(s): "
                            f"{run.stderr[-300:]!r}")
    run = analyze(folder, work / "batch-out")
    if "Traceback" in run.stderr:
        problems.append("batch: traceback")
    if not list((work / "batch-out").glob(f"{good.name}.afmforce.*")):
        problems.append(f"batch: no result for the good file {good.name} ({run.stderr[-300:]!r})")
    print(f"CLI: {len(cases)} mutated files ({refused} refused alone) and a batch of them with {good.name}: "
          f"{len(problems)} problem(s)")
    shutil.rmtree(work, ignore_errors=True)
    return problems


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--out", default="fuzz_readers.json")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--limit", type=int, default=0, help="run about this many cases (an even sample)")
    ap.add_argument("--only", default="", help="regular expression of the file names to mutate")
    ap.add_argument("--summary", default="", help="print the summary of an earlier --out JSON and stop")
    ap.add_argument("--cli", type=int, default=0, help="run `afmforce analyze` on this many mutated files (alone "
                    "and in a folder with a good file) and stop")
    args = ap.parse_args()
    if args.worker:
        worker()
        return
    if args.cli:
        problems = cli_sample(args.cli, DATA / "jpk_cellhesion_spot3.jpk-force")
        print("\n".join(problems) or "CLI: every failure one line naming its file, the batch went on")
        return
    if args.summary:
        print(summary(json.loads(Path(args.summary).read_text())))
        return
    result = campaign(args)
    Path(args.out).write_text(json.dumps(result, indent=0))
    print(summary(result))


if __name__ == "__main__":
    main()
