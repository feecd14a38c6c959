"""Elastic-plastic cycle jumps through the runner: 10^4 physical cycles timed, and the error against every cycle.

For each scene (the paper's Example 2 material on ``cylinder-flat``, gross slip, and ``cylinder-flat-partial``,
partial slip; two deformable bodies, 10 um contact elements, the real k), three runs of the CLI, each a fresh
process:

1. ``--cycles`` physical cycles with ``wear.cycle_jump = true``: wall time, simulated cycles, the bounds that set
   the jumps, the plastic regimes, the final wear and the accumulated error estimates;
2. and 3. the first ``--compare-cycles`` cycles every cycle and jumped: the differences of the final states (wear
   gap, equivalent plastic strain of eps_p, accumulated plastic strain p, contact pressure; from the
   checkpoints, at full precision) against the jumped run's estimates.

Writes ``results/plastic_jump.md`` and ``.json``.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_plastic_jump.py --cycles 10000 --compare-cycles 100
"""

from __future__ import annotations

import argparse
import collections
import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
#: The paper's Example 2 material (Table 2), without the outputs that cost time.
PLASTIC = ["material.model=elastoplastic", "material.yield_stress=840", "material.hardening_modulus=7230",
           "output.xdmf=false", "output.plots=false", "output.progress=false"]


def _run(scene: str, out: Path, cycles: int, jumped: bool) -> float:
    """One CLI run in a fresh process; returns its wall time (s)."""
    sets = [*PLASTIC, f"loading.cycles={cycles}", f"wear.cycle_jump={'true' if jumped else 'false'}"]
    cmd = [sys.executable, "-m", "dolfinx_fretting.cli", "run", scene, "--out", str(out), "--overwrite", "--quiet"]
    cmd += [x for s in sets for x in ("--set", s)]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=ROOT)
    return time.perf_counter() - t0


def _state(folder: Path) -> dict[str, np.ndarray]:
    from dolfinx_fretting.simulation import read_checkpoint

    return read_checkpoint(folder / "checkpoint.npz")[1]


def _last_pressure(folder: Path) -> np.ndarray:
    """Contact pressure at the last increment (contact_profiles.csv: the last cycle is a snapshot)."""
    from dolfinx_fretting.contact_output import read_table

    profiles = read_table(folder / "contact_profiles.csv")
    return profiles["pressure"][profiles["increment"] == profiles["increment"].max()]


def _differences(every_dir: Path, jump_dir: Path) -> dict[str, float]:
    """Largest differences of two final states (serial runs: one rank's plastic arrays)."""
    every, jump = _state(every_dir), _state(jump_dir)
    eq = lambda e: np.sqrt(2 / 3) * np.linalg.norm(e, axis=1)  # noqa: E731 - the equivalent strain
    p_every, p_jump = _last_pressure(every_dir), _last_pressure(jump_dir)
    return {"wear_gap": float(np.abs(every["wear_gap"] - jump["wear_gap"]).max()),
            "wear_gap_max": float(every["wear_gap"].max()),
            "eps_p": float(eq(every["plastic_eps_p"] - jump["plastic_eps_p"]).max()),
            "eps_p_max": float(eq(every["plastic_eps_p"]).max()),
            "p": float(np.abs(every["plastic_p"] - jump["plastic_p"]).max()),
            "p_max": float(every["plastic_p"].max()),
            "pressure": float(np.abs(p_every - p_jump).max()), "pressure_max": float(p_every.max())}


def measure(scene: str, cycles: int, compare_cycles: int, work: Path) -> dict:
    from dolfinx_fretting.contact_output import read_table

    long_dir, every_dir, jump_dir = work / f"{scene}-{cycles}", work / f"{scene}-every", work / f"{scene}-jump"
    result: dict = {"scene": scene}
    result["wall_s"] = _run(scene, long_dir, cycles, True)
    summary = json.loads((long_dir / "summary.json").read_text())
    table = read_table(long_dir / "cycles.csv")
    result["long"] = {"cycles": summary["cycles"], "simulated": summary["cycle_jump"]["simulated_cycles"],
                      "largest_jump": summary["cycle_jump"]["largest_jump"],
                      "max_wear_depth": summary["max_wear_depth"],
                      "wear_error_estimate": summary["cycle_jump"]["wear_error_estimate"],
                      "plastic_error_estimate": summary["cycle_jump"]["plastic_error_estimate"],
                      "max_equivalent_plastic_strain": summary["max_equivalent_plastic_strain"],
                      "max_pressure_end": float(table["max_pressure_end"][-1]),
                      "cycles_wall_s": float(table["wall_time_s"].sum()),
                      "bounds": dict(collections.Counter(table["jump_bound"].tolist())),
                      "regimes": dict(collections.Counter(table["plastic_regime"].tolist()))}
    result["every_wall_s"] = _run(scene, every_dir, compare_cycles, False)
    result["jump_wall_s"] = _run(scene, jump_dir, compare_cycles, True)
    jumped = json.loads((jump_dir / "summary.json").read_text())
    result["compare"] = {"cycles": compare_cycles, "simulated": jumped["cycle_jump"]["simulated_cycles"],
                         "wear_error_estimate": jumped["cycle_jump"]["wear_error_estimate"],
                         "plastic_error_estimate": jumped["cycle_jump"]["plastic_error_estimate"],
                         **_differences(every_dir, jump_dir)}
    return result


