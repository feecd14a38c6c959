"""Collective tests: run them on any number of ranks with

    mpirun -n 2 python -m mpi4py -m pytest tests/test_parallel.py

(``python -m mpi4py`` makes an exception on one rank abort all ranks instead of hanging). Each test runs a
scene on COMM_WORLD and the same scene serially on rank 0 (COMM_SELF), and compares. Serially (one rank)
the two runs are identical by construction; the tests are meant for ``mpirun``.
"""

import json
import shutil
import tempfile
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import run_scene

COMM = MPI.COMM_WORLD
CASES = {
    "hertz": ["geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.tangential_increments=3"],
    "stromberg-block": ["geometry.nx=20", "geometry.ny=20", "loading.cycles=3", "output.snapshot_cycles=[1, 3]"],
    "cylinder-flat": ["geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=1",
                      "loading.increments_per_cycle=8", "material.model='elastoplastic'",
                      "material.yield_stress=840", "material.hardening_modulus=7230"],
    # Elastic-plastic cycle jumps: shakes down elastically from cycle 3, jumps from cycle 2 (the plastic regime
    # and the jumps are decided from every rank's quadrature points).
    "cylinder-flat-partial": ["geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=8",
                              "loading.increments_per_cycle=8", "material.model='elastoplastic'",
                              "material.yield_stress=420", "material.hardening_modulus=7230",
                              "loading.tangential_displacement=0.0005", "wear.cycle_jump=true"],
    # Two elastic bodies, both wearing, the pairing fixed; the window grows once (a small one given) on the way.
    "mccoll": ["geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=2",
               "loading.increments_per_cycle=8", "contact.candidate_half_width=0.05", "contact.sliding='small'"],
    # 3D: the half ball on an elastic flat (node-to-face pairs, rollers on the symmetry plane), coarse mesh.
    "sphere-flat": ["geometry.contact_mesh_size=0.09", "loading.cycles=2", "loading.increments_per_cycle=16"],
    # Finite sliding: the bodies paired anew as they slide (both wearing in mccoll, the master's wear on its nodes);
    # its first cycle in finite sliding's compiled loop (not kept: rank 0's answer broadcast), the second stepwise.
    "mccoll:finite": ["geometry.contact_mesh_size=0.02", "loading.normal_increments=2", "loading.cycles=2",
                      "loading.increments_per_cycle=8", "contact.sliding='finite'", "output.snapshot_cycles=[2]"],
    "sphere-flat:finite": ["geometry.contact_mesh_size=0.09", "loading.cycles=1", "loading.increments_per_cycle=16",
                           "contact.sliding='finite'"],
}
KEYS = ("normal_force", "tangential_force", "max_pressure", "max_wear_depth", "wear_area", "dissipated_energy",
        "contact_width", "stick_width")


