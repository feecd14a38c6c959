"""The re-pairing's closest-segment search (finite sliding, 2D): the full search against the search pruned from each
node's previous facet (``sliding._closest_segments_near``), on McColl's sizes: 101 slave nodes over 110 master facets of
10 um within reach, the nodes slid a quarter facet since their last pairing (a re-pairing's stride). CPU time per
search, medians; the answers compared bit for bit.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding_search.py [--calls 300] [--repeats 5]
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import statistics
import time

import numpy as np

from dolfinx_fretting.contact import _closest_segments
from dolfinx_fretting.sliding import _closest_segments_near


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    h = 0.01
    x = np.arange(111) * h - 0.55                                      # 110 facets, the flat's top within reach
    ends = np.column_stack([x, -2e-4 * np.exp(-(x / 0.1) ** 2)])       # indented by ~0.2 um
    A = np.ascontiguousarray(ends[:-1])
    d = np.ascontiguousarray(ends[1:] - ends[:-1])
    L2 = (d ** 2).sum(axis=1)
    slaves = np.column_stack([np.linspace(-0.5, 0.5, 101) + 0.25 * h, np.full(101, 1e-5)])
    previous = np.empty(101, dtype=np.int64)
    xi, dist = np.empty(101), np.empty(101)
    _closest_segments(slaves - [0.25 * h, 0.0], A, d, L2, previous, xi, dist)   # the pairing a stride ago
    full = np.empty(101, dtype=np.int64), np.empty(101), np.empty(101)
    pruned = np.empty(101, dtype=np.int64), np.empty(101), np.empty(101)
    _closest_segments(slaves, A, d, L2, *full)
    _closest_segments_near(slaves, A, d, L2, previous, *pruned)
    same = all(np.array_equal(a, b) for a, b in zip(full, pruned))
    times: dict[str, list[float]] = {"full": [], "pruned": []}
    for _ in range(args.repeats):   # alternated
        for name in ("full", "pruned"):
            per_call = []
            for _ in range(args.calls):
                t0 = time.process_time_ns()
                if name == "full":
                    _closest_segments(slaves, A, d, L2, *full)
                else:
                    _closest_segments_near(slaves, A, d, L2, previous, *pruned)
                per_call.append((time.process_time_ns() - t0) * 1e-3)
            times[name].append(statistics.median(per_call))
    load = os.getloadavg()
    print(f"Command: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding_search.py --calls {args.calls} "
          f"--repeats {args.repeats}`\n\nDate: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: "
          f"{platform.machine()}, {os.cpu_count()} cores; load average at the end {load[0]:.2f} / {load[1]:.2f} / "
          f"{load[2]:.2f}. CPU time per search (process_time), median of {args.calls} calls, then the median over "
          f"{args.repeats} alternated repeats.\n\n| search | us per search | per-repeat medians (us) |\n"
          "| --- | ---: | --- |")
    for name, values in times.items():
        print(f"| {name} | {statistics.median(values):.1f} | {', '.join(f'{v:.1f}' for v in values)} |")
    print(f"\nThe same facets, t and distances, bit for bit: {same}.")


if __name__ == "__main__":
    main()
