"""Where finite sliding's extra local sweeps come from (issue 26): McColl's increments solved step by step
(``solver.cycle_kernel = false``), the first load-control trial of every increment of the last cycle solved again
from other starts, with ``contact.sliding = "finite"`` and ``"small"``.

The starts: the state's forces (what the package does: after a re-pairing the committed forces turned into the new
frames), the forces of the state's loaded contacts that hold its relative positions in its pairing
(``W_aa r_a = (y - q_abs)_a``, projected on the cones: the re-pairing's inconsistency ``L_new C (L_old - L_new)^T r``
and the wear just committed taken out), zero, the solution of the committed load in the state's pairing, and the
same increment of the previous cycle. Also each trial problem's conditioning (``W_aa`` on the contacts loaded in its
solution, and its normal block scaled by its diagonal) and NSGS's sweeps on it. Sweeps are deterministic (no timing).
The local solves are hooked by wrapping ``increments._local_with_control`` (a measurement, not the package's path).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding_warm.py [--cycles 3] [--out FILE.md]
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import tempfile
from pathlib import Path

import numpy as np
from mpi4py import MPI

import dolfinx_fretting.increments as increments
from dolfinx_fretting import friction, local_solvers
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

PER_CYCLE, PRELOAD = 40, 4   # McColl's increments per cycle and preload increments
STARTS = ("state's forces", "held forces", "zero", "committed load's solution", "previous cycle's")


def held_forces(W: np.ndarray, b: np.ndarray, r: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """``W_aa out_a = b_a`` on the contacts with ``r_n > 0``, the others 0, each projected on its cone (2D)."""
    loaded = np.flatnonzero(r[0::2] > 0)
    rows = np.column_stack([2 * loaded, 2 * loaded + 1]).ravel()
    out = np.zeros_like(r)
    out[rows] = np.linalg.solve(W[np.ix_(rows, rows)], b[rows])
    blocks = out.reshape(-1, 2)
    for c in loaded:
        blocks[c] = local_solvers.project_coulomb(blocks[c], mu[c])
    return out


def measure(sliding: str, cycles: int, work: Path) -> dict[str, np.ndarray]:
    """Per increment of the last cycle: the first trial's sweeps from each start (uzawa), then NSGS's from the
    state's forces and from zero, the loaded contacts, cond(W_aa), cond of the scaled normal block."""
    original = increments._local_with_control
    last: dict[int, np.ndarray] = {}
    rows: list[list[float]] = []

    def hooked(operators, solver, state, targets, controlled, factors, q_body, W, r_warm):
        if W is not None or state.increment < PRELOAD:
            return original(operators, solver, state, targets, controlled, factors, q_body, W, r_warm)
        j = (state.increment - PRELOAD) % PER_CYCLE
        if state.increment >= PRELOAD + (cycles - 1) * PER_CYCLE:
            mu = friction.coefficients(operators.contact, state)
            d = state.obstacle.astype(float).copy()
            d[~controlled] = targets[~controlled]
            q, _ = operators.q(d, factors, state.positions, state.wear_gap)
            committed, q_abs = operators.q(state.obstacle.astype(float), state.load_factors, state.positions,
                                           state.wear_gap)
            options = dict(tol=solver.tol, max_iter=solver.max_iter, block_steps=operators.block_steps)
            same = local_solvers.solve(operators.W, committed, mu, 2, r0=state.forces, **options).r
            starts = (state.forces, held_forces(operators.W, state.positions - q_abs, state.forces, mu), None, same,
                      last.get(j))
            row = [local_solvers.solve(operators.W, q, mu, 2, r0=r0, **options).iterations if r0 is not None or k == 2
                   else np.nan for k, r0 in enumerate(starts)]
            row += [local_solvers.solve(operators.W, q, mu, 2, method="nsgs", r0=r0, **options).iterations
                    for r0 in (state.forces, None)]
            solution = local_solvers.solve(operators.W, q, mu, 2, r0=state.forces, **options).r
            loaded = np.flatnonzero(solution[0::2] > 0)
            block = np.column_stack([2 * loaded, 2 * loaded + 1]).ravel()
            normal = operators.W[np.ix_(2 * loaded, 2 * loaded)]
            scale = np.sqrt(np.diag(normal))
            row += [loaded.size, np.linalg.cond(operators.W[np.ix_(block, block)]),
                    np.linalg.cond(normal / scale[:, None] / scale[None, :])]
            rows.append(row)
        result = original(operators, solver, state, targets, controlled, factors, q_body, W, r_warm)
        last[j] = result.forces.copy()
        return result

    increments._local_with_control = hooked
    try:
        scene = load_scene("mccoll", [f"contact.sliding='{sliding}'", f"loading.cycles={cycles}",
                                      "solver.cycle_kernel=false", "output.plots=false", "output.xdmf=false",
                                      "output.progress=false", "output.snapshot_cycles=[]"])
        run_scene(scene, work / sliding, MPI.COMM_WORLD, overwrite=True)
    finally:
        increments._local_with_control = original
    return np.array(rows, dtype=float)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cycles", type=int, default=3)
    parser.add_argument("--out", default=None, help="write the table to this .md file too")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as work:
        results = {sliding: measure(sliding, args.cycles, Path(work)) for sliding in ("finite", "small")}
    load = os.getloadavg()
    command = f"OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding_warm.py --cycles {args.cycles}"
    lines = [f"Command: `{command}`", "",
             f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: {platform.machine()}, "
             f"{os.cpu_count()} cores; load average at the end {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}. McColl, "
             f"the {PER_CYCLE} increments of cycle {args.cycles}, their first load-control trial; means (min-max).", "",
             "| pairing | " + " | ".join(f"Uzawa sweeps from {s}" for s in STARTS)
             + " | NSGS from the state's forces | NSGS from zero | loaded contacts | cond(W_aa) | cond(scaled W_nn) |",
             "| --- |" + " ---: |" * (len(STARTS) + 5)]
    for sliding, rows in results.items():
        cells = [f"{np.nanmean(c):.1f} ({np.nanmin(c):.0f}-{np.nanmax(c):.0f})" for c in rows.T]
        lines.append(f"| {sliding} | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        Path(args.out).write_text(text)


if __name__ == "__main__":
    main()