@pytest.fixture
def shared_dir():
    """One scratch folder for all ranks (made on rank 0), removed after the test."""
    path = COMM.bcast(tempfile.mkdtemp(prefix="dolfinx_fretting_par_") if COMM.rank == 0 else None, root=0)
    yield Path(path)
    COMM.barrier()
    if COMM.rank == 0:
        shutil.rmtree(path, ignore_errors=True)


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
@pytest.mark.parametrize("name", sorted(CASES))
def test_parallel_run_matches_serial(shared_dir, name):
    overrides = CASES[name] + ["output.plots=false", "output.history_every=1", "output.progress=false"]
    scene = name.split(":")[0]  # "scene:variant" keys: the same scene with other overrides
    parallel = run_scene(load_scene(scene, overrides), shared_dir / "par", COMM, quiet=True)
    serial = None
    if COMM.rank == 0:
        serial = run_scene(load_scene(scene, overrides + ["output.xdmf=false"]), shared_dir / "ser", MPI.COMM_SELF,
                           quiet=True)
    serial = COMM.bcast(serial, root=0)
    assert parallel["contacts"] == serial["contacts"] and parallel["increments"] == serial["increments"]
    extra = [k for k in ("max_equivalent_plastic_strain", "wear_volume", "contact_radius", "stick_radius",
                         "max_wear_depth_master", "master_scar_width") if k in serial]
    for key in KEYS + tuple(extra):
        # The same contact set and local problems; W and the fields differ only by the rounding of a
        # differently ordered factorisation (measured ~1e-13): 1e-8 relative.
        assert parallel[key] == pytest.approx(serial[key], rel=1e-8, abs=1e-12), key
    for key in ("n_open", "n_stick", "n_slip", "plastic_regime_last_cycle", "repairs"):
        assert parallel.get(key) == serial.get(key), key
    if "cycle_jump" in serial:  # the same jumps
        for key in ("simulated_cycles", "jumps", "largest_jump"):
            assert parallel["cycle_jump"][key] == serial["cycle_jump"][key], key
        for key in ("wear_error_estimate", "plastic_error_estimate"):
            assert parallel["cycle_jump"][key] == pytest.approx(serial["cycle_jump"][key], rel=1e-6, abs=1e-15), key
    COMM.barrier()
    if COMM.rank == 0:  # written once: the summary on disk is the returned one, history has one row per increment
        on_disk = json.loads((shared_dir / "par" / "summary.json").read_text())
        assert on_disk["increments"] == parallel["increments"]
        rows = (shared_dir / "par" / "history.csv").read_text().strip().splitlines()
        jumped = 0  # the increments of the cycles a jump stood for are counted, not simulated (no rows)
        if "cycle_jump" in parallel:
            per_cycle = load_scene(scene, overrides).loading.increments_per_cycle
            jumped = (parallel["cycles"] - parallel["cycle_jump"]["simulated_cycles"]) * per_cycle
        assert len(rows) == 1 + parallel["increments"] - jumped


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_parallel_cycle_jumps_match_serial(shared_dir):
    """Jumps are decided on rank 0 and broadcast: the same jumps, wear and error estimate as a serial run."""
    overrides = ["geometry.nx=20", "geometry.ny=20", "loading.cycles=200", "output.snapshot_cycles=[200]",
                 "wear.cycle_jump=true", "output.plots=false", "output.xdmf=false", "output.progress=false"]
    parallel = run_scene(load_scene("stromberg-block", overrides), shared_dir / "par", COMM, quiet=True)
    serial = None
    if COMM.rank == 0:
        serial = run_scene(load_scene("stromberg-block", overrides), shared_dir / "ser", MPI.COMM_SELF, quiet=True)
    serial = COMM.bcast(serial, root=0)
    for key in ("simulated_cycles", "jumps", "largest_jump"):
        assert parallel["cycle_jump"][key] == serial["cycle_jump"][key], key
    # As above: rounding of a differently ordered factorisation only.
    for key in ("max_wear_depth", "wear_area", "dissipated_energy"):
        assert parallel[key] == pytest.approx(serial[key], rel=1e-8), key
    assert parallel["cycle_jump"]["wear_error_estimate"] == pytest.approx(serial["cycle_jump"]["wear_error_estimate"],
                                                                          rel=1e-6)


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_delassus_routes_agree_in_parallel():
    from dolfinx_fretting.simulation import ContactModel

    model = ContactModel(load_scene("hertz", ["geometry.contact_mesh_size=0.04", "output.xdmf=false",
                                              "output.plots=false"]), COMM)
    d, H = model.problem.operators.delassus, model.contact.H
    assert d.method == "owned"  # the default under MPI (benchmarks/results/delassus_owned_np2.md)
    W = {r: d.build(H, method=r) for r in ("block", "selected_inverse", "owned")}
    scale = np.abs(W["block"]).max()
    for r in W:
        # distributed and per-rank MUMPS factors of the same K (condition ~1e5): 1e-10 of max|W|
        assert np.abs(W[r] - W["block"]).max() <= 1e-10 * scale, r
        gathered = COMM.allgather(W[r])  # every rank holds the same W, bit for bit
        assert all(np.array_equal(g, gathered[0]) for g in gathered), r
    # K's values change (K -> 2K) and are refactorised: the owned copy follows (W -> W/2).
    model.problem.operators.K.scale(2.0)
    d.refactorize()
    W2 = d.build(H)
    model.problem.operators.K.scale(0.5)
    d.refactorize()
    assert np.abs(W2 - 0.5 * W["owned"]).max() <= 1e-10 * scale
    model.problem.destroy()


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_w_moves_between_ranks_in_chunks(monkeypatch):
    """W's transfers (the owned route's column blocks to rank 0, the broadcast of the finished W) go in messages of
    at most compliance.MPI_CHUNK doubles, since MPI counts are ints (one message would overflow past ~15 400 3D
    contacts). With a chunk of 7 doubles (every block split, into pieces that straddle the ranks' blocks) W is the
    same bits as with one message per block, on every rank."""
    from dolfinx_fretting import compliance
    from dolfinx_fretting.simulation import ContactModel

    model = ContactModel(load_scene("hertz", ["geometry.contact_mesh_size=0.04", "output.xdmf=false",
                                              "output.plots=false"]), COMM)
    d, H = model.problem.operators.delassus, model.contact.H
    whole = {route: d.build(H, method=route) for route in ("owned", "selected_inverse")}
    assert H.shape[0] ** 2 > 7 * COMM.size
    monkeypatch.setattr(compliance, "MPI_CHUNK", 7)
    for route, W in whole.items():
        chunked = d.build(H, method=route)
        assert np.array_equal(chunked, W), route
        gathered = COMM.allgather(chunked)
        assert all(np.array_equal(g, gathered[0]) for g in gathered), route
    model.problem.destroy()


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_auto_route_stays_owned_under_mpi(monkeypatch):
    """Above AUTO_SCHUR_ROWS rows serial ``auto`` takes the Schur route, which PETSc cannot run distributed: under
    MPI ``auto`` keeps the owned route at any size, on every rank (no rank left waiting in another route)."""
    from dolfinx_fretting import delassus_routes
    from dolfinx_fretting.simulation import ContactModel

    model = ContactModel(load_scene("hertz", ["geometry.contact_mesh_size=0.04", "output.xdmf=false",
                                              "output.plots=false"]), COMM)
    d, H = model.problem.operators.delassus, model.contact.H
    monkeypatch.setattr(delassus_routes, "AUTO_SCHUR_ROWS", 1)  # every H is "large"
    W = d.build(H)
    routes = COMM.allgather(d.stats["last_build_route"])
    assert routes == ["owned"] * COMM.size
    # the same W as the owned route's asked by name: same factor, same route, same bits
    assert np.array_equal(W, d.build(H, method="owned"))
    model.problem.destroy()


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_output_folder_errors_are_collective(shared_dir):
    """Rank 0 checks and locks the folder, every rank raises the same error (none hangs), before any mesh."""
    from dolfinx_fretting.outdir import LOCK_NAME, OutputFolderError, claim_output_folder

    scene = load_scene("stromberg-block", ["geometry.nx=10", "geometry.ny=10", "loading.cycles=1",
                                           "output.plots=false", "output.xdmf=false", "output.progress=false"])
    run_scene(scene, shared_dir / "run", COMM, quiet=True)
    messages = []
    for attempt in (lambda: run_scene(scene, shared_dir / "run", COMM, quiet=True),  # holds a run
                    lambda: claim_output_folder(shared_dir / "run" / "summary.json", COMM)):  # a file
        with pytest.raises(OutputFolderError) as info:
            attempt()
        messages.append(str(info.value))
    gathered = COMM.allgather(messages)
    assert all(m == gathered[0] for m in gathered)
    assert "already holds a run" in messages[0] and "is a file" in messages[1]
    with claim_output_folder(shared_dir / "fresh", COMM) as lock:  # only rank 0 holds the file
        assert lock.held == (COMM.rank == 0)
        COMM.barrier()
        assert (shared_dir / "fresh" / LOCK_NAME).is_file()
        COMM.barrier()
    COMM.barrier()
    assert not (shared_dir / "fresh" / LOCK_NAME).exists()


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_schur_route_is_refused_under_mpi():
    """PETSc has no distributed MUMPS Schur complement: the route says so on every rank before any work (the API's
    ValueError, which the scene runner reports as its own error: one line)."""
    from dolfinx_fretting.simulation import ContactModel, SimulationError

    scene = load_scene("stromberg-block", ["geometry.nx=4", "geometry.ny=4", "solver.delassus_method='schur'"])
    with pytest.raises(SimulationError, match=r"'schur' runs serially only \(this run has \d+ MPI ranks\)"):
        ContactModel(scene, COMM)


