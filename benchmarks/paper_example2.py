"""The paper's Figs 13-19 on the two-body Example 2: elastic against elastic-plastic, gross and partial slip,
the real and the hundredfold wear coefficient, with the paper's quoted numbers and trends beside ours.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/paper_example2.py --out results/paper_example2 \
        --report docs/paper-example2.md

Runs the eight scenes (``dolfinx-fretting run``; a run whose ``summary.json`` says it converged with the
asked cycles is reused), draws each pair with ``dolfinx-fretting compare`` (the paper's figures: wear gap and
pressure after the first cycle and over the cycles, the centre node's history) and writes the report: one
table of measured numbers per run, then the paper's statements point by point with what we measured.
"""

from __future__ import annotations

import argparse
import json
import platform
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from dolfinx_fretting.contact_output import read_profiles  # noqa: E402

PLASTIC = ["material.model='elastoplastic'", "material.yield_stress=840", "material.hardening_modulus=7230"]
#: (scene, slip regime label); the paper's partial-slip k is 4.5e-8 1/MPa, gross 8.5e-9 (the scenes' defaults).
CASES = {"gross": "cylinder-flat", "partial": "cylinder-flat-partial"}
#: Paper, section 8.2: first-cycle elastic-plastic peak pressures (MPa).
PAPER_PEAK = {"gross": 747.4, "partial": 788.3}
#: Wear gap above this fraction of its maximum counts towards the wear width (the scar's extent).
WEAR_WIDTH_FRACTION = 0.01


def run_name(regime: str, plastic: bool, acceleration: int) -> str:
    return f"{regime}_{'ep' if plastic else 'el'}_k{acceleration}"


def run(out: Path, regime: str, plastic: bool, acceleration: int, cycles: int) -> Path:
    folder = out / "runs" / run_name(regime, plastic, acceleration)
    summary = folder / "summary.json"
    if summary.is_file():
        s = json.loads(summary.read_text())
        if s.get("converged") and s.get("cycles") == cycles:
            return folder
    snapshots = sorted({1, min(10, cycles), cycles})
    sets = [f"loading.cycles={cycles}", f"wear.acceleration={acceleration}", f"output.snapshot_cycles={snapshots}",
            f"output.loop_cycles={sorted({1, cycles})}"] + (PLASTIC if plastic else [])
    cmd = [sys.executable, "-m", "dolfinx_fretting", "run", CASES[regime], "--out", str(folder), "--quiet",
           "--overwrite"]
    for s in sets:
        cmd += ["--set", s]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True)
    print(f"{folder.name}: {time.perf_counter() - t0:.0f} s", flush=True)
    return folder


def end_of_cycle(profiles, cycle: int) -> int:
    rows = profiles.rows_of_cycle(cycle)
    return int(rows[-1])


def measures(folder: Path, cycle: int) -> dict[str, float]:
    """Pressure and wear at the end of ``cycle`` (cycle 0: the end of the preload)."""
    p = read_profiles(folder / "contact_profiles.csv")
    i = end_of_cycle(p, cycle)
    x, pressure, wear = p.position, p.values["pressure"][i], p.values["wear"][i]
    loaded = np.flatnonzero(pressure > 0)
    j = int(np.nanargmax(pressure))
    w_max = float(np.nanmax(wear))
    worn = np.flatnonzero(wear > WEAR_WIDTH_FRACTION * w_max) if w_max > 0 else np.array([], int)
    centre = int(np.argmin(np.abs(x)))
    return {"peak": float(pressure[j]), "peak_at": float(x[j]),
            "centroid": float(np.sum(x * pressure) / np.sum(pressure)),
            "contact_width": float(x[loaded[-1]] - x[loaded[0]]) if loaded.size else 0.0,
            "centre_pressure": float(pressure[centre]),
            "max_wear": w_max, "wear_width": float(x[worn[-1]] - x[worn[0]]) if worn.size else 0.0}


def verdict(ok: bool) -> str:
    return "agrees" if ok else "**differs**"


