"""Elastic-plastic cylinder-flat (gross slip, Table 2 material, 10 um contact mesh): cost of the Newton
iteration matrices and their error against full Newton.

Modes (``solver.newton_tangent``):

* ``consistent`` (default, full Newton): elastic predictor, then the consistent tangent refactorised
  (numeric only) and W rebuilt (MUMPS selected inverse) at every iteration;
* ``adaptive``: the last factorised matrix kept while it contracts the residual 10x per iteration;
* ``elastic``: the initial-stiffness method (one factorisation, one W, for the whole run).

Each mode runs ``--cycles`` cycles; time per cycle, Newton iterations, refactorisations, and the
relative differences of the peak pressure and maximum wear depth at the end of each cycle against the
consistent run are written to ``benchmarks/results/plastic.md`` (with the command). A mode that fails
(no convergence) is recorded as such.

Usage::

    .venv/bin/python benchmarks/bench_plastic.py [--cycles 3] [--out FILE]
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import shlex
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from dolfinx_fretting.plots import read_table  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import SimulationError, run_scene  # noqa: E402

PLASTIC = ["material.model='elastoplastic'", "material.yield_stress=840", "material.hardening_modulus=7230",
           "output.xdmf=false", "output.plots=false", "output.progress=false", "output.contact_profiles=false"]


def run(tmp: Path, mode: str, cycles: int) -> dict:
    out = tmp / mode
    scene = load_scene("cylinder-flat", PLASTIC + [f"loading.cycles={cycles}", f"solver.newton_tangent='{mode}'"])
    t0 = time.perf_counter()
    try:
        s = run_scene(scene, out, quiet=True)
        error = None
    except SimulationError as exc:
        s, error = json.loads((out / "summary.json").read_text()), str(exc)
    wall = time.perf_counter() - t0
    cyc = read_table(out / "cycles.csv") if (out / "cycles.csv").is_file() else {}
    hist = read_table(out / "history.csv")
    done = len(cyc.get("cycle", []))
    return {"mode": mode, "wall_s": wall, "error": error, "cycles_done": done,
            "s_per_cycle": float(np.sum(cyc["wall_time_s"]) / done) if done else float("nan"),
            "newton_per_increment": float(np.mean(hist["newton_iterations"][hist["cycle"] > 0])) if done else 0,
            "cutbacks": int(np.sum(hist["cutbacks"])), "max_wear": list(map(float, cyc.get("max_wear_depth", []))),
            "p_end": list(map(float, cyc.get("max_pressure_end", []))),
            "max_equivalent_plastic_strain": s.get("max_equivalent_plastic_strain")}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cycles", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results" / "plastic.md"))
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        results = [run(tmp, m, args.cycles) for m in ("consistent", "adaptive", "elastic")]
    ref = results[0]
    lines = ["# Elastic-plastic cylinder-flat: Newton iteration matrices", "",
             f"Command: `{' '.join(shlex.quote(a) for a in [sys.executable, *sys.argv])}`  ",
             f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}, {platform.node()}, "
             f"{platform.machine()}; gross slip delta = 0.03 mm, 80 increments a cycle, 10 um contact mesh.", "",
             "| tangent | cycles done | s / cycle | Newton iterations / increment | cut-backs | max rel. diff. peak pressure vs consistent | max rel. diff. max wear vs consistent | outcome |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    for r in results:
        n = min(r["cycles_done"], ref["cycles_done"])
        if n:
            dp = max(abs(a / b - 1) for a, b in zip(r["p_end"][:n], ref["p_end"][:n]))
            dw = max(abs(a / b - 1) for a, b in zip(r["max_wear"][:n], ref["max_wear"][:n]))
        else:
            dp = dw = float("nan")
        outcome = "converged" if r["error"] is None else "FAILED: " + r["error"][:160].replace("|", "/")
        lines.append(f"| {r['mode']} | {r['cycles_done']} | {r['s_per_cycle']:.2f} | {r['newton_per_increment']:.2f} | "
                     f"{r['cutbacks']} | {dp:.1e} | {dw:.1e} | {outcome} |")
    text = "\n".join(lines) + "\n"
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps({"command": sys.argv, "results": results}, indent=2))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