def _sphere_history(comm):
    """The 3D sphere on an identical flat (half model, a/h = 2: tests/support/sphere.py) on ``comm``: pressed by
    force, a Cattaneo-Mindlin tangential force, gross-slip increments with wear and one compiled cycle."""
    import dolfinx_fretting as dfr
    from support.sphere import P, pressed, sphere_model

    body, problem, a, p0, h = sphere_model(2, 4.0, 1.6, flat=True, mu=0.5, wear=dfr.Archard(1e-6), comm=comm)
    state = pressed(problem, P / 2)
    state = problem.commit(state, problem.solve(state, tangential=(dfr.Force(0.1 * P), dfr.Displacement(0.0))))
    for d in (0.005, 0.01):
        state = problem.commit(state, problem.solve(state, tangential=(dfr.Displacement(d), dfr.Displacement(0.0))))
    state = problem.commit(state, problem.run_cycle(
        state, dfr.CyclePath.waveform(8, normal=state.obstacle[0], tangential=[0.01, 0.0])))
    out = {"coordinates": problem.contact.contact_set.coords, "forces": state.forces, "positions": state.positions,
           "wear": state.wear_gap, "obstacle": state.obstacle, "energy": np.array([state.dissipated_energy]),
           "W": problem.operators.W}
    problem.destroy()
    return out


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_parallel_3d_sphere_matches_serial():
    """3D, two bodies (node-to-face pairing, held rows on the symmetry plane), through the API: the same contact
    set in the same order and the same history on every partition."""
    parallel = _sphere_history(COMM)
    serial = _sphere_history(MPI.COMM_SELF) if COMM.rank == 0 else None
    serial = COMM.bcast(serial, root=0)
    assert np.array_equal(parallel["coordinates"], serial["coordinates"])
    for key, value in parallel.items():
        # As the 2D scenes: other factorisations' rounding only (W to ~1e-13 of its largest entry): 1e-8.
        scale = max(np.abs(serial[key]).max(), 1e-300)
        assert np.abs(value - serial[key]).max() <= 1e-8 * scale, key


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_contact_surface_checks_are_collective():
    """A surface whose facets one rank alone tags is a surface on every rank; a marker no rank tags is refused on
    every rank with the same message, naming the markers of all ranks (decided by reductions, so none hangs)."""
    from dolfinx import mesh

    import dolfinx_fretting as dfr
    from dolfinx_fretting.compat import vector_space

    n = 8
    msh = mesh.create_unit_square(COMM, n, n)
    V = vector_space(msh, 1)
    msh.topology.create_connectivity(1, 0)
    bottom = mesh.locate_entities_boundary(msh, 1, lambda x: np.isclose(x[1], 0.0))
    bottom = bottom[bottom < msh.topology.index_map(1).size_local].astype(np.int32)  # owned: each facet once
    holder = COMM.allgather(bottom.size > 0).index(True)  # the first rank that owns bottom facets tags them 1
    marker = 1 if COMM.rank == holder else 20 + COMM.rank  # the others tag theirs with their own marker
    tags = mesh.meshtags(msh, 1, bottom, np.full(bottom.size, marker, dtype=np.int32))

    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, -0.1], [0.0, 1.0]), mu=0.3)
    # Reference: the holder's facets are intervals of length 1/n on y = 0 centred at their midpoints; their end
    # points (on the grid k/n, rounded to it) are the contact nodes.
    mid = mesh.compute_midpoints(msh, 1, bottom)[:, 0] if COMM.rank == holder else np.zeros(0)
    ends = COMM.bcast(np.unique(np.round(np.concatenate([mid - 0.5 / n, mid + 0.5 / n]) * n)) / n, root=holder)
    assert np.allclose(contact.contact_set.coords[:, 0], ends, rtol=0, atol=1e-12)
    assert np.allclose(contact.contact_set.gap0, 0.1, rtol=0, atol=1e-12)

    held = sorted({1} | {20 + r for r, owns in enumerate(COMM.allgather(bottom.size > 0)) if owns and r != holder})
    with pytest.raises(ValueError) as info:
        dfr.Contact(V, (tags, 7), dfr.RigidPlane([0.0, -0.1], [0.0, 1.0]), mu=0.3)
    assert str(info.value) == f"Contact: surface marker 7 tags no facet; the facet tags hold markers {held}"


