"""Elastic-plastic cylinder-flat (the paper's Example 2: two deformable bodies, gross slip, Table 2 material,
10 um contact mesh, 80 increments a cycle): where a cycle's time goes, and the cost of the Newton iteration
matrices against full Newton.

Two sub-commands; every run is a subprocess with ``PYTHONPATH`` set to a package tree, so that two trees
(this one and e.g. ``/work/main``) run side by side in one invocation on the same machine load:

``profile``
    One run, instrumented: wall time inside each part of the Newton loop (factorisations, W rebuilds,
    linear solves, tangent and residual assembly, strain evaluation, return mapping, contact solves, the
    rest of the loop), counted only inside ``ElastoplasticBody.increment``, per cycle, with the counts
    (Newton iterations, refactorisations, selected inverses: W_T rebuilds or zone builds, linear and
    local solves). Writes ``results/plastic_profile.md``.
``compare``
    Runs the ``--runs`` configurations (tree:tangent, e.g. ``before:adaptive``) and writes per-cycle times
    (wall and process CPU), their ratio against the first run, and the differences of the peak pressure,
    pressure profile and wear profile at the end of every cycle against the ``--reference`` run (full
    Newton, ``solver.newton_tangent=consistent``), at full precision (taken from the run's state, not the
    10-digit CSVs). ``--before COMMIT`` extracts that commit's package (``git archive``) for the runs on
    tree ``before``; ``--repeat N`` runs every configuration N times in alternating order and keeps each
    cycle's minimum time. Writes ``results/plastic.md`` and ``.json``.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_plastic.py profile --cycles 3
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_plastic.py compare --cycles 10 --before c1eb8dc --repeat 2
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

#: The elastic-plastic Example 2 (gross slip) as the issue states it, without the outputs that cost time.
PLASTIC = ["material.model=elastoplastic", "material.yield_stress=840", "material.hardening_modulus=7230",
           "output.xdmf=false", "output.plots=false", "output.progress=false"]

SELECTED = "selected inverse: W_T rebuild / the zone's (K^-1)_XX"
#: (module, class or None, attribute, category) timed inside ``ElastoplasticBody.increment``; an entry
#: missing from a tree is skipped (both trees are measured with the same table).
TIMED = [
    ("compliance", "DelassusOperator", "factorize", "factorisation (symbolic + numeric)"),
    ("compliance", "DelassusOperator", "refactorize", "refactorisation (numeric)"),
    ("compliance", "DelassusOperator", "build", SELECTED),
    ("plasticity", "PlasticState", "create_tangent", "tangent assembly"),
    ("plasticity", "PlasticState", "assemble_tangent", "tangent assembly"),
    ("compliance", "DelassusOperator", "solve", "linear solves (MUMPS)"),
    ("plasticity", "ElastoplasticBody", "_verify", "check of the converged iterate on the whole body (glue)"),
    ("plasticity", "PlasticState", "update", "state update of all points (glue)"),
    ("plasticity", "PlasticState", "strain", "strain at all points (fem.Expression)"),
    ("plasticity", None, "return_mapping", "return mapping at all points (numba)"),
    ("plasticity", "PlasticState", "assemble_residual", "residual assembly"),
    ("plasticity", "PlasticZone", "_build", "zone (re)build (glue: B matrices, HZ)"),
    ("plasticity", "PlasticZone", "evaluate", "zone: strains, return mapping, plastic forces (numba)"),
    ("plasticity", "PlasticZone", "tangent", "zone: low-rank tangent (D, LU, W_T)"),
    ("plasticity", "PlasticZone", "inverse_of", "zone: Z g (rows where g changed)"),
    ("plasticity", "ElastoplasticBody", "_solve_condensed", "whole-body solves (condensed path)"),
    ("problem", "FrettingProblem", "_local_with_control", "contact solve: load control (Python)"),
    ("local_solvers", None, "solve", "contact solve: local solver calls"),
]
#: Categories nested in others: reported exclusive of their children.
NESTED = {"state update of all points (glue)": ["strain at all points (fem.Expression)",
                                                "return mapping at all points (numba)"],
          "check of the converged iterate on the whole body (glue)": ["state update of all points (glue)",
                                                                      "residual assembly",
                                                                      "zone (re)build (glue: B matrices, HZ)"],
          "zone (re)build (glue: B matrices, HZ)": [SELECTED],
          "contact solve: load control (Python)": ["contact solve: local solver calls"],
          "whole-body solves (condensed path)": ["linear solves (MUMPS)"]}


# ------------------------------------------------------------------------------------------------------
# The measured run (child process)
# ------------------------------------------------------------------------------------------------------
def child(spec: dict) -> dict:
    """Run the scene of ``spec`` with the package of ``spec['tree']``; return times, counts and profiles."""
    sys.path.insert(0, spec["tree"])
    import importlib

    from dolfinx_fretting import simulation as sim
    from dolfinx_fretting.scenes import load_scene

    assert Path(sim.__file__).resolve().is_relative_to(Path(spec["tree"]).resolve()), sim.__file__
    times: dict[str, float] = {}
    calls: dict[str, int] = {}
    inside = [0]

    def timed(fn, key):
        def wrapper(*args, **kwargs):
            if not inside[0]:
                return fn(*args, **kwargs)
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                times[key] = times.get(key, 0.0) + time.perf_counter() - t0
                calls[key] = calls.get(key, 0) + 1
        return wrapper

    if spec.get("instrument", True):
        for mod, cls, attr, key in TIMED:
            owner = importlib.import_module(f"dolfinx_fretting.{mod}")
            if cls is not None:
                owner = getattr(owner, cls, None)
            if owner is not None and callable(getattr(owner, attr, None)):
                setattr(owner, attr, timed(getattr(owner, attr), key))

    from dolfinx_fretting import plasticity

    increment = plasticity.ElastoplasticBody.increment
    newton = {"increments": 0, "failed": 0, "time": 0.0}

    def counted_increment(self, local_solve, pressure):
        inside[0] += 1
        newton["increments"] += 1
        t0 = time.perf_counter()
        try:
            return increment(self, local_solve, pressure)
        except plasticity.NewtonError:
            newton["failed"] += 1
            raise
        finally:
            newton["time"] += time.perf_counter() - t0
            inside[0] -= 1

    plasticity.ElastoplasticBody.increment = counted_increment
    if spec.get("condensed") is not None:
        if not hasattr(plasticity.ElastoplasticBody, "condensed"):
            raise RuntimeError(f"{spec['tree']} has no condensed Newton iteration")
        plasticity.ElastoplasticBody.condensed = spec["condensed"]
    cycles: list[dict] = []
    cycle_row = sim._Run._cycle_row
    clock = {"cpu": time.process_time()}

    def recording_cycle_row(self, cycle, h, wall, jump=None):
        row = cycle_row(self, cycle, h, wall, jump)
        cpu = time.process_time()
        st, cs = self.state, self.model.contact
        body = self.problem.body
        cycles.append({"cycle": cycle, "wall_s": wall, "cpu_s": cpu - clock["cpu"],
                       "max_pressure_end": row["max_pressure_end"], "max_wear_depth": row["max_wear_depth"],
                       "pressure": (st.forces[0::cs.dim] / cs.tributary).tolist(), "wear_gap": st.wear_gap.tolist(),
                       "newton_iterations_history": int(h["newton_iterations"].sum()),
                       "increments": newton["increments"], "failed_increments": newton["failed"],
                       "newton_time_s": newton["time"], "refactorizations": body.refactorizations,
                       "tangent_updates": getattr(body, "tangent_updates", 0),
                       "zone_growths": getattr(body, "zone_growths", 0),
                       "zone_dofs": int(body.zone.X.size) if getattr(body, "zone", None) is not None else 0,
                       "condensed_fallbacks": getattr(body, "condensed_fallbacks", 0),
                       "condensed": bool(getattr(body, "condensed", False)),
                       "times": dict(times), "calls": dict(calls)})
        clock["cpu"] = time.process_time()
        return row

    sim._Run._cycle_row = recording_cycle_row
    run_cycles = sim._Run.run_cycles
    start: dict = {}

    def recording_run_cycles(self):  # the counters at the end of the preload: cycle 1 starts from them
        body = self.problem.body
        start.update({"increments": newton["increments"], "failed_increments": newton["failed"],
                      "newton_time_s": newton["time"], "refactorizations": body.refactorizations,
                      "times": dict(times), "calls": dict(calls)})
        clock["cpu"] = time.process_time()
        return run_cycles(self)

    sim._Run.run_cycles = recording_run_cycles
    scene = load_scene("cylinder-flat", PLASTIC + [f"loading.cycles={spec['cycles']}",
                                                   f"solver.newton_tangent={spec['tangent']}"]
                       + spec.get("extra", []))
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as out:
        summary = sim.run_scene(scene, out, quiet=True)
    return {"spec": spec, "wall_s": time.perf_counter() - t0, "start": start, "cycles": cycles,
            "dofs": summary["dofs"], "contacts": summary["contacts"],
            "max_equivalent_plastic_strain": summary["max_equivalent_plastic_strain"]}


def run_child(spec: dict) -> dict:
    env = dict(os.environ, PYTHONPATH=spec["tree"], OPENBLAS_NUM_THREADS="1")
    p = subprocess.run([sys.executable, str(Path(__file__).resolve()), "_child", json.dumps(spec)], env=env,
                       capture_output=True, text=True, cwd=tempfile.gettempdir())
    if p.returncode != 0:
        raise RuntimeError(f"run {spec} failed:\n{p.stderr[-3000:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def tree_commit(tree: str) -> str:
    marker = Path(tree) / "COMMIT"
    if marker.is_file():  # a tree extracted by checkout()
        return marker.read_text().strip() + " (git archive)"
    p = subprocess.run(["git", "-C", tree, "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
    dirty = subprocess.run(["git", "-C", tree, "status", "--porcelain", "--untracked-files=no", "--",
                            "dolfinx_fretting"], capture_output=True, text=True).stdout.strip()  # the package
    return (p.stdout.strip() or "unknown commit") + (" + uncommitted changes to the package" if dirty else "")


def header(title: str, argv: list[str]) -> list[str]:
    cmd = "OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_plastic.py " + shlex.join(argv)
    load = os.getloadavg()
    return [f"# {title}", "", f"Command: `{cmd}`  ",
            f"Date: {datetime.datetime.now().isoformat(timespec='seconds')}, {platform.node()}, "
            f"{platform.machine()}, {os.cpu_count()} cores shared with other jobs (load average at the end "
            f"{load[0]:.1f}).  ",
            "Scene: `cylinder-flat` " + " ".join(f"--set {s}" for s in PLASTIC[:3])
            + " (two deformable bodies, gross slip 0.03 mm, 80 increments a cycle, 10 um contact mesh).", ""]


# ------------------------------------------------------------------------------------------------------
# profile
# ------------------------------------------------------------------------------------------------------
def exclusive(times: dict[str, float]) -> dict[str, float]:
    """Inclusive timer totals -> exclusive ones (a parent minus its children's inclusive times)."""
    out = dict(times)
    for parent, children in NESTED.items():
        if parent in out:
            out[parent] = out[parent] - sum(times.get(c, 0.0) for c in children)
    return out


def deltas(cycles: list[dict], start: dict) -> list[dict]:
    """Per-cycle increments of the cumulative counters of :func:`child`."""
    out, prev = [], start
    for c in cycles:
        out.append({"cycle": c["cycle"], "wall_s": c["wall_s"], "cpu_s": c["cpu_s"],
                    "newton_s": c["newton_time_s"] - prev["newton_time_s"],
                    "increments": c["increments"] - prev["increments"],
                    "failed": c["failed_increments"] - prev["failed_increments"],
                    "refactorizations": c["refactorizations"] - prev["refactorizations"],
                    "times": {k: v - prev["times"].get(k, 0.0) for k, v in c["times"].items()},
                    "calls": {k: v - prev["calls"].get(k, 0) for k, v in c["calls"].items()}})
        prev = c
    return out


def profile(args, argv) -> int:
    tree = str(Path(args.tree).resolve())
    L = header("Elastic-plastic cylinder-flat: where a cycle's time goes", argv)
    L += [f"Tree: `{tree}` ({tree_commit(tree)}). Times: wall clock, by timers wrapped around the named "
          "functions and counted only inside `ElastoplasticBody.increment` (failed tries included); a nested "
          "category is exclusive of its children. A *Newton call* is one `increment()` (a failed adaptive "
          "try, then its full-Newton retry, are two calls); a *Newton iteration* is one contact solve with its "
          "load control (one per iteration). \"Outside Newton\" is the rest of the cycle (wear update, "
          "history rows, bookkeeping).",
          ""]
    results = []
    for tangent in args.tangent:
        res = run_child({"tree": tree, "cycles": args.cycles, "tangent": tangent})
        results.append(res)
        L += profile_section(res, tangent)
    text = "\n".join(L) + "\n"
    Path(args.out).write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps({"command": argv, "results": results}, indent=1))
    print(text)
    return 0