def _markdown(results: list[dict], argv: list[str], load: float) -> str:
    L = ["# Elastic-plastic cycle jumps: 10^4 cycles timed, and the error against every cycle", "",
         f"Command: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_plastic_jump.py {shlex.join(argv)}`  ",
         f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}, {platform.node()}, {os.cpu_count()} "
         f"cores (load average at the end {load:.1f}).  ",
         "Scenes: two deformable bodies, 10 um contact elements, the real k (8.5e-9 1/MPa), the paper's Example 2 "
         "material (`" + " ".join(f"--set {s}" for s in PLASTIC[:3]) + "`), `wear.cycle_jump = true` with the "
         "defaults (wear 0.1 h, pressure 5 %, plastic 0.1 of the yield point per jump, shakedown tolerance 1e-3 "
         "of the yield strain). Each run is one CLI process (wall time: set-up, mesh, W, preload, cycles, "
         "outputs).", "",
         "## The long runs", "",
         "| scene | cycles | wall (s) | simulated | largest jump | max wear depth (mm) | wear estimate (mm) | "
         "plastic estimate | max p | p_max end (MPa) |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in results:
        g = r["long"]
        L.append(f"| `{r['scene']}` | {g['cycles']} | {r['wall_s']:.0f} | {g['simulated']} | {g['largest_jump']} | "
                 f"{g['max_wear_depth']:.4e} | {g['wear_error_estimate']:.2e} | {g['plastic_error_estimate']:.2e} | "
                 f"{g['max_equivalent_plastic_strain']:.4f} | {g['max_pressure_end']:.1f} |")
    L += ["", "Simulated cycles by the bound that set their jump, and by plastic regime:", ""]
    for r in results:
        g = r["long"]
        L.append(f"* `{r['scene']}`: " + ", ".join(f"{k} {v}" for k, v in sorted(g["bounds"].items(),
                                                                                 key=lambda kv: -kv[1]))
                 + "; " + ", ".join(f"{k} {v}" for k, v in sorted(g["regimes"].items(), key=lambda kv: -kv[1])))
    L += ["", "## Jumped against every cycle", "",
          "The first cycles of each scene every cycle and jumped; the largest differences of the final states "
          "(contacts, quadrature points) against the jumped run's accumulated estimates.", "",
          "| scene | cycles | simulated | every / jumped wall (s) | wear gap: diff / estimate / max (mm) | "
          "eps_p: diff / max | p: diff / max | plastic estimate | pressure: diff / max (MPa) |",
          "|---|---:|---:|---:|---|---|---|---:|---|"]
    for r in results:
        c = r["compare"]
        L.append(f"| `{r['scene']}` | {c['cycles']} | {c['simulated']} | {r['every_wall_s']:.0f} / "
                 f"{r['jump_wall_s']:.0f} | {c['wear_gap']:.2e} / {c['wear_error_estimate']:.2e} / "
                 f"{c['wear_gap_max']:.3e} | {c['eps_p']:.2e} / {c['eps_p_max']:.4f} | {c['p']:.2e} / "
                 f"{c['p_max']:.4f} | {c['plastic_error_estimate']:.2e} | {c['pressure']:.3g} / "
                 f"{c['pressure_max']:.1f} |")
    return "\n".join(L) + "\n"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cycles", type=int, default=10000)
    ap.add_argument("--compare-cycles", type=int, default=100)
    ap.add_argument("--scenes", nargs="+", default=["cylinder-flat", "cylinder-flat-partial"])
    ap.add_argument("--work", default="/tmp/bench_plastic_jump", help="folder for the runs (kept)")
    ap.add_argument("--out", default=str(HERE / "results" / "plastic_jump.md"))
    args = ap.parse_args(argv)
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    results = [measure(scene, args.cycles, args.compare_cycles, work) for scene in args.scenes]
    text = _markdown(results, argv, os.getloadavg()[0])
    Path(args.out).write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps(results, indent=1))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