def _hertz_window_decision(comm):
    """The Hertz cylinder with a candidate window narrower than its contact (tests/test_window_check.py): the
    WindowError's decision, then the peak pressure once solved in the window needed."""
    import dolfinx_fretting as dfr
    from dolfinx_fretting.geometries import build_scene_model

    scene = load_scene("hertz", ["geometry.contact_mesh_size=0.02", "contact.mu=0.0", "loading.tangential_force=0.0"])
    model = build_scene_model(scene, comm)
    contact = dfr.Contact(model.V, model.surface, model.obstacle, 0.0, model.bcs, window=0.05)
    problem = dfr.FrettingProblem(model.form, contact, model.bcs)
    state = problem.initial_state()
    with pytest.raises(dfr.WindowError) as caught:
        problem.solve(state, normal=dfr.Force(199.24))
    err = caught.value
    state = problem.set_window(state, err.window_needed)
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(199.24)))
    peak = float(problem.contact_fields(state)["pressure"].max())
    problem.destroy()
    return {"needed": err.window_needed, "positions": err.positions, "penetration": err.penetration, "peak": peak}


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_window_check_decides_alike_on_every_rank():
    """Nodes outside the candidate window penetrating: the check is decided on rank 0 and raised on every rank
    (none hangs in a collective), with the serial run's decision: the same penetrating nodes and window needed."""
    parallel = _hertz_window_decision(COMM)
    serial = _hertz_window_decision(MPI.COMM_SELF) if COMM.rank == 0 else None
    serial = COMM.bcast(serial, root=0)
    # The same nodes (listed deepest first: the symmetric pairs' order is rounding's, so compared as sets; 2D node
    # coordinates are tabulated by the cells' maps, equal to ~1e-16).
    key = lambda x: x[np.lexsort(x.T[::-1])]  # noqa: E731
    assert np.allclose(key(parallel["positions"]), key(serial["positions"]), rtol=0, atol=1e-12)
    assert parallel["needed"] == pytest.approx(serial["needed"], rel=1e-12)
    # As the runs above: other factorisations' rounding only: 1e-8.
    assert parallel["penetration"] == pytest.approx(serial["penetration"], rel=1e-8)
    assert parallel["peak"] == pytest.approx(serial["peak"], rel=1e-8)