def report(out: Path, cycles: int, folders: dict, times: dict, target: Path) -> None:
    mid = min(10, cycles)
    m = {key: {c: measures(f, c) for c in sorted({0, 1, mid, cycles})} for key, f in folders.items()}
    lines = ["# The paper's Example 2, Figs 13-19, on the two-body model",
             "",
             f"Command: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/paper_example2.py --out {out} "
             f"--report {target}`  ",
             f"Date: {time.strftime('%Y-%m-%dT%H:%M:%S')}, {platform.node()}, {platform.machine()}, 2 cores shared "
             "with other jobs.  ",
             "Scenes `cylinder-flat` (gross slip, delta = 0.03 mm, 80 increments, k = 8.5e-9 1/MPa) and "
             "`cylinder-flat-partial` (partial slip, delta = 0.01 mm, 64 increments, k = 4.5e-8 1/MPa): a cylinder "
             "R = 6 mm on a flat of the same material (two deformable bodies, 10 um contact elements), "
             "P = 199.24 N/mm; elastic-plastic: J2, sigma_y = 840 MPa, H = 7230 MPa (the paper's Table 2); x100: "
             f"`wear.acceleration=100`. {cycles} cycles each. Pressures and wear are taken at the end of a cycle "
             f"(delta back to 0); wear width: where the wear gap exceeds {WEAR_WIDTH_FRACTION:g} of its maximum.",
             "",
             "| run | wall (s) | cycle | peak p (MPa) | at x (mm) | pressure centroid (mm) | contact width (mm) | "
             "max wear gap (mm) | wear width (mm) |",
             "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for key, per in m.items():
        for c, v in per.items():
            lines.append(f"| {key} | {times[key]:.0f} | {c if c else 'preload'} | {v['peak']:.1f} | {v['peak_at']:+.4f} | "
                         f"{v['centroid']:+.5f} | {v['contact_width']:.3f} | {v['max_wear']:.3e} | "
                         f"{v['wear_width']:.3f} |")

    def g(regime, plastic, acc, c, key):
        return m[run_name(regime, plastic, acc)][c][key]

    rows = []
    for regime, fig in (("gross", "13"), ("partial", "17")):
        ours = g(regime, True, 1, 1, "peak")
        paper = PAPER_PEAK[regime]
        rows.append((f"Fig. {fig}", f"{regime} slip, elastic-plastic peak pressure after the first cycle: "
                     f"{paper} MPa", f"{ours:.1f} MPa ({100 * (ours / paper - 1):+.1f} %)",
                     verdict(abs(ours / paper - 1) < 0.03)))
    e0, e1 = m[run_name("gross", False, 1)][0], m[run_name("gross", False, 1)][1]
    rows.append(("Fig. 13", "gross, elastic: the pressure after the first cycle is almost the preload's but moves "
                 "a little to the left",
                 f"peak {e0['peak']:.1f} -> {e1['peak']:.1f} MPa; centroid {e0['centroid']:+.5f} -> "
                 f"{e1['centroid']:+.5f} mm", verdict(abs(e1['peak'] / e0['peak'] - 1) < 0.02
                                                       and e1['centroid'] < e0['centroid'])))
    for regime, fig, c in (("gross", "13", 1), ("gross", "15", cycles)):
        el, ep = g(regime, False, 1, c, "max_wear"), g(regime, True, 1, c, "max_wear")
        wl, wp = g(regime, False, 1, c, "wear_width"), g(regime, True, 1, c, "wear_width")
        rows.append((f"Fig. {fig}", f"gross, cycle {c}: max wear gap elastic-plastic < elastic, wear width "
                     "elastic-plastic > elastic", f"max wear {ep:.3e} vs {el:.3e} mm; width {wp:.3f} vs {wl:.3f} mm",
                     verdict(ep < el and wp > wl)))
    pe1, pec = g("gross", False, 1, 1, "peak"), g("gross", False, 1, cycles, "peak")
    pp1, ppc = g("gross", True, 1, 1, "peak"), g("gross", True, 1, cycles, "peak")
    rows.append(("Fig. 15", f"gross, real k: pressures decrease a little by cycle {cycles} (wear gap ~1e-5 mm)",
                 f"elastic {pe1:.1f} -> {pec:.1f}, elastic-plastic {pp1:.1f} -> {ppc:.1f} MPa; max wear "
                 f"{g('gross', False, 1, cycles, 'max_wear'):.2e} mm",
                 verdict(pec < pe1 and ppc < pp1 and pec > 0.9 * pe1)))
    for plastic in (False, True):
        p1, p10, pc = (g("gross", plastic, 100, c, "peak") for c in (1, mid, cycles))
        w1, wc = g("gross", plastic, 100, 1, "contact_width"), g("gross", plastic, 100, cycles, "contact_width")
        rows.append(("Fig. 16", f"gross, x100 k, {'elastic-plastic' if plastic else 'elastic'}: the peak falls "
                     "obviously by cycle 10 and keeps falling while the contact widens",
                     f"peak {p1:.1f} -> {p10:.1f} -> {pc:.1f} MPa; contact width {w1:.3f} -> {wc:.3f} mm",
                     verdict(p10 < 0.95 * p1 and pc < p10 and wc > w1)))
    pe, pp = g("gross", False, 100, cycles, "peak"), g("gross", True, 100, cycles, "peak")
    pe_1, pp_1 = g("gross", False, 100, 1, "peak"), g("gross", True, 100, 1, "peak")
    rows.append(("Fig. 16", f"gross, x100 k: at cycle {cycles} both materials' pressures become similar",
                 f"peaks {pe:.1f} vs {pp:.1f} MPa ({100 * abs(pe - pp) / pe:.1f} % apart; cycle 1: "
                 f"{100 * abs(pe_1 - pp_1) / pe_1:.1f} %)", verdict(abs(pe - pp) / pe < abs(pe_1 - pp_1) / pe_1)))
    p0, p1 = g("partial", False, 1, 0, "peak"), g("partial", False, 1, 1, "peak")
    rows.append(("Fig. 17", "partial, elastic: the pressure after the first cycle is almost the preload's",
                 f"peak {p0:.1f} -> {p1:.1f} MPa", verdict(abs(p1 / p0 - 1) < 0.01)))
    el, ep = g("partial", False, 1, 1, "max_wear"), g("partial", True, 1, 1, "max_wear")
    rows.append(("Fig. 17", "partial, cycle 1: max wear gap elastic-plastic > elastic (unlike gross slip)",
                 f"{ep:.3e} vs {el:.3e} mm", verdict(ep > el)))
    r1 = g("partial", True, 1, 1, "max_wear") / g("partial", False, 1, 1, "max_wear")
    rc = g("partial", True, 1, cycles, "max_wear") / g("partial", False, 1, cycles, "max_wear")
    rows.append(("Fig. 18", "partial, real k: elastic-plastic's max wear gap falls behind elastic's gradually",
                 f"ratio elastic-plastic / elastic {r1:.3f} (cycle 1) -> {rc:.3f} (cycle {cycles})", verdict(rc < r1)))
    pe1, pec = g("partial", False, 1, 1, "peak"), g("partial", False, 1, cycles, "peak")
    rows.append(("Fig. 18", f"partial, real k, elastic: the pressure stays almost the same over {cycles} cycles",
                 f"peak {pe1:.1f} -> {pec:.1f} MPa", verdict(abs(pec / pe1 - 1) < 0.02)))
    r1 = g("partial", True, 100, 1, "max_wear") / g("partial", False, 100, 1, "max_wear")
    rc = g("partial", True, 100, cycles, "max_wear") / g("partial", False, 100, cycles, "max_wear")
    rows.append(("Fig. 19", "partial, x100 k: elastic-plastic's max wear gap catches up with and exceeds "
                 "elastic's gradually", f"ratio {r1:.3f} (cycle 1) -> {rc:.3f} (cycle {cycles})",
                 verdict(rc > 1.0)))
    for plastic in (False, True):
        v = m[run_name("partial", plastic, 100)][cycles]
        rows.append(("Fig. 19", f"partial, x100 k, {'elastic-plastic' if plastic else 'elastic'}: "
                     + ("the peak sits between the sticking and sliding regions" if not plastic
                        else "no such peak (plasticity smooths the pressure)"),
                     f"peak {v['peak']:.1f} MPa at x = {v['peak_at']:+.4f} mm, centre {v['centre_pressure']:.1f} MPa",
                     verdict((v["peak"] > 1.05 * v["centre_pressure"]) != plastic)))
    lines += ["", "## The paper's statements, point by point", "",
              "| figure | the paper (section 8.2) | ours | |", "| --- | --- | --- | --- |"]
    lines += [f"| {a} | {b} | {c} | {d} |" for a, b, c, d in rows]
    lines += ["", "Where we differ: in partial slip the paper's elastic-plastic peak after the first cycle falls to "
              "788.3 MPa; ours rises a little above the elastic one (841.1 against 830.6 MPa; why is not settled). "
              "The paper's flat is not given (McColl's specimen; ours 20 x 10 mm) "
              "and it pressed by u = 0.008 mm, which gives 176.4 N/mm here against the 199.24 N/mm we prescribe "
              "(Hertz peak 781 MPa instead of 830 MPa at that force): the two set-ups do not share the preload, so the "
              "partial-slip numbers are compared as trends. Wear widths are resolved to one 10 um element (two nodes "
              "at the edges of a 0.3 mm contact)."]
    lines += ["", "## Pictures", "", "`dolfinx-fretting compare`, elastic against elastic-plastic: wear gap and "
              "pressure at the end of cycles 1, 10 and 100.", ""]
    lines += [f"![{p.stem}](paper-example2/{p.name})" for p in sorted(target.parent.glob("paper-example2/*.png"))]
    lines += [""]
    target.write_text("\n".join(lines) + "\n")
    print(target.read_text())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/paper_example2"))
    ap.add_argument("--cycles", type=int, default=100)
    ap.add_argument("--report", type=Path, default=Path("docs/paper-example2.md"))
    args = ap.parse_args()
    folders, times = {}, {}
    for regime in CASES:
        for acc in (1, 100):
            for plastic in (False, True):
                key = run_name(regime, plastic, acc)
                t0 = time.perf_counter()
                folders[key] = run(args.out, regime, plastic, acc, args.cycles)
                times[key] = json.loads((folders[key] / "summary.json").read_text()).get(
                    "wall_time_s", time.perf_counter() - t0)
    pictures = args.report.parent / "paper-example2"
    pictures.mkdir(parents=True, exist_ok=True)
    for regime in CASES:
        for acc in (1, 100):
            pair = [folders[run_name(regime, p, acc)] for p in (False, True)]
            cmp_out = args.out / f"compare_{regime}_k{acc}"
            subprocess.run([sys.executable, "-m", "dolfinx_fretting", "compare", *map(str, pair), "--out", str(cmp_out),
                            "--labels", "elastic,elastic-plastic", "--cycles", ",".join(map(str, sorted({1, min(10, args.cycles), args.cycles})))], check=True,
                           stdout=subprocess.DEVNULL)
            shutil.copy(cmp_out / "compare_cycles.png", pictures / f"{regime}_k{acc}_cycles.png")
    report(args.out, args.cycles, folders, times, args.report)


if __name__ == "__main__":
    main()
