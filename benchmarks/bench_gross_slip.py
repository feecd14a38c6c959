"""A fretting cycle's local solves one by one at 1000-2000 3D contacts: the gross-slip predictor on and off.

The problems: a cycle of the package's compiled loop (``cycling.run_increments``, displacement control, Archard
k = 1e-4, each increment warm started from the one before) on the synthetic half-space W of the sphere's structure
(``tests/support/local_problems.half_space``, as ``bench_loop_speed.py``: approach 1, contact radius a third of the
grid's side, mu 0.8, slip 3.4 x cos over the cycle). Each increment's problem (its ``q`` from the loop's outputs,
its warm start the answer of the increment before) is then solved again by ``local_solvers.solve`` (``uzawa``, tol
1e-10, the working set with its block held, as the package solves), the predictor on (the default) and off
(``gross_slip_predictor=False``), in turn increment by increment (the same set, so both sweep the held block);
CPU time of each call (one thread), median of the repeats. An increment is *gross slip* when every loaded contact
of its answer slides (``contact_states``); the others are the cycle's reversals (partial slip), where the
predictor stops after a step and the sweeps answer. ``--before TREE``: the ``local_solvers.solve`` of another
checkout (its default, the block held by its own module) in turn with the two, side by side.

Usage (from the repository root)::

    git archive d5a0d42 dolfinx_fretting | tar -x -C /tmp/solve-before
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_gross_slip.py --sides 32 38 45 --repeats 3 \\
        --before /tmp/solve-before --out /tmp/gross-slip/gross_slip
"""

from __future__ import annotations

import argparse
import sys
import time
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

# benchmarks/ is on sys.path when a script runs
from _machine import command_line, machine_lines, machine_record, write_results  # noqa: E402
from bench_loop_speed import APPROACH, MU, SLIP, module_of  # noqa: E402
from support.local_problems import cycle_q, half_space, sphere_flat_cycle  # noqa: E402

from dolfinx_fretting import local_solvers  # noqa: E402

TOL = 1e-10  # the scenes' solver.local_tol