def _two_zone_run(comm: MPI.Comm) -> dict:
    """Two blocks in one mesh, two zones: block A pressed by a displacement, block B by a force, then a compiled
    fretting cycle of A's plane with wear, and a window too narrow on B (support.blocks)."""
    import dolfinx_fretting as dfr
    from support.blocks import TIGHT, elasticity, plane_above, two_blocks

    V, tags, bcs = two_blocks(comm=comm)
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.5, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.5, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT, wear=dfr.Archard(1e-6))
    state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: dfr.Force(100.0)})
    state = problem.commit(state, problem.run_cycle(state, dfr.CyclePath.waveform(
        8, normal={b: state.obstacle[2]}, tangential={a: 3e-3})))
    narrow = dfr.Contact(V, (tags, 2), plane_above(), mu=0.5, bcs=bcs, window=0.2)
    windowed = dfr.FrettingProblem(elasticity(V), [a, narrow], bcs, solver=TIGHT)
    try:
        windowed.solve(windowed.initial_state(), normal={a: 1e-3, narrow: 1e-3})
        zone = None
    except dfr.WindowError as exc:
        zone = exc.zone
    return {"forces": [problem.total_force(state, zone_) for zone_ in (a, b)], "wear": state.wear_gap,
            "obstacle": state.obstacle, "window_zone": zone}


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_two_contact_zones_match_serial():
    """Several zones under MPI: targets per zone, force control, a compiled cycle of two zones and a zone's window
    check give every rank the serial run's answer (other factorisations' rounding only: 1e-8) and raise alike."""
    parallel = _two_zone_run(COMM)
    serial = COMM.bcast(_two_zone_run(MPI.COMM_SELF) if COMM.rank == 0 else None, root=0)
    assert parallel["window_zone"] == serial["window_zone"] == 1
    for mine, theirs in zip(parallel["forces"], serial["forces"]):
        assert mine == pytest.approx(theirs, rel=1e-8, abs=1e-10)
    assert parallel["wear"] == pytest.approx(serial["wear"], rel=1e-8, abs=1e-8 * serial["wear"].max())
    assert parallel["obstacle"] == pytest.approx(serial["obstacle"], rel=1e-8, abs=1e-14)


def _evolving_friction_run(comm: MPI.Comm, compiled: bool) -> dict:
    """Two blocks rubbed two cycles, one zone's mu a table of the cycles, the other's of the energy."""
    import dolfinx_fretting as dfr
    from support.blocks import elasticity, plane_above, two_blocks

    V, tags, bcs = two_blocks(comm=comm)
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=dfr.EvolvingFriction([(0, 0.2), (1, 0.6)]), bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=dfr.EvolvingFriction([(0, 0.2), (0.15, 0.8)], "energy"),
                    bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, wear=dfr.EnergyWear(2e-6),
                                  solver=dfr.LocalSolver(tol=1e-12, compiled_cycles=compiled))
    state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: 1e-3})
    path = dfr.CyclePath.waveform(8, tangential={a: 3e-3, b: 3e-3})
    for _ in range(2):
        state = problem.commit(state, problem.run_cycle(state, path))
    out = {"energy": state.friction_energy, "wear": state.wear_gap, "cycles": state.cycles}
    problem.destroy()
    return out


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "stepwise"])
def test_evolving_friction_matches_serial(compiled):
    """Friction of the cycles and of the energy under MPI: every rank holds the serial run's energies, wear and
    cycle count (other factorisations' rounding only: 1e-8)."""
    parallel = _evolving_friction_run(COMM, compiled)
    serial = COMM.bcast(_evolving_friction_run(MPI.COMM_SELF, compiled) if COMM.rank == 0 else None, root=0)
    assert parallel["cycles"] == serial["cycles"] == 2.0
    assert serial["energy"].max() > 0.15   # mu of the energy zone reached its last value
    assert parallel["energy"] == pytest.approx(serial["energy"], rel=1e-8, abs=1e-12)
    assert parallel["wear"] == pytest.approx(serial["wear"], rel=1e-8, abs=1e-8 * serial["wear"].max())


