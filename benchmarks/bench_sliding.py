"""What the fixed (small-sliding) pairing costs against re-pairing as the bodies slide (finite sliding).

For each scene, ``dolfinx-fretting study`` runs the finite-sliding model as the reference (the scene's own
numerics otherwise) and the fixed pairing as the one swept point, so the four study errors (maximum wear, worn
profile, peak pressure, energy) are the fixed pairing's; the runs' summaries add what only the finite model
resolves: the flat's own wear (depth and scar width, where the master wears) and the number of re-pairings.
The errors are set beside the scene's discretisation error (its contact elements against half of them) from
the trade studies in ``benchmarks/results/study_<scene>.md``.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding.py [--scenes cylinder-flat mccoll] \
        [--work /tmp/bench_sliding] [--out benchmarks/results/sliding]
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import os
import platform
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: Each scene's horizon: cylinder-flat's 100 cycles as written; McColl's first 1000 physical cycles (40 simulated
#: at the scene's wear acceleration 25), the horizon of its trade study.
SCENES = {"cylinder-flat": [], "mccoll": ["loading.cycles=40"]}
ERRORS = ("err_max_wear", "err_wear_l2", "err_peak_pressure", "err_energy")
FROM_SUMMARY = ("max_wear_depth", "max_wear_depth_slave", "max_wear_depth_master", "master_scar_width", "repairs",
                "max_pressure", "dissipated_energy", "contact_width", "wall_time_s")


def run(scene: str, overrides: list[str], work: Path) -> dict:
    """One study: the finite model as reference, the fixed pairing swept; returns its table and summaries."""
    out = work / scene
    command = [str(Path(sys.executable).parent / "dolfinx-fretting"), "study", scene, "--out", str(out),
               "--overwrite", "--quiet", "--reference", "contact.sliding=finite", "--sweep", "contact.sliding=small"]
    for item in overrides:
        command += ["--set", item]
    subprocess.run(command, check=True)
    with open(out / "study.csv") as f:
        rows = list(csv.DictReader(f))
    runs = {}
    for model, label in (("finite", "reference"), ("small", "sliding=small")):
        summary = json.loads((out / "runs" / label / "summary.json").read_text())
        runs[model] = {k: summary.get(k) for k in FROM_SUMMARY}
    return {"command": " ".join(command), "study": rows, "runs": runs}


def table(scene: str, result: dict) -> list[str]:
    small = next(r for r in result["study"] if "sliding" in r["label"] and r["label"] != "reference")
    ref, fixed = result["runs"]["finite"], result["runs"]["small"]
    lines = [f"### `{scene}`", "", f"Command: `{result['command']}`", "",
             "| quantity | finite sliding (reference) | fixed pairing | difference |", "| --- | ---: | ---: | ---: |"]
    for key in FROM_SUMMARY:
        a, b = ref.get(key), fixed.get(key)
        if a is None and b is None:
            continue
        diff = "" if not (isinstance(a, (int, float)) and isinstance(b, (int, float)) and a) else f"{(b - a) / a:+.3%}"
        lines.append(f"| {key} | {a:.6g} | {b:.6g} | {diff} |" if isinstance(a, float) and isinstance(b, float)
                     else f"| {key} | {a} | {b} | {diff} |")
    lines += ["", "Study errors of the fixed pairing against the finite model: "
              + ", ".join(f"{k[4:]} {float(small[k]):.3g}" for k in ERRORS if small.get(k) not in (None, "")), ""]
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", nargs="+", default=list(SCENES))
    parser.add_argument("--work", default="/tmp/bench_sliding")
    parser.add_argument("--out", default=str(HERE / "results" / "sliding"))
    args = parser.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    results = {scene: run(scene, SCENES[scene], work) for scene in args.scenes}
    load = os.getloadavg()
    header = ["# Fixed pairing against finite sliding (two elastic bodies)", "",
              f"Command: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_sliding.py "
              f"--scenes {' '.join(args.scenes)}`", "",
              f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}; machine: {platform.machine()}, "
              f"{os.cpu_count()} cores; load average at the end {load[0]:.2f} / {load[1]:.2f} / {load[2]:.2f}.", "",
              "What these numbers decide (which scenes re-pair): `benchmarks/README.md`, \"Fixed pairing against "
              "finite sliding\".", ""]
    body = [line for scene, result in results.items() for line in table(scene, result)]
    Path(args.out + ".md").write_text("\n".join(header + body) + "\n")
    Path(args.out + ".json").write_text(json.dumps(results, indent=1) + "\n")
    print("\n".join(header + body))


if __name__ == "__main__":
    main()
