"""The local solves of the package's compiled cycle loop at 700-2000 3D contacts: the working set's block held or not.

Runs a fretting cycle of gross-slip increments through ``cycling.run_increments`` (displacement control) and
``cycling.run_force_increments`` (the normal force held, as the sphere-flat scene: several local solves an
increment) on the synthetic half-space W of the sphere's structure (``tests/support/local_problems.half_space``,
the problems of ``make_sphere_flat_problems.py --half-space N``: approach 1, contact radius a third of the grid's
side, mu 0.8), each increment warm started from the one before (``--warm increment``) or, the package's default
(``--warm cycle``), a second cycle, each increment from the same increment of the first (force control: from the
one before, as the package). Variants, alternating within each repeat (the
machine is shared: medians of the repeats, and the load average is recorded):

* ``before`` (``--before TREE``): the loop of another checkout (e.g. ``git archive``'s copy of the commit before),
  imported from ``TREE/dolfinx_fretting`` beside this one;
* ``gathered``: this loop with ``hold_block=False`` (``W_AA`` gathered at every local solve);
* ``held``: this loop's default (``W_AA`` held from one local solve to the next while the set is the same);
* ``held float32`` (``--float32``): the same with the sweeps' updates of x read from a float32 copy of ``W_AA``.

The CPU time of the whole call (one thread), per increment and per local solve: the local solves are nearly all of
it (the rest, the increment's right-hand side and its commit, is O(m) an increment). Answers: ``same bits`` as
``gathered`` (every output array of the loop), or the largest difference of the forces relative to their largest.

Usage (from the repository root)::

    git archive 78edfb7 dolfinx_fretting | tar -x -C /tmp/loop-before
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_loop_speed.py --sides 26 32 38 45 --increments 20 \\
        --before /tmp/loop-before --out /tmp/loop-speed/loop_speed
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
import types
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))

# benchmarks/ is on sys.path when a script runs
from _machine import command_line, machine_lines, machine_record, write_results  # noqa: E402
from support.local_problems import half_space, sphere_flat_cycle  # noqa: E402

from dolfinx_fretting import cycling  # noqa: E402

MU = 0.8        # the sphere-flat scene's (make_sphere_flat_problems.py)
APPROACH = 1.0  # as make_sphere_flat_problems.py: a contact radius of a third of the side
SLIP = 3.4      # the gross-slip amplitude of its gross-slip problem (times the approach)
OUTPUTS = ("rows", "r", "x", "y", "wear_gap", "states", "d", "solves")


def module_of(tree: Path, name: str = "cycling") -> types.ModuleType:
    """The module ``name`` of the checkout at ``tree``, as ``dolfinx_fretting_before.<name>`` (the package's
    ``__init__`` is not run: ``cycling`` imports only ``loading``, ``local_solvers`` and ``wear``, all pure
    NumPy/numba, and ``local_solvers`` nothing of the package). One tree a process: the first call's tree serves
    every later call."""
    if "dolfinx_fretting_before" not in sys.modules:
        package = types.ModuleType("dolfinx_fretting_before")
        package.__path__ = [str(tree / "dolfinx_fretting")]
        sys.modules["dolfinx_fretting_before"] = package
    return importlib.import_module(f"dolfinx_fretting_before.{name}")


def timed(W: np.ndarray, xy: np.ndarray, radius: float, slips: np.ndarray, force: float | None, wear: float,
          variant: tuple, start: dict | None = None) -> tuple[dict, float]:
    hold, loop, single = variant
    t0 = time.process_time()
    out = sphere_flat_cycle(W, xy, radius, APPROACH, slips, MU, wear, force, hold, loop, start, single)
    elapsed = time.process_time() - t0
    if out["done"] != slips.size or out["status"] != 1:
        raise RuntimeError(f"loop stopped at increment {out['done']}: status {out['status']}, error {out['error']}")
    return out, elapsed


def difference(out: dict, reference: dict) -> str:
    if all(np.array_equal(out[k], reference[k]) for k in OUTPUTS):
        return "same bits"
    return f"dr {np.abs(out['r'] - reference['r']).max() / np.abs(reference['r']).max():.1e}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sides", type=int, nargs="+", default=[26, 32, 38, 45], help="grid sides N (N^2 contacts)")
    ap.add_argument("--increments", type=int, default=20, help="increments of the cycle")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--wear", type=float, default=1e-4, help="Archard coefficient (the gaps move a little)")
    ap.add_argument("--before", type=Path, default=None, help="a checkout whose loop runs beside this one")
    ap.add_argument("--float32", action="store_true", help="also the held loop with float32 sweeps")
    ap.add_argument("--warm", choices=["increment", "cycle"], default="increment",
                    help="each increment from the one before, or a second cycle from the first's increments")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "loop_speed")
    args = ap.parse_args(argv)
    command = command_line("bench_loop_speed.py", sys.argv[1:] if argv is None else argv)

    variants = {}
    if args.before is not None:
        before = module_of(args.before.resolve())
        # A tree whose loops take hold_block / float32_sweeps (HELD_BLOCK_ARGUMENTS) holds the block, as this one.
        variants["before"] = (True if hasattr(before, "HELD_BLOCK_ARGUMENTS") else None, before, False)
    variants |= {"gathered": (False, cycling, False), "held": (True, cycling, False)}
    if args.float32:
        variants["held float32"] = (True, cycling, True)
    info = machine_record(repeats=args.repeats, increments=args.increments, wear=args.wear, warm=args.warm,
                          variants=list(variants))
    slips = SLIP * APPROACH * np.cos(2.0 * np.pi * np.arange(1, args.increments + 1) / args.increments)
    records = []
    for side in args.sides:
        W, xy = half_space(side)
        radius = (side / 3.0) ** 2 / APPROACH
        nc = xy.shape[0]
        # The normal force of the approach (the first increment's), for the force-controlled cycle.
        first, _ = timed(W, xy, radius, slips[:1], None, 0.0, variants["held"])
        force = float(first["r"][0, 0::3].sum())
        for control, load in (("displacement", None), ("normal force", force)):
            for variant in variants.values():  # JIT (cached on disk) and first touch of W out of the timings
                timed(W, xy, radius, slips[:2], load, args.wear, variant)
            start = timed(W, xy, radius, slips, load, args.wear, variants["held"])[0]["end"] if args.warm == "cycle" \
                else None
            times: dict[str, list[float]] = {name: [] for name in variants}
            outs: dict[str, dict] = {}
            for _ in range(args.repeats):
                for name, variant in variants.items():  # alternating: the machine's load hits all alike
                    outs[name], elapsed = timed(W, xy, radius, slips, load, args.wear, variant, start)
                    times[name].append(elapsed)
            solves = int(outs["held"]["solves"].sum())
            sweeps = float(outs["held"]["rows"][:, -2].sum())
            rec = {"nc": nc, "W_mb": W.nbytes / 2**20, "control": control, "force": load, "solves": solves,
                   "mean_sweeps_per_solve": sweeps / solves, "held_counts": outs["held"]["counts"].tolist(),
                   "variants": {name: {"median_s": float(np.median(t)), "min_s": float(np.min(t)),
                                       "per_increment_s": float(np.median(t)) / args.increments,
                                       "per_solve_s": float(np.median(t)) / solves,
                                       "answer": difference(outs[name], outs["gathered"]),
                                       "max_error": float(outs[name]["rows"][:, -1].max())}
                                for name, t in times.items()}}
            records.append(rec)
            print(f"{nc} {control}: " + ", ".join(f"{n} {1e3 * v['per_increment_s']:.3g} ms/increment "
                                                   f"({1e3 * v['per_solve_s']:.3g} ms/solve, {v['answer']})"
                                                   for n, v in rec["variants"].items())
                  + f"; {solves} solves, {sweeps / solves:.1f} sweeps a solve, counts {rec['held_counts']}",
                  flush=True)
            write_results(args.out, command, info, records, markdown)
    print(f"wrote {args.out.with_suffix('.md')}")
    return 0


def markdown(command: str, info: dict, records: list[dict]) -> str:
    names = info["variants"]
    L = ["## The compiled cycle loop's local solves: the block held (half-space, uzawa, tol 1e-10)", "",
         f"Command (from the repository root): `{command}`", "",
         *machine_lines(info),
         f"- a cycle of {info['increments']} gross-slip increments (slip {SLIP:g} x cos), warm start "
         f"`{info['warm']}` (`increment`: each increment from the one before; `cycle`: a second cycle, each increment "
         f"from the same of the first; force control from the one before), Archard k = {info['wear']:g}; "
         f"{info['repeats']} repeats, the variants alternating; median CPU time of the loop's call per increment and "
         "per local solve (min of the repeats in brackets, per increment)", "",
         "| contacts | W | control | " + " | ".join(f"{n}: per increment (min)" for n in names) + " | "
         + " | ".join(f"{n}: per solve" for n in names) + " | solves | sweeps a solve | held / gathered solves | "
         + " | ".join(f"answer {n}" for n in names if n != "gathered") + " | largest local error |",
         "|---:|---:|---|" + "---:|" * (2 * len(names)) + "---:|---:|---|" + "---|" * len(names)]
    for rec in records:
        v = rec["variants"]
        counts = rec["held_counts"]
        L.append(f"| {rec['nc']} | {rec['W_mb']:.0f} MB | {rec['control']} | "
                 + " | ".join(f"{1e3 * v[n]['per_increment_s']:.3g} ms ({1e3 * v[n]['min_s'] / info['increments']:.3g})"
                              for n in names) + " | "
                 + " | ".join(f"{1e3 * v[n]['per_solve_s']:.3g} ms" for n in names)
                 + f" | {rec['solves']} | {rec['mean_sweeps_per_solve']:.1f} | {counts[3]} / {counts[4]} | "
                 + " | ".join(v[n]["answer"] for n in names if n != "gathered") + " | "
                 + " / ".join(f"{v[n]['max_error']:.1e}" for n in names) + " |")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())