def _two_block_problem(comm: MPI.Comm, plastic: bool = False):
    import dolfinx_fretting as dfr
    from support.blocks import E, NU, TIGHT, elasticity, plane_above, two_blocks

    V, tags, bcs = two_blocks(comm=comm)
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.5, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.5, bcs=bcs)
    # yield 400 MPa: block A's friction shear makes it yield (tests/test_zones.py)
    plasticity = dfr.Plasticity(dfr.J2Plasticity(E, NU, 400.0, 1000.0)) if plastic else None
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, solver=TIGHT, wear=dfr.Archard(1e-6),
                                  plasticity=plasticity)
    return problem, a, b


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
@pytest.mark.parametrize("plastic", [False, True], ids=["elastic", "elastic-plastic"])
def test_a_checkpoint_moves_between_rank_counts(shared_dir, plastic):
    """A state saved on N ranks loads on one and back (issue 27): the contact set is recognised by its nodes'
    coordinates, not by DOLFINx's global node numbers, which differ between rank counts, and an elastic-plastic
    state's displacement and quadrature-point history by the input mesh's node index and the points' coordinates,
    not by each rank's layout; the next
    increment from the loaded state is the one from the saved state (the same local problem and Newton iteration:
    1e-8, other factorisations' rounding only)."""
    problem, a, b = _two_block_problem(COMM, plastic)
    state, _ = problem.advance(problem.initial_state(), normal={a: 1e-3, b: 5e-4})
    state, _ = problem.advance(state, tangential={a: 2e-3})
    path = shared_dir / "state.npz"
    problem.save_state(state, path)
    after, _ = problem.advance(state, tangential={a: -1e-3})
    yielded = COMM.allreduce(float(state.plastic.p.max(initial=0.0)), op=MPI.MAX) if plastic else 0.0
    serial = history = failure = None
    if COMM.rank == 0:   # (an error here is raised on every rank below: no rank waits for one that failed)
        try:
            alone, a1, _ = _two_block_problem(MPI.COMM_SELF, plastic)
            loaded, _ = alone.load_state(path)
            assert np.array_equal(loaded.forces, state.forces) and np.array_equal(loaded.wear_gap, state.wear_gap)
            if plastic:   # the whole history, matched by coordinates: its largest plastic strain is the saved one
                assert yielded > 1e-4 and loaded.plastic.p.max() == yielded
            serial, _ = alone.advance(loaded, tangential={a1: -1e-3})
            alone.save_state(serial, shared_dir / "serial.npz")
            history = (serial.plastic.p.max(), serial.plastic.p.sum()) if plastic else None
            serial = serial.forces
        except Exception as exc:  # noqa: BLE001 - re-raised on every rank
            failure = f"{type(exc).__name__}: {exc}"
    serial, history, failure = COMM.bcast((serial, history, failure), root=0)
    assert failure is None, failure
    back, _ = problem.load_state(shared_dir / "serial.npz")   # and from one rank to N
    scale = np.abs(after.forces).max()
    assert np.abs(serial - after.forces).max() <= 1e-8 * scale
    assert np.abs(back.forces - after.forces).max() <= 1e-8 * scale
    if plastic:   # the serial history spread back over N ranks: each point's value once (the sum to rounding)
        assert COMM.allreduce(float(back.plastic.p.max()), op=MPI.MAX) == history[0]
        assert COMM.allreduce(float(back.plastic.p.sum()), op=MPI.SUM) == pytest.approx(history[1], rel=1e-12)


def _sliding_problem(comm: MPI.Comm):
    """The cylinder on the flat (both deformable, h = 40 um) with finite sliding, both bodies wearing."""
    import dolfinx_fretting as dfr
    from support.finite_sliding import cylinder_on_flat, sliding_problem

    return sliding_problem(cylinder_on_flat(comm, 0.04), "finite", wear=dfr.Archard(k_slave=1e-6, k_master=1e-6))


