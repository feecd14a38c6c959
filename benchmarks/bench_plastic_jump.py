"""Cycle jumps for an elastic-plastic body, extrapolating the plastic state (an experiment for the runner).

The scene runner refuses ``wear.cycle_jump`` for elastic-plastic bodies. This script measures what the
functions of :mod:`dolfinx_fretting.cycle_jump` for plastic bodies would give if the runner called them: it
replaces ``simulation._Run._jump`` by a version that, after each simulated cycle, classifies the cycle
(:func:`~dolfinx_fretting.cycle_jump.analyse_plastic_cycle`), bounds the jump by the plastic state's change
(:func:`~dolfinx_fretting.cycle_jump.plastic_jump_limit`, passed to ``choose_jump``), runs the runner's own
wear jump, extrapolates the plastic history (u, sigma, eps_p, p) over the same jump
(:func:`~dolfinx_fretting.cycle_jump.extrapolate`) and accumulates the error estimates
(:func:`~dolfinx_fretting.cycle_jump.plastic_jump_error`). It runs the elastic-plastic Example 2 (two bodies,
gross slip, real k) every cycle and jumped, in one process, and compares the end states.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_plastic_jump.py --cycles 60 --fraction 0.1
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import shlex
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
PLASTIC = ["material.model=elastoplastic", "material.yield_stress=840", "material.hardening_modulus=7230",
           "output.xdmf=false", "output.plots=false", "output.progress=false", "output.contact_profiles=false"]


def run(cycles: int, jumped: bool, fraction: float, tol_fraction: float) -> dict:
    from dolfinx_fretting import cycle_jump as cj
    from dolfinx_fretting import simulation as sim
    from dolfinx_fretting.problem import PlasticHistory
    from dolfinx_fretting.scenes import load_scene

    scene = load_scene("cylinder-flat", PLASTIC + [f"loading.cycles={cycles}", f"output.snapshot_cycles=[{cycles}]"])
    m = scene.material
    E, sy, H = m.E, m.yield_stress, m.plastic_modulus
    tol = tol_fraction * sy / E
    if jumped:
        scene.wear.cycle_jump = True  # past the scene check that refuses it for plastic bodies: what is measured
    rows: list[dict] = []
    limit = [math.inf]
    memo = {"prev": None, "prev_jump": 1, "eps": 0.0, "p": 0.0}
    choose, own_jump = cj.choose_jump, sim._Run._jump

    def plastic_jump(self, cycle, start, new, result, room, regrown):
        a, b = start.plastic, new.plastic
        pc = cj.analyse_plastic_cycle(a.eps_p, a.p, b.eps_p, b.p, tol, self.comm)
        if memo["prev"] is not None:
            e, p = cj.plastic_jump_error(memo["prev"], pc, memo["prev_jump"], self.comm)
            memo["eps"], memo["p"] = memo["eps"] + e, memo["p"] + p
        limit[0] = cj.plastic_jump_limit(pc, fraction, sy, E, H)
        state, jump = own_jump(self, cycle, start, new, result, room, regrown)
        dN = jump["jump"]
        if dN > 1:
            state = replace(state, plastic=PlasticHistory(*(cj.extrapolate(getattr(a, f), getattr(b, f), dN)
                                                            for f in ("u", "sigma", "eps_p", "p"))))
        memo["prev"], memo["prev_jump"] = pc, dN
        rows.append({"cycle": cycle, "jump": dN, "bound": jump["bound"], "regime": pc.regime, "flow": pc.flow,
                     "net": pc.net, "plastic_limit": limit[0], "wear_error": jump["error_total"],
                     "eps_error": memo["eps"], "p_error": memo["p"]})
        return state, jump

    cj.choose_jump = lambda *args, **kw: choose(*args, **kw, plastic_limit=limit[0])
    sim._Run._jump = plastic_jump
    try:
        t0 = time.perf_counter()
        with tempfile.TemporaryDirectory() as d:
            r = sim._Run(scene, Path(d), sim.MPI.COMM_WORLD, True, False)
            r.run_stepwise(sim.preload_path(scene.loading))
            t1 = time.perf_counter()
            r.run_cycles()
            st, cs = r.state, r.model.contact
            ps = r.problem.plastic_state(st)
            return {"wall_s": time.perf_counter() - t0, "cycles_s": time.perf_counter() - t1,
                    "simulated": len(rows) if jumped else cycles, "rows": rows, "wear_gap": st.wear_gap.copy(),
                    "pressure": st.forces[0::cs.dim] / cs.tributary, "eps_p": ps.eps_p.copy(), "p": ps.p.copy()}
    finally:
        cj.choose_jump, sim._Run._jump = choose, own_jump


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cycles", type=int, default=60)
    ap.add_argument("--fraction", type=float, default=0.1, help="plastic_jump_limit's fraction of the yield point")
    ap.add_argument("--tol-fraction", type=float, default=1e-3, help="regime tolerance / yield strain")
    ap.add_argument("--out", default=str(HERE / "results" / "plastic_jump.md"))
    args = ap.parse_args(argv)
    every = run(args.cycles, False, args.fraction, args.tol_fraction)
    jumped = run(args.cycles, True, args.fraction, args.tol_fraction)
    eq = lambda e: math.sqrt(2 / 3) * np.linalg.norm(e, axis=1)  # noqa: E731
    last = jumped["rows"][-1]
    dw = float(np.abs(jumped["wear_gap"] - every["wear_gap"]).max())
    de = float(eq(jumped["eps_p"] - every["eps_p"]).max())
    dp = float(np.abs(jumped["p"] - every["p"]).max())
    dpr = float(np.abs(jumped["pressure"] - every["pressure"]).max())
    load = os.getloadavg()
    L = ["# Elastic-plastic cycle jumps with the plastic state extrapolated: jumped vs every cycle", "",
         f"Command: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_plastic_jump.py {shlex.join(argv)}`  ",
         f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}, {platform.node()}, {os.cpu_count()} cores "
         f"shared with other jobs (load average at the end {load[0]:.1f}).  ",
         "Scene: `cylinder-flat` " + " ".join(f"--set {s}" for s in PLASTIC[:3]) + f" --set loading.cycles="
         f"{args.cycles}: two bodies, gross slip, 80 increments a cycle, the real k (8.5e-9 1/MPa), every "
         f"cycle and jumped (wear bounds of the scene's defaults, plus plastic_jump_limit with fraction "
         f"{args.fraction}; regime tolerance {args.tol_fraction} x the yield strain).", "",
         "| run | simulated cycles | cycles' wall time (s) |", "| --- | ---: | ---: |",
         f"| every cycle | {every['simulated']} | {every['cycles_s']:.1f} |",
         f"| jumped | {jumped['simulated']} | {jumped['cycles_s']:.1f} |", "",
         f"At cycle {args.cycles}, jumped against every cycle (max over the contacts / quadrature points), with "
         "the jumped run's accumulated error estimate:", "",
         "| quantity | every cycle: max | difference | estimate |", "| --- | ---: | ---: | ---: |",
         f"| wear gap (mm) | {every['wear_gap'].max():.4e} | {dw:.2e} | {last['wear_error']:.2e} |",
         f"| equivalent plastic strain of eps_p | {eq(every['eps_p']).max():.4e} | {de:.2e} | {last['eps_error']:.2e} |",
         f"| accumulated plastic strain p | {every['p'].max():.4e} | {dp:.2e} | {last['p_error']:.2e} |",
         f"| contact pressure at the end (MPa) | {every['pressure'].max():.2f} | {dpr:.3g} | |", "",
         "The jumped run's simulated cycles (flow: largest increase of p in the cycle; net: largest equivalent "
         "change of eps_p; plastic limit: plastic_jump_limit):", "",
         "| cycle | regime | flow | net | plastic limit | jump | bound |", "| ---: | --- | ---: | ---: | ---: | ---: | --- |"]
    for r in jumped["rows"]:
        L.append(f"| {r['cycle']} | {r['regime']} | {r['flow']:.2e} | {r['net']:.2e} | {r['plastic_limit']:.3g} | "
                 f"{r['jump']} | {r['bound']} |")
    text = "\n".join(L) + "\n"
    Path(args.out).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