def timed(W: np.ndarray, q: np.ndarray, r0: np.ndarray, steps: np.ndarray, variant: str,
          before: types.ModuleType | None = None) -> tuple[local_solvers.LocalResult, float]:
    start = time.process_time()
    if variant == "before":
        result = before.solve(W, q, MU, 3, tol=TOL, r0=r0, block_steps=steps)
    else:
        result = local_solvers.solve(W, q, MU, 3, tol=TOL, r0=r0, block_steps=steps,
                                     gross_slip_predictor=variant == "on")
    elapsed = time.process_time() - start
    if not result.converged:
        raise RuntimeError(result.message)
    return result, elapsed


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sides", type=int, nargs="+", default=[32, 38, 45], help="contacts per side of the grid")
    ap.add_argument("--increments", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--before", type=Path, default=None, help="a checkout whose solve runs beside this one's")
    ap.add_argument("--out", type=Path, default=Path("/tmp/gross-slip/gross_slip"))
    args = ap.parse_args(argv)
    command = command_line("bench_gross_slip.py", sys.argv[1:] if argv is None else argv)
    before = None if args.before is None else module_of(args.before.resolve(), "local_solvers")
    variants = ["on", "off"] + ([] if before is None else ["before"])
    info = machine_record(repeats=args.repeats, increments=args.increments, variants=variants)
    slips = SLIP * APPROACH * np.cos(2.0 * np.pi * np.arange(1, args.increments + 1) / args.increments)
    records = []
    for side in args.sides:
        W, xy = half_space(side)
        nc = xy.shape[0]
        radius = (side / 3.0) ** 2 / APPROACH
        cycle = sphere_flat_cycle(W, xy, radius, APPROACH, slips, mu=MU, wear=1e-4)
        steps = local_solvers.block_rho(W, 3)
        problems = [(cycle_q(cycle, j), cycle["r"][j - 1]) for j in range(1, args.increments)]
        for variant in variants:   # compiled (cached on disk), W touched, out of the timings
            timed(W, *problems[0], steps, variant, before)
        times = {variant: np.zeros((args.repeats, len(problems))) for variant in variants}
        results: dict[str, list] = {variant: [] for variant in variants}
        for repeat in range(args.repeats):
            for j, (q, r0) in enumerate(problems):
                for variant in variants:   # in turn: the same set, each solve on its module's held block
                    result, times[variant][repeat, j] = timed(W, q, r0, steps, variant, before)
                    if repeat == 0:
                        results[variant].append(result)
        rows = []
        for j, (q, _) in enumerate(problems):
            on, off = results["on"][j], results["off"][j]
            states = local_solvers.contact_states(on.r, on.x, MU, 3)
            loaded = on.r[0::3] > 0
            rows.append({"increment": j + 1, "loaded": int(loaded.sum()), "working_set": on.working_set,
                         "gross_slip": bool(np.all(states[loaded] == local_solvers.SLIP)),
                         "stick": int(np.sum(states == local_solvers.STICK)),
                         "on_s": float(np.median(times["on"][:, j])), "off_s": float(np.median(times["off"][:, j])),
                         "before_s": float(np.median(times["before"][:, j])) if before is not None else None,
                         "on_steps": on.predictor_steps, "on_sweeps": on.sweeps, "off_sweeps": off.sweeps,
                         "difference": float(np.abs(on.r - off.r).max() / np.abs(off.r).max()),
                         "difference_before": (float(np.abs(on.r - results["before"][j].r).max() / np.abs(off.r).max())
                                               if before is not None else None),
                         "error_on": float(local_solvers.natural_map_error(W, q, on.r, MU, 3))})
        gross = [row for row in rows if row["gross_slip"]]
        record = {"nc": nc, "W_mb": W.nbytes / 2**20, "rows": rows,
                  "gross_on_ms": 1e3 * float(np.median([row["on_s"] for row in gross])) if gross else None,
                  "gross_off_ms": 1e3 * float(np.median([row["off_s"] for row in gross])) if gross else None,
                  "gross_max_on_ms": 1e3 * max(row["on_s"] for row in gross) if gross else None,
                  "cycle_on_ms": 1e3 * float(np.mean([row["on_s"] for row in rows])),
                  "cycle_off_ms": 1e3 * float(np.mean([row["off_s"] for row in rows]))}
        if before is not None:
            record |= {"gross_before_ms": 1e3 * float(np.median([row["before_s"] for row in gross])) if gross else None,
                       "cycle_before_ms": 1e3 * float(np.mean([row["before_s"] for row in rows]))}
        records.append(record)
        print(f"{nc} contacts: gross slip {len(gross)} of {len(rows)} increments, median {record['gross_on_ms']:.3g} "
              f"ms (off {record['gross_off_ms']:.3g} ms), cycle mean {record['cycle_on_ms']:.3g} ms (off "
              f"{record['cycle_off_ms']:.3g} ms)" + ("" if before is None else
                                                       f"; before: median {record['gross_before_ms']:.3g} ms, cycle "
                                                       f"mean {record['cycle_before_ms']:.3g} ms"), flush=True)
        write_results(args.out, command, info, records, markdown)
    print(f"wrote {args.out.with_suffix('.md')}")
    return 0


def markdown(command: str, info: dict, records: list[dict]) -> str:
    before = "before" in info.get("variants", [])
    extra = " | before" if before else ""
    L = ["## A cycle's local solves one by one: the gross-slip predictor (half-space, uzawa, tol 1e-10)", "",
         f"Command (from the repository root): `{command}`", "",
         *machine_lines(info),
         f"- the increments 1-{info['increments'] - 1} of a cycle of {info['increments']} (slip {SLIP:g} x cos, mu "
         f"{MU:g}), each from the answer of the one before; CPU time of `local_solvers.solve` per increment, median "
         f"of {info['repeats']} repeats, the predictor on and off"
         + (" and the solve of the checkout `--before` (its default)" if before else "") + " in turn", "",
         f"| contacts | W | gross-slip increments | their median: on | off{extra} | their slowest: on | cycle mean: on "
         f"| off{extra} |", "|---:|---:|---:|---:|---:|" + ("---:|" if before else "") + "---:|---:|---:|"
         + ("---:|" if before else "")]
    for rec in records:
        gross = sum(row["gross_slip"] for row in rec["rows"])
        L.append(f"| {rec['nc']} | {rec['W_mb']:.0f} MB | {gross} of {len(rec['rows'])} | "
                 f"{rec['gross_on_ms']:.3g} ms | {rec['gross_off_ms']:.3g} ms | "
                 + (f"{rec['gross_before_ms']:.3g} ms | " if before else "")
                 + f"{rec['gross_max_on_ms']:.3g} ms | {rec['cycle_on_ms']:.3g} ms | {rec['cycle_off_ms']:.3g} ms |"
                 + (f" {rec['cycle_before_ms']:.3g} ms |" if before else ""))
    L += ["", "Per increment (predictor on: steps + sweeps; off: sweeps; the answers' largest difference relative to "
          "the largest force" + (", on against off and against before" if before else "")
          + "; the natural-map error of the answer on the whole problem, recomputed):", "",
          f"| contacts | increment | loaded | set | sticking | gross slip | on | off{extra} | on: steps + sweeps "
          f"| off: sweeps | difference{' (before)' if before else ''} | error |",
          "|---:|---:|---:|---:|---:|---|---:|---:|" + ("---:|" if before else "") + "---:|---:|---:|---:|"]
    for rec in records:
        for row in rec["rows"]:
            L.append(f"| {rec['nc']} | {row['increment']} | {row['loaded']} | {row['working_set']} | {row['stick']} | "
                     f"{'yes' if row['gross_slip'] else 'no'} | {1e3 * row['on_s']:.3g} ms | "
                     f"{1e3 * row['off_s']:.3g} ms | " + (f"{1e3 * row['before_s']:.3g} ms | " if before else "")
                     + f"{row['on_steps']} + {row['on_sweeps']} | {row['off_sweeps']} | {row['difference']:.1e}"
                     + (f" ({row['difference_before']:.1e})" if before else "") + f" | {row['error_on']:.1e} |")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    sys.exit(main())