def _master_wear_volume(problem, state) -> float:
    """The master's worn measure: its depth at the surface compliance's nodes times their tributary lengths (the
    same whatever order the nodes are in)."""
    return float(problem.operators.surface_compliance.master_areas @ state.master_wear)


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_a_finite_sliding_checkpoint_moves_between_rank_counts(shared_dir):
    """A re-paired, worn finite-sliding state saved on N ranks loads on one and back (issue 27): each contact's
    master facet and the master's wear are saved by the input mesh's node indices, not by DOLFINx's global node
    numbers or the replicated master surface's facet order, which differ between rank counts and launches. The
    loaded pairing faces the same master points (1e-12 of the surface's extent: the same reference coordinates and
    weights, summed perhaps in another node order), the master's wear is the saved one node by node (its worn
    measure and largest depth: the same numbers reordered, 1e-12) and the next increment is the one from the
    saved state (1e-8: the force control's tolerance and other factorisations' rounding)."""
    from support.finite_sliding import pressed

    problem = _sliding_problem(COMM)
    state = pressed(problem)
    for stroke in np.linspace(0.0, 0.1, 6)[1:]:   # 2.5 elements: paired anew on the way
        state = problem.commit(state, problem.solve(state, tangential=stroke))
    assert problem.sliding.repairs > 0 and state.master_wear.max() > 0
    path = shared_dir / "sliding.npz"
    problem.save_state(state, path)
    after = problem.commit(state, problem.solve(state, tangential=0.11))
    serial = failure = None
    if COMM.rank == 0:   # (an error here is raised on every rank below: no rank waits for one that failed)
        try:
            alone = _sliding_problem(MPI.COMM_SELF)
            loaded, _ = alone.load_state(path)
            extent = np.ptp(state.pairing.coords, axis=0).max()
            assert np.abs(loaded.pairing.master_points - state.pairing.master_points).max() <= 1e-12 * extent
            assert np.array_equal(loaded.forces, state.forces) and np.array_equal(loaded.wear_gap, state.wear_gap)
            assert _master_wear_volume(alone, loaded) == pytest.approx(_master_wear_volume(problem, state),
                                                                       rel=1e-12)
            assert loaded.master_wear.max() == state.master_wear.max()
            moved = alone.commit(loaded, alone.solve(loaded, tangential=0.11))
            alone.save_state(moved, shared_dir / "serial.npz")
            serial = (moved.forces, moved.wear_gap, _master_wear_volume(alone, moved))
        except Exception as exc:  # noqa: BLE001 - re-raised on every rank
            failure = f"{type(exc).__name__}: {exc}"
    serial, failure = COMM.bcast((serial, failure), root=0)
    assert failure is None, failure
    back, _ = problem.load_state(shared_dir / "serial.npz")   # and from one rank to N
    scale = np.abs(after.forces).max()
    assert np.abs(serial[0] - after.forces).max() <= 1e-8 * scale
    assert np.abs(back.forces - after.forces).max() <= 1e-8 * scale
    assert np.abs(serial[1] - after.wear_gap).max() <= 1e-8 * np.abs(after.wear_gap).max()
    assert serial[2] == pytest.approx(_master_wear_volume(problem, after), rel=1e-8)
    assert _master_wear_volume(problem, back) == pytest.approx(serial[2], rel=1e-12)


def _rubbed_block_fatigue(comm: MPI.Comm):
    """Fatigue parameters of one rubbing cycle of the graded pulled block (tests/support/fatigue_block.py): the
    summary and every rank's points gathered on rank 0."""
    from dolfinx_fretting import fatigue
    from dolfinx_fretting.fatigue_fields import fatigue_over_cycle
    from dolfinx_fretting.materials import LinearElastic
    from support.blocks import E, NU
    from support.fatigue_block import pulled_block, rubbed_cycle

    problem = pulled_block(comm, n=8, gap=0.0, graded=True)
    # depth 1: the whole block, so that every rank has points (a partition may give the top to one rank)
    result = fatigue_over_cycle(problem, rubbed_cycle(problem), 1.0, LinearElastic(E, NU),
                                fatemi_socie=fatigue.FatemiSocie(0.5, 800.0),
                                strain_life=fatigue.BasquinCoffinManson(2464.0, -0.1715, 0.0711, -0.6098, 116000.0),
                                critical=fatigue.CriticalDistance(0.1, "line", band=0.1))
    problem.destroy()
    order = np.lexsort(result.ruiz_coordinates.T[::-1])   # the contact set's order may follow the partition
    return result.summary, result.gather(comm), result.ruiz[order]


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_batched_displacements_match_one_back_solve_each():
    """problem.displacements under MPI (one distributed multiple right-hand-side MUMPS solve, what the fatigue
    glue reads) gives each rank the owned and ghost values of problem.displacement's one back-solve per state,
    in batches of 3 (the same factors and right-hand sides: 1e-12 of the largest displacement)."""
    from dolfinx_fretting import readers
    from support.fatigue_block import pulled_block, rubbed_cycle

    problem = pulled_block(COMM, n=8, gap=0.0, graded=True)
    states = rubbed_cycle(problem)
    singles = [problem.displacement(state).x.array.copy() for state in states]
    scale = COMM.allreduce(max(np.abs(u).max(initial=0.0) for u in singles), op=MPI.MAX)
    batch_size = readers.batch_size
    readers.batch_size = lambda operators: 3
    try:
        batched = problem.displacements(states)
    finally:
        readers.batch_size = batch_size
    worst = max(np.abs(u.x.array - single).max(initial=0.0) for u, single in zip(batched, singles))
    problem.destroy()
    assert scale > 0 and COMM.allreduce(worst, op=MPI.MAX) <= 1e-12 * scale


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_fatigue_over_cycle_matches_serial():
    """The fatigue glue under MPI (issue 24): the maxima, their places and planes, Ruiz's parameter at the contact
    nodes and every point's columns equal the serial run's (other factorisations' rounding only: 1e-8; the
    plane angles, on a 1-degree grid, exactly)."""
    summary, columns, ruiz = _rubbed_block_fatigue(COMM)
    serial = failure = None
    if COMM.rank == 0:   # (an error here is raised on every rank below: no rank waits for one that failed)
        try:
            serial = _rubbed_block_fatigue(MPI.COMM_SELF)
        except Exception as exc:  # noqa: BLE001 - re-raised on every rank
            failure = f"{type(exc).__name__}: {exc}"
    failure = COMM.bcast(failure, root=0)
    assert failure is None, failure
    serial_summary, serial_ruiz = COMM.bcast((serial[0], serial[2]) if COMM.rank == 0 else None, root=0)
    assert summary["swt_max"] > 0 and summary["ruiz_max"] > 0   # a case with something to compare
    for key, value in serial_summary.items():
        if value is None or key.endswith("angle"):
            assert summary[key] == value, key
        else:
            assert summary[key] == pytest.approx(value, rel=1e-8, abs=1e-12), key
    assert ruiz == pytest.approx(serial_ruiz, rel=1e-8, abs=1e-12 * np.abs(serial_ruiz).max())
    if COMM.rank == 0:
        serial_columns = serial[1]
        order = np.lexsort((columns["depth"], columns["x"]))
        serial_order = np.lexsort((serial_columns["depth"], serial_columns["x"]))
        for name, values in columns.items():
            assert values[order] == pytest.approx(serial_columns[name][serial_order], rel=1e-8, abs=1e-12), name


