"""CPU time and peak RSS of ``analyze`` on one long quasi-static curve (the memory of
``static_curve`` included in the RSS before the analysis).

    python benchmarks/bench_long_curve.py [--sample-rate 200000]

``static_curve(sample_rate=S)`` has about 1.015 S points (2,000 Hz: 2,030).
"""

from __future__ import annotations

import argparse
import resource
import time

from afmforce.analysis import synthetic
from afmforce.analysis.pipeline import analyze


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sample-rate", type=float, default=200_000.0)
    args = ap.parse_args()
    analyze(synthetic.static_curve(sample_rate=2000.0, noise=0.05e-9))  # compile / warm the kernels
    curve = synthetic.static_curve(sample_rate=args.sample_rate, noise=0.05e-9)
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t = time.process_time()
    analyze(curve)
    cpu = time.process_time() - t
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f"points={curve.truth['separation'].size} analyze_cpu_s={cpu:.2f} "
          f"maxrss_before_MB={rss0 / 1024:.0f} maxrss_after_MB={rss1 / 1024:.0f}")


if __name__ == "__main__":
    main()
