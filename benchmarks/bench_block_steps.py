"""The per-contact Uzawa steps ``block_rho(W)`` held with W (``ContactOperators.block_steps``) against recomputed at
every local solve, side by side in one process.

*Before*: ``local_solvers.solve`` wrapped so that it ignores the steps its caller holds and computes
``block_rho(W, dim)`` itself (what every solve did before the steps were held); *after*: the package as it is. Runs
alternate (B A B A ...), each timed by its process CPU time and wall time around ``run_scene``; the ratio is taken
pair by pair. Scenes:

* a 3D ``sphere-flat`` run of a few cycles (normal force control: the increment-by-increment path, ~5 local solves
  an increment: where the steps were recomputed);
* the main job, Example 1 ``stromberg-block`` (its cycles in the compiled loop, which already held the steps; its
  preload and ramp increment by increment).

The answers must be the same bits: every number of the two summaries but the timings is compared exactly.

Usage::

    .venv/bin/python benchmarks/bench_block_steps.py [--pairs 3] [--sphere-cycles 10] [--block-cycles 9000]
"""

from __future__ import annotations

import argparse
import datetime
import json
import shlex
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from _machine import cpu_model  # noqa: E402

from dolfinx_fretting import local_solvers  # noqa: E402
from dolfinx_fretting.contact_output import read_table  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import run_scene  # noqa: E402

QUIET = ["output.xdmf=false", "output.plots=false", "output.progress=false", "output.contact_profiles=false"]
#: Summary entries that are timings (differ from run to run) and not answers.
TIMINGS = ("wall_time_s", "_s", "timings")


def _solve_recomputing(original):
    def solve(*args, block_steps=None, **kwargs):  # the steps held are dropped: block_rho at every solve
        return original(*args, **kwargs)
    return solve


def run(tmp: Path, scene: str, cycles: int, before: bool, name: str) -> tuple[float, float, float, dict]:
    original = local_solvers.solve
    if before:
        local_solvers.solve = _solve_recomputing(original)
    try:
        sc = load_scene(scene, QUIET + [f"loading.cycles={cycles}", f"output.snapshot_cycles=[{cycles}]",
                                        f"output.loop_cycles=[{cycles}]"])
        c0, t0 = time.process_time(), time.perf_counter()
        summary = run_scene(sc, tmp / name, quiet=True, overwrite=True)
        cpu, wall = time.process_time() - c0, time.perf_counter() - t0
        in_cycles = float(read_table(tmp / name / "cycles.csv")["wall_time_s"].sum())  # the cycles alone (wall)
        return cpu, wall, in_cycles, summary
    finally:
        local_solvers.solve = original


def answers(summary: dict) -> dict:
    return {k: v for k, v in summary.items()
            if not any(k == t or k.endswith(t) for t in TIMINGS) and "time" not in k}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--sphere-cycles", type=int, default=10)
    ap.add_argument("--block-cycles", type=int, default=9000)
    ap.add_argument("--out", default=str(HERE / "results" / "block_steps.md"))
    args = ap.parse_args(argv)
    cmd = " ".join([".venv/bin/python", "benchmarks/bench_block_steps.py", *map(shlex.quote, sys.argv[1:])])
    lines = []
    results = {}
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        run(tmp, "stromberg-block", 2, False, "warmup")  # numba compilation
        for scene, cycles in (("sphere-flat", args.sphere_cycles), ("stromberg-block", args.block_cycles)):
            rows = {"before": [], "after": []}
            same = True
            for i in range(args.pairs):
                for label in ("before", "after"):
                    cpu, wall, in_cycles, summary = run(tmp, scene, cycles, label == "before", f"{scene}-{label}-{i}")
                    rows[label].append((cpu, wall, answers(summary), in_cycles))
                    print(scene, label, i, f"cpu {cpu:.2f} s wall {wall:.2f} s cycles {in_cycles:.2f} s", flush=True)
                same &= json.dumps(rows["before"][-1][2], default=str) == json.dumps(rows["after"][-1][2],
                                                                                       default=str)
            ratio_cpu = [b[0] / a[0] for b, a in zip(rows["before"], rows["after"])]
            ratio_wall = [b[1] / a[1] for b, a in zip(rows["before"], rows["after"])]
            ratio_cycles = [b[3] / a[3] for b, a in zip(rows["before"], rows["after"])]
            summary = rows["after"][-1][2]
            results[scene] = {"cycles": cycles, "cpu_before": [r[0] for r in rows["before"]],
                              "cpu_after": [r[0] for r in rows["after"]],
                              "wall_before": [r[1] for r in rows["before"]],
                              "wall_after": [r[1] for r in rows["after"]],
                              "cycles_wall_before": [r[3] for r in rows["before"]],
                              "cycles_wall_after": [r[3] for r in rows["after"]], "speedup_cycles": ratio_cycles,
                              "speedup_cpu": ratio_cpu, "speedup_wall": ratio_wall, "same_answers": same}
            med = statistics.median
            lines += [f"## {scene}, {cycles} cycles ({summary['contacts']} contacts, {summary['dofs']} dofs, cycle "
                      f"path {summary.get('cycle_path', '?')})", "",
                      "| | run CPU s (median, min-max) | run wall s (median) | the cycles' wall s (median) |",
                      "| --- | ---: | ---: | ---: |",
                      f"| before: block_rho at every solve | {med(results[scene]['cpu_before']):.2f} "
                      f"({min(results[scene]['cpu_before']):.2f}-{max(results[scene]['cpu_before']):.2f}) | "
                      f"{med(results[scene]['wall_before']):.2f} | {med(results[scene]['cycles_wall_before']):.2f} |",
                      f"| after: held with W | {med(results[scene]['cpu_after']):.2f} "
                      f"({min(results[scene]['cpu_after']):.2f}-{max(results[scene]['cpu_after']):.2f}) | "
                      f"{med(results[scene]['wall_after']):.2f} | {med(results[scene]['cycles_wall_after']):.2f} |", "",
                      f"Before/after pair by pair, whole run CPU (set-up included): median {med(ratio_cpu):.3f} (min "
                      f"{min(ratio_cpu):.3f}, max {max(ratio_cpu):.3f}); wall: median {med(ratio_wall):.3f}; the "
                      f"cycles alone (cycles.csv's wall_time_s summed): median {med(ratio_cycles):.3f} (min "
                      f"{min(ratio_cycles):.3f}, max {max(ratio_cycles):.3f}). Answers (every summary number "
                      f"but timings) equal to the last bit: {'yes' if same else 'NO'}.", ""]
    head = ["# block_rho held with W against recomputed at every local solve", "",
            f"Command: `{cmd}`  ",
            f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}, {cpu_model()}, 2 cores shared with "
            "other jobs while this ran (CPU times are the steadier measure); Debian stack unless the command says "
            "otherwise; one process, runs alternating before/after, numba compiled by a warm-up run.", "",
            "Before: `local_solvers.solve` made to ignore the steps its caller holds (`block_steps`) and compute "
            "`block_rho(W, dim)` (a batched 3x3 / 2x2 SVD of W's diagonal blocks) at every solve, as every solve did; "
            "after: `ContactOperators.block_steps`, computed once per W (build, window change), passed by the "
            "increment's local solve, the compiled loop and the window check.", ""]
    Path(args.out).write_text("\n".join(head + lines) + "\n")
    Path(args.out).with_suffix(".json").write_text(json.dumps(results, indent=1))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