def _force_cycle_run(comm: MPI.Comm) -> dict:
    """Two blocks, zone A pressed by a held normal force, zone B by a displacement, rubbed two compiled cycles
    (issue 26: A's approach found inside the loop); then a tangential force beyond mu P on A, which must fail."""
    import dolfinx_fretting as dfr
    from support.blocks import elasticity, plane_above, two_blocks

    V, tags, bcs = two_blocks(comm=comm)
    a = dfr.Contact(V, (tags, 1), plane_above(), mu=0.3, bcs=bcs)
    b = dfr.Contact(V, (tags, 2), plane_above(), mu=0.3, bcs=bcs)
    problem = dfr.FrettingProblem(elasticity(V), [a, b], bcs, wear=dfr.Archard(1e-6),
                                  solver=dfr.LocalSolver(tol=1e-12))
    state, _ = problem.advance(problem.initial_state(), normal={a: dfr.Force(100.0), b: 1e-3})
    path = dfr.CyclePath.waveform(8, tangential={a: 3e-3, b: 3e-3})
    for _ in range(2):
        result = problem.run_cycle(state, path)
        assert result.compiled
        state = problem.commit(state, result)
    failure = None
    try:
        problem.run_cycle(state, dfr.CyclePath.waveform(8, tangential={a: dfr.Force(60.0), b: 3e-3}))
    except dfr.ConvergenceError as exc:
        failure = (exc.step, str(exc))
    out = {"wear": state.wear_gap, "obstacle": state.obstacle, "force": problem.total_force(state, a),
           "failure": failure}
    problem.destroy()
    return out


@pytest.mark.skipif(COMM.size == 1, reason="collective test: ./tasks.sh test runs it under mpirun -n 2 and -n 3")
def test_force_controlled_compiled_cycles_match_serial():
    """A held force in the compiled loop under MPI (the load control runs on rank 0, broadcast): every rank holds
    the serial run's wear and obstacle (other factorisations' rounding only: 1e-8), and the failure of a force
    beyond friction is raised on every rank at the serial run's step."""
    parallel = _force_cycle_run(COMM)
    serial = COMM.bcast(_force_cycle_run(MPI.COMM_SELF) if COMM.rank == 0 else None, root=0)
    assert parallel["force"][0] == pytest.approx(100.0, rel=1e-7)   # force_tol 1e-8 of the largest force
    assert parallel["wear"] == pytest.approx(serial["wear"], rel=1e-8, abs=1e-8 * serial["wear"].max())
    assert parallel["obstacle"] == pytest.approx(serial["obstacle"], rel=1e-8)
    assert parallel["failure"] is not None and parallel["failure"][0] == serial["failure"][0]
    assert "cannot be reached" in parallel["failure"][1]
