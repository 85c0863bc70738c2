"""``afmforce demo``: the main job on built-in defaults.

1. ``reproduce --fast``: the paper's figures and every recomputable number, ours
   beside the paper's, into ``./afmforce-paper/``;
2. one virtual experiment analysed end to end: the virtual AFM records a
   simulated run, the raw file is read back and analysed by the pipeline, and
   the recovered Hamaker constant is compared with the truth (without and
   with tip friction);
3. a liquid experiment (issue 25): a colloid probe in water with slip, four speeds, the slip
   length and the spring constant fitted in situ against the truth.

Each part is printed when it is done (the paper's closed-form and static rows first: they need
no integrator, so a first run that compiles shows them in about a second too); the figures are
drawn in a forked child meanwhile (:class:`_Aside`; in this process where there is no fork or
one CPU). Issue 35 item 4; measured in ``benchmarks/README.md``, "Cold start".
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import print_json


def register(sub) -> None:
    p = sub.add_parser("demo", help="reproduce the paper (fast) and analyse a virtual experiment end to end",
                       description="The main job on built-in defaults: the paper's figures and numbers "
                                   "(reproduce --fast), then a virtual experiment: simulated run -> virtual "
                                   "AFM -> raw file -> analysis -> Hamaker constant vs the truth.")
    p.add_argument("--out", default="afmforce-paper", help="output folder (default ./afmforce-paper)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def _check_head() -> list[str]:
    head = (f"{'quantity':<64} {'source':<20} {'kind':<9} {'paper':>10} {'afmforce':>12} {'unit':<7} "
            f"{'diff':>7}  ok")
    return [head, "-" * len(head)]


def _check_rows(results) -> list[str]:
    lines = []
    for r in results:
        paper = "-" if r.paper is None else f"{r.paper:.4g}"
        if r.kind == "estimate" and r.estimate is not None:
            paper = f"~{r.estimate:.3g}"
        diff = "-" if r.relative_difference is None or r.kind != "check" else \
            f"{100 * r.relative_difference:+.1f}%"
        ok = "-" if r.passed is None else ("yes" if r.passed else "NO")
        lines.append(f"{r.quantity[:64]:<64} {r.source[:20]:<20} {r.kind:<9} {paper:>10} {r.ours:>12.5g} "
                     f"{r.unit:<7} {diff:>7}  {ok}")
    return lines


def _check_tail(results) -> list[str]:
    gated = [r for r in results if r.passed is not None]
    n_ok = sum(bool(r.passed) for r in gated)
    return [f"{n_ok} of {len(gated)} gated numbers pass (the paper within its stated tolerance, its "
            f"bound, or our reference); {len(results) - len(gated)} shown without pass/fail"]


def format_checks(results) -> str:
    """A plain-text table of evaluated paper checks (kind: what gates each entry)."""
    return "\n".join(_check_head() + _check_rows(results) + _check_tail(results))


#: The paper's check groups computed without the integrator (closed forms, statics: ~0.4 s as
#: Python or compiled, nothing to compile): printed first, also on a first run that compiles.
FIRST_GROUPS = ("forces", "inertia", "statics")


class _Aside:
    """Work done in a forked child while this process goes on (figures: matplotlib's layout and
    rendering are about half of the demo's CPU time, and need nothing the rest computes).

    ``work()`` returns something JSON can write; :meth:`result` waits for it. Where no fork is
    possible (Windows), or only one CPU is usable, or the child fails in any way, the work is
    done here instead (so an error is raised here, as the CLI reports it)."""

    def __init__(self, work, *, inline: bool = False):
        import os

        self._work, self._pid, self._fd = work, None, None
        if inline or not hasattr(os, "fork"):
            return
        from .._cores import available_cores

        if available_cores() < 2:
            return
        import sys

        for stream in (sys.stdout, sys.stderr):
            stream.flush()
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:                    # the child: do the work, say how it went, exit at once
            os.close(read)
            status = 1
            try:
                import json

                os.write(write, json.dumps({"value": work()}).encode())
                status = 0
            except BaseException:       # noqa: BLE001 - the parent does the work again and raises
                pass
            finally:
                os._exit(status)
        os.close(write)
        self._pid, self._fd = pid, read

    def result(self):
        import json
        import os

        if self._pid is None:
            return self._work()
        chunks = []
        while chunk := os.read(self._fd, 1 << 16):
            chunks.append(chunk)
        os.close(self._fd)
        _, status = os.waitpid(self._pid, 0)
        self._pid = None
        if status == 0:
            try:
                return json.loads(b"".join(chunks))["value"]
            except (ValueError, KeyError):
                pass
        return self._work()             # the child failed: do it here (and raise here if it fails)

    def cancel(self) -> None:
        import os
        import signal

        if self._pid is not None:
            try:
                os.kill(self._pid, signal.SIGTERM)
                os.waitpid(self._pid, 0)
            except OSError:
                pass
            os.close(self._fd)
            self._pid = None


def run(args: argparse.Namespace) -> int:
    """The demo's parts, each printed when it is done: the paper's numbers first (their runs
    are shared with the figures), then the virtual and the liquid experiments; the figures
    (the paper's and the virtual runs' analyses) are drawn in a forked child meanwhile."""
    import sys
    import time

    from ..paper.demo import draw_virtual, virtual_runs
    from ..paper.numbers import evaluate_checks
    from ..paper.reproduce import FIGURES, ReproduceResult, write_figures, write_reports
    from ._validate import check_output
    from ._outcome import reported
    from .common import busy
    from .reproduce import summarize

    def say(*lines: str) -> None:
        if not args.json:
            print(*lines, sep="\n", flush=True)

    check_output(args.out, folder=True)
    t0 = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from ..paper.numbers import all_checks

    every = all_checks()
    order = {c.key: i for i, c in enumerate(every)}
    say("afmforce demo: Attard, Carambassis & Rutland, Langmuir 15, 553 (1999), recomputed\n", *_check_head())
    checks = evaluate_checks([c for c in every if c.group in FIRST_GROUPS])
    say(*_check_rows(checks))           # the first results: no integrator needed
    with busy("afmforce demo: the paper's simulated numbers"):
        later = evaluate_checks([c for c in every if c.group not in FIRST_GROUPS])
    say(*_check_rows(later))
    checks = sorted(checks + later, key=lambda c: order[c.key])   # the reports keep the paper's order
    say(*_check_tail(checks), "")

    def paper_figures():
        written, failed = write_figures(out, list(FIGURES), fast=True)
        return {k: [str(p) for p in v] for k, v in written.items()}, failed

    figures = _Aside(paper_figures)
    drawing = None
    try:
        with busy("afmforce demo: virtual experiment"):
            runs = virtual_runs(out / "virtual")
        drawing = _Aside(lambda: draw_virtual(runs))
        say("virtual experiment: inclined cantilever, R = 100 nm, A = 5e-19 J, 0.2 um/s, 'typical' instrument;",
            "raw file -> drift, calibration, zero of separation, jump-in, van der Waals fit")
        for r, _, _ in runs:
            say(f"  {r.label:<30} A = {r.hamaker_fit:.3g} J (+- {r.hamaker_se:.1g}) vs true {r.hamaker_true:.3g} J: "
                f"{100 * r.relative_error:+.0f} %; friction signature: {r.friction or '-'}")
        say("  friction makes the apparent attraction weaker: the fit underestimates A (paper section 2.3)", "")
        from ..paper.demo_liquid import liquid_experiment

        with busy("afmforce demo: liquid experiment"):
            liq = liquid_experiment(out / "liquid")
        lo, hi = liq.slip_interval
        say("liquid experiment: colloid probe R = 5 um on a flat in water, b = 3 nm, 4 speeds 5-40 um/s,",
            "the file's spring constant 8 % off; fit of slip length and spring constant (in situ):",
            f"  slip length {liq.slip_fit * 1e9:.3f} nm (95 % [{lo * 1e9:.3f}, {hi * 1e9:.3f}]) vs true "
            f"{liq.slip_true * 1e9:.3g} nm; slip {'detected' if liq.slip_detected else 'not detected'} "
            f"(p = {liq.slip_p_value:.2g}); k {liq.spring_constant_fit:.4g} N/m vs true "
            f"{liq.spring_constant_true:.4g} (file {liq.spring_constant_file:.4g}); {liq.fit_seconds:.1f} s", "")
        with busy("afmforce demo: figures"):
            written, failed = figures.result()
            drawing.result()
    except BaseException:
        figures.cancel()
        if drawing is not None:
            drawing.cancel()
        raise
    written = {k: [Path(p) for p in v] for k, v in written.items()}
    write_reports(out, checks, written, failed)
    res = ReproduceResult(out, written, checks, failed, time.perf_counter() - t0)
    reported(args.out)  # its files are named below (and in the JSON)
    if args.json:
        print_json({"out_dir": str(res.out_dir), "passed": res.passed,
                    "checks": [c.to_dict() for c in res.checks],
                    "virtual_experiment": [r.__dict__ | {"raw_file": str(r.raw_file), "figure": str(r.figure)}
                                           for r, _, _ in runs],
                    "liquid_experiment": liq.__dict__})
        return 0 if res.passed else 1
    print(summarize(res))
    print(f"virtual runs, raw files and analysis figures in {out / 'virtual'}/")
    sys.stdout.flush()
    return 0 if res.passed else 1
