"""Madge et al.'s trend on the fretting-fatigue rig (issue 24, a study, not a test): the life by SWT with Miner's
sum over a wear run against the slip amplitude, in partial and in gross slip.

Madge, Leen, McColl & Shipway (Wear 262, 2007; IJF 29, 2007) found the fretting-fatigue life falls with the slip
amplitude in partial slip and rises again in gross slip, where wear removes the trailing edge's stress
concentration (and the material that carries the damage). Here: the ``pad-specimen`` scene on a CI-sized mesh
(``geometry.contact_mesh_size = 0.04`` mm, a/9.5), the pad rubbed by a tangential displacement amplitude delta
(``loading.tangential_displacement``) without bulk stress (see ``RIG``), Archard wear on both bodies (k the scene's
key, 2.75e-8 1/MPa, quoted as Madge's Ti-6Al-4V value: not checked against the paper), cycle jumps, ``[fatigue]``
on the specimen (its default body) at every simulated cycle with Al 2024-like strain-life constants
(sigma_f = 900 MPa, b = -0.102, eps_f = 0.22, c = -0.59: representative, NOT checked against a source; E from the
scene). The life: the run's initiation cycle (Miner's sum reaching 1) or, if the run ends first, the run's cycles /
the largest damage (the last block's rate held: an estimate, marked). The published comparison (the papers' inputs
and lives) is not made: results/fatigue_slip.md says why; tests/test_pad_specimen_trend.py asserts the trend.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_fatigue_slip.py [--deltas 0.0002 0.0004 ...]
        [--cycles 100000] [--jump-max 1000000] [--out benchmarks/results/fatigue_slip]
"""

from __future__ import annotations

import argparse
import csv
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from _machine import cpu_model  # noqa: E402

from dolfinx_fretting._dolfinx import DOLFINX_VERSION  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import run_scene  # noqa: E402

#: The CI-sized rig, rubbed by a displacement, worn, with cycle jumps (the jump's own bounds decide its length).
#: No bulk stress: under a displacement amplitude the specimen's stretch by sigma_B (~20 um at the contact for the
#: scene's 92.7 MPa over the 20 mm from the grip) would slide it under the pad, so delta would not set the slip; the
#: refined zone widened to 1.5 mm, as gross-slip wear widens the contact (0.8 mm was reached at 0.2 um, 38k cycles).
RIG = ["geometry.contact_mesh_size=0.04", "geometry.contact_half_width=1.5", "loading.tangential_force=none",
       "loading.bulk_stress=none", "wear.law='archard'", "wear.k=2.75e-8",
       "wear.cycle_jump=true", "wear.jump_max=20000", "output.xdmf=false", "output.plots=false",
       "output.contact_profiles=false", "output.progress=false"]
FATIGUE = ["fatigue.enabled=true", "fatigue.region=0.1", "fatigue.cycles=1", "fatigue.sigma_f=900.0",
           "fatigue.b=-0.102", "fatigue.eps_f=0.22", "fatigue.c=-0.59"]


def run_once(delta: float, cycles: int, jump_max: int | None = None) -> dict:
    extra = [] if jump_max is None else [f"wear.jump_max={jump_max}"]   # later overrides win
    scene = load_scene("pad-specimen", RIG + FATIGUE + extra + [f"loading.tangential_displacement={delta}",
                                                                 f"loading.cycles={cycles}"])
    with tempfile.TemporaryDirectory() as out:
        started = time.perf_counter()
        summary = run_scene(scene, out, quiet=True)
        wall = time.perf_counter() - started
        with open(Path(out) / "cycles.csv") as table:   # the last simulated cycle's extremes
            last = list(csv.DictReader(table))[-1]
    assert summary["converged"], summary.get("error")
    f = summary["fatigue"]
    damage = f["miner_damage_max"]
    initiated = f["initiation_cycles"] is not None
    life = f["initiation_cycles"] if initiated else (cycles / damage if damage else float("inf"))
    return {"delta_mm": delta, "cycles": cycles, "simulated_cycles": summary["cycle_jump"]["simulated_cycles"],
            "regime": summary["regime"], "max_relative_tangential_mm": summary["max_relative_tangential"],
            "tangential_force_max": float(last["tangential_force_max"]), "max_wear_depth_mm": summary["max_wear_depth"],
            "swt_max_last": f["swt_max"], "swt_x_last": f["swt_x"], "miner_damage_max": damage,
            "life": life, "life_estimated": not initiated, "initiation_x": f["initiation_x"], "wall_s": wall}


def table(rows: list[dict]) -> str:
    lines = ["| delta (um) | regime | Q max, last cycle (N/mm) | slip max (um) | max wear (um) | simulated cycles | "
             "SWT max, last (MPa) | Miner D at the end | life (cycles) | wall (s) |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        life = f"{r['life']:.3g}" + (" (est.)" if r["life_estimated"] else "")
        lines.append(f"| {r['delta_mm'] * 1e3:g} | {r['regime']} | {r['tangential_force_max']:.4g} | "
                     f"{r['max_relative_tangential_mm'] * 1e3:.3g} | "
                     f"{r['max_wear_depth_mm'] * 1e3:.3g} | {r['simulated_cycles']} | {r['swt_max_last']:.4g} | "
                     f"{r['miner_damage_max']:.3g} | {life} | {r['wall_s']:.0f} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--deltas", nargs="+", type=float,
                        default=[0.0001, 0.0004, 0.001, 0.003, 0.005, 0.008, 0.01, 0.012, 0.02, 0.03, 0.05])
    parser.add_argument("--cycles", type=int, default=10000)
    parser.add_argument("--jump-max", type=int, default=None,
                        help="wear.jump_max instead of RIG's 20000 (longer runs: lives to Miner's sum 1)")
    parser.add_argument("--out", type=Path, default=HERE / "results" / "fatigue_slip")
    args = parser.parse_args()
    rows = []
    for delta in args.deltas:
        rows.append(run_once(delta, args.cycles, args.jump_max))
        print(json.dumps(rows[-1]), flush=True)
    machine = {"cpu": cpu_model(), "python": platform.python_version(), "dolfinx": DOLFINX_VERSION,
               "command": " ".join(["benchmarks/bench_fatigue_slip.py", *sys.argv[1:]])}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".json").write_text(json.dumps({"machine": machine, "rows": rows}, indent=1) + "\n")
    print(table(rows))


if __name__ == "__main__":
    main()
