"""Freeze the answers of the built-in scenes, CI-sized, and of an API run into ``tests/data/reference_summaries.json``.

The scene runner is about to be refactored; ``tests/test_reference_summaries.py`` runs the same cases and
compares every number stored here to 1e-10, so that the refactor is checked against the arithmetic of the
release it starts from. Run it (serially) from the repository root at the commit to freeze:

    .venv/bin/python tests/data/make_reference_summaries.py [--out tests/data/reference_summaries.json]

It refuses to run when ``dolfinx_fretting/`` has uncommitted changes (the stored commit would not be the
code that made the numbers). The output holds no time or path, so two runs at one commit are identical
byte for byte (serial runs are deterministic); the wall time of each case goes to stderr only.

Each case is a built-in scene with ``--set`` overrides that make it small (coarse contact mesh, few
increments and cycles) while keeping the path it was chosen for; ``PURPOSE`` says which. The cases of
:data:`API_CASES` are Python scripts on the public API instead (no scene: the model is the script's own).

``--only NAME [NAME ...]`` computes the named cases and keeps the others as they are in ``--out`` (their own
commits recorded with them): cases added later are frozen at their own commit.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

#: Overrides every case gets: no pictures, no XDMF fields, no progress bar (outputs that hold no answer).
COMMON_OVERRIDES = ["output.plots=false", "output.xdmf=false", "output.progress=false"]

#: name -> (built-in scene, overrides). ``output.snapshot_cycles`` is set to the cases' own cycles, as the
#: scenes' snapshots (up to 9000) lie past the shortened runs.
CASES: dict[str, tuple[str, list[str]]] = {
    "hertz-force": ("hertz", [
        "geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.tangential_increments=3",
        "contact.candidate_half_width=none"]),
    "stromberg-block-kernel": ("stromberg-block", [
        "geometry.nx=20", "geometry.ny=20", "loading.cycles=3", "output.snapshot_cycles=[1, 3]"]),
    "stromberg-block-jump": ("stromberg-block", [
        "geometry.nx=20", "geometry.ny=20", "loading.cycles=200", "output.snapshot_cycles=[200]",
        "wear.cycle_jump=true"]),
    "cylinder-flat-kernel": ("cylinder-flat", [
        "geometry.contact_mesh_size=0.02", "loading.normal_force=none", "loading.normal_displacement=0.008",
        "loading.normal_increments=2", "loading.cycles=3", "loading.increments_per_cycle=8",
        "wear.acceleration=100", "output.snapshot_cycles=[3]"]),
    "cylinder-flat-plastic": ("cylinder-flat", [
        "geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=1",
        "loading.increments_per_cycle=4", "material.model='elastoplastic'", "material.yield_stress=840",
        "material.hardening_modulus=7230", "output.snapshot_cycles=[1]"]),
    "cylinder-flat-partial-python": ("cylinder-flat-partial", [
        "geometry.contact_mesh_size=0.02", "loading.normal_force=none", "loading.normal_displacement=0.008",
        "loading.normal_increments=2", "loading.cycles=2", "loading.increments_per_cycle=8",
        "solver.cycle_kernel=false", "wear.acceleration=100", "output.snapshot_cycles=[2]"]),
    "cylinder-flat-partial-force": ("cylinder-flat-partial", [
        "geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=1",
        "loading.increments_per_cycle=8", "loading.tangential_displacement=none",
        "loading.tangential_force=89.658", "contact.candidate_half_width=none",
        "output.snapshot_cycles=[1]"]),
    "mccoll-grow": ("mccoll", [
        "geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=2",
        "loading.increments_per_cycle=8", "contact.candidate_half_width=0.05", "contact.sliding='small'",
        "output.snapshot_cycles=[2]"]),
    "mccoll-finite-sliding": ("mccoll", [
        "contact.sliding='finite'", "geometry.contact_mesh_size=0.02", "loading.cycles=2",
        "loading.increments_per_cycle=16", "output.snapshot_cycles=[2]"]),
    "sphere-flat-3d": ("sphere-flat", [
        "geometry.contact_mesh_size=0.09", "loading.cycles=2", "loading.increments_per_cycle=8",
        "loading.normal_increments=2", "wear.k=1e-6", "output.snapshot_cycles=[2]"]),
}

#: What each case is there for (stored with it; the test names it in a failure).
PURPOSE = {
    "hertz-force": "monotonic run, normal AND tangential force control (partial slip, Q = 0.5 mu P), rigid "
                   "plane, automatic contact window (Hertz estimate), no wear",
    "stromberg-block-kernel": "compiled cycle loop with pattern reuse, face pressure load, rectangle on a "
                              "rigid plane, Archard wear",
    "stromberg-block-jump": "cycle jumps (wear.cycle_jump) in the compiled loop: 200 cycles, few simulated",
    "cylinder-flat-kernel": "two deformable bodies in the compiled loop with pattern reuse (displacement "
                            "control), wear acceleration x100, gross slip",
    "cylinder-flat-plastic": "elastic-plastic bodies (J2, yield 840 MPa, H = 7230 MPa): Newton with the "
                             "contact inside, force-controlled preload",
    "cylinder-flat-partial-python": "solver.cycle_kernel=false: the per-increment Python path through "
                                    "cycles, two bodies, partial slip, wear acceleration x100",
    "cylinder-flat-partial-force": "cyclic tangential force control (frozen on the Python path; the compiled "
                                   "loop since issue 26), automatic window, two bodies, partial slip",
    "mccoll-grow": "two bodies with wear shares (k_slave, k_master), wear acceleration x25, force-controlled "
                   "preload, a small given window that grows once",
    "mccoll-finite-sliding": "finite sliding (contact.sliding = 'finite'): two bodies re-paired as they slide "
                             "(surface compliance, the master's wear carried on its nodes), both bodies wearing",
    "sphere-flat-3d": "3D: the half ball on an identical elastic flat (node-to-face pairing on hexahedra, a "
                      "symmetry plane, the whole contact's sums and radii), the normal force held through gross-slip "
                      "cycles (frozen increment by increment; the compiled loop since issue 26), wear",
    "api-block": "the Python API without a scene: prescribed Dirichlet data press a block on a rigid plane, a "
                 "named side load cycles with a tangential force (force control; frozen increment by increment, the "
                 "compiled loop since issue 26), wear",
}

#: Cases whose answer is also stored as full Newton gives it (``"full_newton"``: these overrides added). The
#: elastic-plastic answer is defined to the Newton tolerances; the default iteration may stop anywhere inside
#: them, full Newton's quadratic last steps pin it to rounding (tests/test_reference_summaries.py).
FULL_NEWTON = {"cylinder-flat-plastic": ["solver.newton_tangent='consistent'"]}

#: Summary keys stored when present (``window_growths`` is stored as its count, ``cycle_jump.*`` from the
#: nested jump summary).
FLOAT_KEYS = ("normal_force", "tangential_force", "max_pressure", "contact_width", "stick_width",
              "max_wear_depth", "wear_area", "dissipated_energy", "equivalent_cycles", "max_wear_depth_slave",
              "max_wear_depth_master", "max_equivalent_plastic_strain", "max_von_mises", "contact_window",
              "cycle_jump.wear_error_estimate", "contact_radius", "stick_radius", "contact_extent_along",
              "contact_extent_across", "wear_volume", "master_scar_width")
INT_KEYS = ("increments", "cycles", "contacts", "n_open", "n_stick", "n_slip", "window_growths",
            "cycle_jump.simulated_cycles", "repairs")
#: Exact strings: the case must still take the path it was chosen for.
STR_KEYS = ("cycle_path",)


def _lookup(summary: dict[str, Any], dotted: str) -> tuple[bool, Any]:
    node: Any = summary
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return False, None
        node = node[part]
    return True, node


def extract_answer(summary: dict[str, Any], out_dir: Path) -> dict[str, Any]:
    """The numbers that define a run's answer: summary keys, final wear-gap profile, last cycle's energy.

    Args:
        summary: What ``run_scene`` returned.
        out_dir: The run's output folder (``worn_profiles.csv``, ``cycles.csv``).

    Returns:
        ``{"values": {key: number or None}, "wear_gap": [...] or None,
        "last_cycle_dissipated_energy": float or None}``, and ``"master_wear": [...]`` (the flat's wear at its
        nodes) for a finite-sliding run.
    """
    values: dict[str, Any] = {}
    for key in FLOAT_KEYS:
        present, value = _lookup(summary, key)
        if present:
            values[key] = None if value is None else float(value)
    for key in INT_KEYS:
        present, value = _lookup(summary, key)
        if present:
            values[key] = len(value) if key == "window_growths" else int(value)
    for key in STR_KEYS:
        present, value = _lookup(summary, key)
        if present:
            values[key] = str(value)
    wear_gap = master_wear = None
    worn = out_dir / "worn_profiles.csv"
    if worn.is_file():  # written by runs with a wear law (printed with 12 significant digits)
        with open(worn, newline="") as f:
            rows = list(csv.DictReader(f))
        # Finite sliding writes the flat's nodes as rows of their own (the slave's columns nan there): the flat's
        # scar, carried on its nodes, is an answer of its own.
        wear_gap = [float(row["wear_gap"]) for row in rows if row["position"] != "nan"]
        if rows and "flat_wear" in rows[0]:
            master_wear = [float(row["flat_wear"]) for row in rows if row["flat_position"] != "nan"]
    last_energy = None
    cycles = out_dir / "cycles.csv"
    if cycles.is_file():  # cyclic runs (printed with 10 significant digits)
        with open(cycles, newline="") as f:
            rows = list(csv.DictReader(f))
        if rows:
            last_energy = float(rows[-1]["dissipated_energy"])
    answer = {"values": values, "wear_gap": wear_gap, "last_cycle_dissipated_energy": last_energy}
    if master_wear is not None:
        answer["master_wear"] = master_wear
    return answer


def api_block() -> dict[str, Any]:
    """The ``api-block`` case: a model written as a DOLFINx user would, run through the public API only.

    A 2 x 1 mm block (16 x 8 quadrilaterals, plane strain, E = 200 GPa, nu = 0.3) on a rigid plane y = 0
    (mu = 0.4, Archard k = 1e-4 1/MPa); its top is lowered by 2e-3 mm as prescribed Dirichlet data ``lower``
    (two increments), then two cycles of 8 increments drive a tangential force +-0.9 mu P (P the pressed normal
    force; force control, increment by increment) with a named traction ``side`` (-20, -30) MPa on the right face
    cycling with it (the same triangular waveform).

    Returns:
        The answer in :func:`extract_answer`'s form, from the states' records and the wear gap at full precision.
    """
    from mpi4py import MPI

    import ufl
    from dolfinx import fem, mesh
    from petsc4py import PETSc

    import dolfinx_fretting as dfr
    from dolfinx_fretting import _dolfinx as dfx

    comm = MPI.COMM_SELF
    msh = mesh.create_rectangle(comm, [[-1.0, 0.0], [1.0, 1.0]], [16, 8], mesh.CellType.quadrilateral)
    found = [mesh.locate_entities_boundary(msh, 1, where) for where in (
        lambda x: np.isclose(x[1], 0.0), lambda x: np.isclose(x[1], 1.0), lambda x: np.isclose(x[0], 1.0))]
    facets = np.concatenate(found)
    values = np.concatenate([np.full(f.size, i + 1, dtype=np.int32) for i, f in enumerate(found)])
    order = np.argsort(facets)
    tags = mesh.meshtags(msh, 1, facets[order], values[order])
    V = dfx.vector_space(msh, 1)
    E, nu = 200000.0, 0.3
    lmbda, mu_lame = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    form = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * mu_lame * eps(u), eps(v)) * ufl.dx
    lowered = fem.Function(V)
    lowered.x.array.reshape(-1, 2)[:, 1] = -2e-3
    top = fem.dirichletbc(lowered, fem.locate_dofs_topological(V, 1, tags.find(2)))
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
    side = ufl.inner(fem.Constant(msh, PETSc.ScalarType((-20.0, -30.0))), v) * ds(3)
    mu = 0.4
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, 0.0], [0.0, 1.0]), mu=mu, bcs=[top])
    problem = dfr.FrettingProblem(form, contact, [], prescribed={"lower": [top]}, loads={"side": side},
                                  wear=dfr.Archard(1e-4))
    try:
        state = problem.initial_state()
        energy = 0.0
        for factor in (0.5, 1.0):
            state = problem.commit(state, problem.solve(state, loads={"lower": factor}))
            energy += state.record["dissipated_energy"]
        P = float(problem.total_force(state)[0])
        path = dfr.CyclePath.waveform(8, tangential=dfr.Force(0.9 * mu * P), loads={"side": 1.0})
        for _ in range(2):
            result = problem.run_cycle(state, path)
            state = problem.commit(state, result)
            cycle_energy = float(np.sum(result.records["dissipated_energy"]))
            energy += cycle_energy
        record = state.record
        values = {key: float(record[key]) for key in ("normal_force", "tangential_force", "max_pressure",
                                                       "contact_width", "stick_width", "max_wear_depth",
                                                       "wear_area")}
        values.update({"dissipated_energy": energy, "increments": int(state.increment), "cycles": 2,
                       "contacts": int(problem.contact.contact_set.nc),
                       **{key: int(record[key]) for key in ("n_open", "n_stick", "n_slip")}})
        return {"values": values, "wear_gap": [float(g) for g in state.wear_gap],
                "last_cycle_dissipated_energy": cycle_energy}
    finally:
        problem.destroy()


#: Cases run through the Python API: name -> the function that builds and runs the model (no scene, no folder).
API_CASES = {"api-block": api_block}


def run_case(name: str, out_dir: Path, overrides: list[str] | None = None, scene: str | None = None
             ) -> dict[str, Any]:
    """Run one case serially into ``out_dir`` and return :func:`extract_answer` of it.

    Args:
        name: A key of :data:`CASES` (its scene and overrides are used unless given) or of :data:`API_CASES`
            (its function; nothing is written to ``out_dir``).
        out_dir: Output folder of the run.
        overrides: The full override list (``CASES[name]`` plus :data:`COMMON_OVERRIDES` if None).
        scene: The built-in scene (``CASES[name][0]`` if None).

    Returns:
        The answer (:func:`extract_answer`).
    """
    from mpi4py import MPI

    if name in API_CASES:
        return API_CASES[name]()

    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import run_scene

    if scene is None:
        scene = CASES[name][0]
    if overrides is None:
        overrides = CASES[name][1] + COMMON_OVERRIDES
    summary = run_scene(load_scene(scene, overrides), out_dir, MPI.COMM_SELF, quiet=True)
    return extract_answer(summary, Path(out_dir))


def environment() -> dict[str, str]:
    """Versions of what does the arithmetic (a reference is exact for this stack only)."""
    import dolfinx
    import numba
    import numpy
    import petsc4py

    return {"dolfinx": dolfinx.__version__, "petsc4py": petsc4py.__version__, "numpy": numpy.__version__,
            "numba": numba.__version__, "python": sys.version.split()[0]}


def _commit(repo: Path) -> str:
    dirty = subprocess.run(["git", "status", "--porcelain", "--", "dolfinx_fretting"], cwd=repo, check=True,
                           capture_output=True, text=True).stdout.strip()
    if dirty:
        raise SystemExit(f"dolfinx_fretting/ has uncommitted changes; commit or stash them first:\n{dirty}")
    return subprocess.run(["git", "rev-parse", "--short=7", "HEAD"], cwd=repo, check=True,
                          capture_output=True, text=True).stdout.strip()


def main() -> None:
    repo = Path(__file__).resolve().parents[2]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=repo / "tests" / "data" / "reference_summaries.json")
    parser.add_argument("--only", nargs="+", metavar="NAME", choices=[*CASES, *API_CASES],
                        help="compute these cases only; keep the others of --out")
    args = parser.parse_args()
    commit = _commit(repo)
    kept = {}
    if args.only:
        previous = json.loads(args.out.read_text())
        kept = {case["name"]: case for case in previous["cases"] if case["name"] not in args.only}
    cases = []
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="reference_summaries_") as tmp:
        for name, (scene, overrides) in [*CASES.items(), *((name, (None, [])) for name in API_CASES)]:
            if name in kept:
                cases.append(kept[name])
                continue
            t0 = time.perf_counter()
            answer = run_case(name, Path(tmp) / name)
            print(f"{name}: {time.perf_counter() - t0:.2f} s", file=sys.stderr, flush=True)
            case = {"name": name, "scene": scene, "overrides": overrides + COMMON_OVERRIDES if scene else [],
                    "purpose": PURPOSE[name], "commit": commit, **answer}
            if name in FULL_NEWTON:
                full = run_case(name, Path(tmp) / f"{name}-full-newton",
                                overrides=overrides + COMMON_OVERRIDES + FULL_NEWTON[name])
                case["full_newton"] = {"added_overrides": FULL_NEWTON[name], **full}
            cases.append(case)
    print(f"all cases: {time.perf_counter() - t_all:.2f} s", file=sys.stderr)
    data = {"about": "Answers of the built-in scenes, CI-sized, frozen by "
                     "tests/data/make_reference_summaries.py; checked by tests/test_reference_summaries.py",
            "commit": commit if not args.only else previous["commit"],
            "environment": environment(), "cases": cases}
    args.out.write_text(json.dumps(data, indent=1) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