def profile_section(res: dict, tangent: str) -> list[str]:
    per = deltas(res["cycles"], res["start"])
    L = [f"## `solver.newton_tangent={tangent}`", "",
         f"{res['dofs']} dofs, {res['contacts']} contacts; whole run {res['wall_s']:.1f} s (mesh, set-up, JIT and "
         "preload included).", "", "### Per cycle", "",
          "| cycle | wall (s) | CPU (s) | inside Newton (s) | outside Newton (s) | Newton calls (failed) | "
          "Newton iterations | refactorisations | selected inverses | linear solves: MUMPS / whole-body "
          "(condensed) | local solver calls |",
          "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for d in per:
        c = d["calls"]
        L.append(f"| {d['cycle']} | {d['wall_s']:.2f} | {d['cpu_s']:.2f} | {d['newton_s']:.2f} | "
                 f"{d['wall_s'] - d['newton_s']:.2f} | {d['increments']} ({d['failed']}) | "
                 f"{c.get('contact solve: load control (Python)', 0)} | {d['refactorizations']} | "
                 f"{c.get(SELECTED, 0)} | {c.get('linear solves (MUMPS)', 0)} / "
                 f"{c.get('whole-body solves (condensed path)', 0)} | "
                 f"{c.get('contact solve: local solver calls', 0)} |")
    return L + [""] + breakdown(per)


def breakdown(per: list[dict]) -> list[str]:
    """Where the cycles' time went, by category (exclusive), totals and per cycle."""
    times: dict[str, float] = {}
    calls: dict[str, int] = {}
    for d in per:
        for k, v in d["times"].items():
            times[k] = times.get(k, 0.0) + v
            calls[k] = calls.get(k, 0) + d["calls"].get(k, 0)
    times = exclusive(times)
    newton = sum(d["newton_s"] for d in per)
    wall = sum(d["wall_s"] for d in per)
    n = len(per)
    rest = newton - sum(times.values())
    L = [f"### Breakdown over cycles 1..{n} ({wall:.1f} s of cycles, {newton:.1f} s inside Newton)", "",
         "| category | time (s) | per cycle (s) | share of the cycles' time | calls | ms / call |",
         "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for k, v in sorted(times.items(), key=lambda kv: -kv[1]):
        L.append(f"| {k} | {v:.2f} | {v / n:.3f} | {100 * v / wall:.1f} % | {calls[k]} | "
                 f"{1e3 * v / max(calls[k], 1):.2f} |")
    L.append(f"| rest of the Newton loop (Python: vector copies, norms, allreduce, set_bc) | {rest:.2f} | "
             f"{rest / n:.3f} | {100 * rest / wall:.1f} % | | |")
    L.append(f"| outside Newton (wear, history, bookkeeping) | {wall - newton:.2f} | {(wall - newton) / n:.3f} | "
             f"{100 * (wall - newton) / wall:.1f} % | | |")
    return L + [""]


def checkout(commit: str) -> str:
    """The package of ``commit`` of this repository, extracted into a temporary folder (``git archive``)."""
    full = subprocess.run(["git", "-C", str(HERE.parent), "rev-parse", "--short", commit], capture_output=True,
                          text=True, check=True).stdout.strip()
    folder = Path(tempfile.mkdtemp(prefix=f"bench_plastic_{full}_"))
    archive = subprocess.run(["git", "-C", str(HERE.parent), "archive", full, "dolfinx_fretting"],
                             capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    (folder / "COMMIT").write_text(full + "\n")
    return str(folder)


def parse_run(text: str, before: str | None) -> dict:
    """``label=tree:tangent[:condensed|refactorizing]``; tree ``this`` or ``before`` (``--before``) or a path."""
    label, _, rest = text.partition("=")
    parts = rest.split(":")
    tree = {"this": str(HERE.parent), "before": before}.get(parts[0], parts[0])
    if tree is None:
        raise SystemExit(f"run {text!r} names the 'before' tree: give --before")
    spec = {"label": label, "tree": str(Path(tree).resolve()), "tangent": parts[1]}
    if len(parts) > 2:
        spec["condensed"] = {"condensed": True, "refactorizing": False}[parts[2]]
    return spec


def rel(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def compare(args, argv) -> int:
    before = args.before
    if before is not None and not Path(before).is_dir():
        before = checkout(before)
    specs = [parse_run(t, before) for t in args.runs]
    # Repeats in alternating order (forward, backward, ...): each configuration meets the same drift of
    # the machine's load; a cycle's time is the minimum over the repeats, the answers are the first run's.
    results: list[dict | None] = [None] * len(specs)
    for rep in range(args.repeat):
        order = range(len(specs)) if rep % 2 == 0 else reversed(range(len(specs)))
        for i in order:
            spec = dict(specs[i], cycles=args.cycles)
            print(f"running {spec['label']} (repeat {rep + 1}/{args.repeat}) ...", flush=True)
            res = run_child(spec)
            res["per_cycle"] = deltas(res["cycles"], res["start"])
            if results[i] is None:
                results[i] = res
                res["per_cycle_first"] = [dict(d) for d in res["per_cycle"]]  # the breakdown's (not min'ed)
                res["repeats"] = [[(d["wall_s"], d["cpu_s"]) for d in res["per_cycle"]]]
            else:
                first = results[i]
                first["repeats"].append([(d["wall_s"], d["cpu_s"]) for d in res["per_cycle"]])
                for d, e in zip(first["per_cycle"], res["per_cycle"]):
                    d["wall_s"], d["cpu_s"] = min(d["wall_s"], e["wall_s"]), min(d["cpu_s"], e["cpu_s"])
    base = results[0]
    ref = next(r for r in results if r["spec"]["label"] == args.reference)
    L = header("Elastic-plastic cylinder-flat: cost per cycle and the answer against full Newton", argv)
    L += ["Runs, one after the other in this invocation, each in a subprocess with `PYTHONPATH` = its tree:", ""]
    for r in results:
        sp_ = r["spec"]
        how = {None: "", True: ", condensed iteration", False: ", refactorising iteration"}[sp_.get("condensed")]
        L.append(f"- **{sp_['label']}**: `{sp_['tree']}` ({tree_commit(sp_['tree'])}), "
                 f"`solver.newton_tangent={sp_['tangent']}`{how}; whole run {r['wall_s']:.1f} s")
    if args.repeat > 1:
        L += ["", f"Each configuration ran {args.repeat} times, in alternating order (forward, backward, ...); "
              "a cycle's wall and CPU times are the minima over the repeats."]
    L += ["", f"Ratios are against **{base['spec']['label']}**, cycle by cycle; differences are against "
          f"**{ref['spec']['label']}** at the end of each cycle: peak pressure (relative), pressure profile "
          "(max |difference| / peak pressure) and wear profile (the wear gap: max |difference| / max wear), "
          "from the runs' states at full precision. CPU is the process time of the cycle (the machine is "
          "shared: wall times carry other jobs' load).", "",
          "| run | cycle | wall (s) | CPU (s) | CPU ratio | wall ratio | Newton iterations | tangents (refact. / "
          "low-rank) | peak pressure | pressure profile | wear profile |",
          "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in results:
        prev_t = {"refactorizations": r["start"].get("refactorizations", 0), "tangent_updates": 0}
        for k, (d, c) in enumerate(zip(r["per_cycle"], r["cycles"])):
            b, f = base["per_cycle"][k], ref["cycles"][k]
            tangents = (f"{c['refactorizations'] - prev_t['refactorizations']} / "
                        f"{c['tangent_updates'] - prev_t['tangent_updates']}")
            prev_t = c
            its = d["calls"].get("contact solve: load control (Python)", 0)
            L.append(f"| {r['spec']['label']} | {d['cycle']} | {d['wall_s']:.2f} | {d['cpu_s']:.2f} | "
                     f"{b['cpu_s'] / d['cpu_s']:.2f} | {b['wall_s'] / d['wall_s']:.2f} | {its} | {tangents} | "
                     f"{abs(c['max_pressure_end'] / f['max_pressure_end'] - 1):.1e} | "
                     f"{rel(c['pressure'], f['pressure']) * max(f['pressure']) / f['max_pressure_end']:.1e} | "
                     f"{rel(c['wear_gap'], f['wear_gap']):.1e} |")
    L += ["", "| run | cycles 1..N: wall (s) | CPU (s) | CPU ratio | wall ratio | cycles 2..N: CPU (s) | CPU ratio | "
          "max difference vs reference (peak pressure / pressure profile / wear profile) |",
          "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
    bw, bc = (sum(d[k] for d in base["per_cycle"]) for k in ("wall_s", "cpu_s"))
    bc2 = sum(d["cpu_s"] for d in base["per_cycle"][1:])
    for r in results:
        w, c = (sum(d[k] for d in r["per_cycle"]) for k in ("wall_s", "cpu_s"))
        c2 = sum(d["cpu_s"] for d in r["per_cycle"][1:])
        dp = max(abs(x["max_pressure_end"] / y["max_pressure_end"] - 1) for x, y in zip(r["cycles"], ref["cycles"]))
        dpp = max(rel(x["pressure"], y["pressure"]) * max(y["pressure"]) / y["max_pressure_end"]
                  for x, y in zip(r["cycles"], ref["cycles"]))
        dw = max(rel(x["wear_gap"], y["wear_gap"]) for x, y in zip(r["cycles"], ref["cycles"]))
        last = r["cycles"][-1]
        extra = (f"; zone {last['zone_dofs']} dofs, {last['zone_growths']} growths, "
                 f"{last['condensed_fallbacks']} fallbacks" if last.get("zone_dofs") else "")
        L.append(f"| {r['spec']['label']} | {w:.1f} | {c:.1f} | {bc / c:.2f} | {bw / w:.2f} | "
                 f"{c2:.1f} | {bc2 / max(c2, 1e-9):.2f} | {dp:.1e} / {dpp:.1e} / {dw:.1e}{extra} |")
    for r in results:
        L += ["", f"## Where the time of **{r['spec']['label']}** goes (its first repeat)", ""]
        L += breakdown(r["per_cycle_first"])
    text = "\n".join(L) + "\n"
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text)
    Path(args.out).with_suffix(".json").write_text(json.dumps({"command": argv, "results": results}))
    print(text)
    return 0


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "_child":
        print(json.dumps(child(json.loads(argv[1]))))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("profile")
    p.add_argument("--cycles", type=int, default=3)
    p.add_argument("--tangent", nargs="+", default=["adaptive"], help="one section per value")
    p.add_argument("--tree", default=str(HERE.parent))
    p.add_argument("--out", default=str(HERE / "results" / "plastic_profile.md"))
    c = sub.add_parser("compare")
    c.add_argument("--cycles", type=int, default=3)
    c.add_argument("--before", default=None, help="package tree, or commit of this repository, of the 'before' runs")
    c.add_argument("--runs", nargs="+", default=["before (adaptive)=before:adaptive",
                                                 "full Newton, refactorising=this:consistent:refactorizing",
                                                 "condensed (default)=this:adaptive"],
                   help="label=tree:tangent[:condensed|refactorizing]; the first is the ratios' base")
    c.add_argument("--reference", default="full Newton, refactorising", help="label of the reference run")
    c.add_argument("--repeat", type=int, default=1, help="runs of each configuration, in alternating order")
    c.add_argument("--out", default=str(HERE / "results" / "plastic.md"))
    args = ap.parse_args(argv)
    if args.command == "profile":
        return profile(args, argv)
    return compare(args, argv)


if __name__ == "__main__":
    sys.exit(main())
