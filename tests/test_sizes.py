"""The size estimate before meshing (dolfinx_fretting.sizes) against the models actually built, and the refusal
of a model that would not fit in memory (before any mesh, with a message naming the keys and the numbers)."""

from __future__ import annotations

import functools
import math
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx_fretting import delassus_routes, sizes
from dolfinx_fretting.cli import main
from dolfinx_fretting.geometries import half_cylinder
from dolfinx_fretting.geometries import sphere as sphere_module
from dolfinx_fretting.scenes import SceneError, load_scene
from dolfinx_fretting.sizes import SizeError, check_size, estimate, msh_node_count

COMM = MPI.COMM_WORLD
#: Quiet, short outputs for the runs of these tests.
QUIET = ["output.xdmf=false", "output.plots=false", "output.progress=false"]

#: Each built-in scene on its default mesh and on a coarser one.
CASES = [
    ("hertz", []), ("hertz", ["geometry.contact_mesh_size=0.02"]),
    ("cylinder-flat", []), ("cylinder-flat", ["geometry.contact_mesh_size=0.02"]),
    ("cylinder-flat-partial", []), ("cylinder-flat-partial", ["geometry.contact_mesh_size=0.04"]),
    ("mccoll", []), ("mccoll", ["geometry.contact_mesh_size=0.02"]),
    ("stromberg-block", []), ("stromberg-block", ["geometry.nx=25", "geometry.ny=20"]),
    ("sphere-flat", []), ("sphere-flat", ["geometry.contact_mesh_size=0.09"]),
    # the sphere's uniform zone sized from the wear of 10^4 cycles (0.51 mm, window 0.42 mm), and set by hand
    ("sphere-flat", ["loading.cycles=10000", "wear.cycle_jump=true", "geometry.contact_mesh_size=0.09"]),
    ("sphere-flat", ["geometry.contact_half_width=0.4", "geometry.contact_mesh_size=0.09"]),
    ("pad-specimen", []), ("pad-specimen", ["geometry.contact_mesh_size=0.04"]),
]


@pytest.mark.parametrize("name,overrides", CASES, ids=[" ".join([n, *o]) for n, o in CASES])
def test_estimate_matches_the_built_model(name, overrides):
    """Dofs and contacts estimated before meshing against the model built from the same scene."""
    from dolfinx_fretting.simulation import ContactModel

    scene = load_scene(name, overrides)
    size = estimate(scene, COMM.size)
    model = ContactModel(scene, COMM)
    try:
        dofs, contacts = model.problem.n_dofs, model.contact.nc
    finally:
        model.problem.destroy()
    assert size.contacts == contacts  # the contact zones are structured: the window's nodes are counted exactly
    if size.exact:  # rectangle and sphere: structured meshes, counted exactly
        assert size.dofs == dofs
    else:
        # gmsh's unstructured part: a node density fitted on 18 meshes (h = 1.25-40 um) of gmsh 4.8 with
        # residuals <= 1.4 %; 10 % leaves room for another gmsh release's frontal mesher (the 0.11 stack has 4.15).
        assert size.dofs == pytest.approx(dofs, rel=0.10)
    assert size.total_bytes > sizes.BASELINE_BYTES * COMM.size


@pytest.mark.parametrize("overrides", [["geometry.contact_mesh_size=0.04"],
                                       ["geometry.contact_mesh_size=0.04", "contact.obstacle=rigid_plane"]])
def test_estimate_counts_the_depth_graded_sphere(overrides, monkeypatch):
    """The sphere's opt-in depth-graded mesh (meshes_3d.sphere_on_flat's depth_growth, coarsening, field_cell,
    read through Sphere.mesh_options by both the estimate and the build): dofs and contacts exact, as the
    tensor grid's."""
    from dolfinx_fretting.geometries.sphere import Sphere
    from dolfinx_fretting.simulation import ContactModel

    today = Sphere.mesh_options
    monkeypatch.setattr(Sphere, "mesh_options", lambda self, scene: {
        **today(self, scene), "depth_growth": 1.5, "coarsening": 2, "field_cell": 0.25})
    scene = load_scene("sphere-flat", overrides)
    size = estimate(scene, COMM.size)
    model = ContactModel(scene, COMM)
    try:
        dofs, contacts = model.problem.n_dofs, model.contact.nc
    finally:
        model.problem.destroy()
    monkeypatch.setattr(Sphere, "mesh_options", today)
    assert size.exact and size.dofs == dofs and size.contacts == contacts
    # the options reached the estimate: not today's count (at this coarse h the zone, rounded up to 9 cubes for
    # two coarsenings, makes the graded mesh the larger one)
    assert size.dofs != estimate(scene, COMM.size).dofs


@pytest.mark.parametrize("name", ["hertz", "cylinder-flat", "mccoll"])
def test_estimate_does_not_depend_on_the_last_bit_of_a_sine(name, monkeypatch):
    """The half-cylinder's boundary samples lie on its arc up to the rounding of sin and cos, which differs between
    numpy builds and CPUs (issue 22: 951 against 934 nodes for hertz on an AVX-512 machine's numpy 2). Moving every
    sample by a few units in the last place, inwards or outwards, must give the same estimate."""
    scene = load_scene(name, ["geometry.contact_mesh_size=0.02"])
    expected = estimate(scene)
    boundary = half_cylinder._cylinder_boundary
    for factor in (1 - 4e-16, 1 + 4e-16):
        def rounded_otherwise(R, n=20000, factor=factor):
            x, y, length = boundary(R, n)
            # scale about the axis (0, R): every arc sample moves radially by ~ R * 4e-16 (a couple of ulps)
            return x * factor, R + (y - R) * factor, length
        monkeypatch.setattr(half_cylinder, "_cylinder_boundary", rounded_otherwise)
        moved = estimate(scene)
        # exactly: the only floating-point differences are ~1e-16 relative in one sample's weight
        assert (moved.nodes, moved.contacts) == (expected.nodes, expected.contacts), factor


def test_estimate_is_pure_and_fast_for_a_typo():
    """The estimate of a mesh 10^4 times too fine imports no DOLFINx and builds nothing (a fresh interpreter)."""
    code = ("import sys; from dolfinx_fretting.scenes import load_scene; from dolfinx_fretting.sizes import estimate; "
            "e = estimate(load_scene('cylinder-flat', ['geometry.contact_mesh_size=5e-5'])); "
            "print(e.dofs, 'dolfinx' in sys.modules, 'gmsh' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).resolve().parents[1]).stdout.split()
    # 2 bodies x ~(2 x 9000 arc segments) x (2250 layers) structured nodes alone: > 8e7 dofs
    assert int(out[0]) > 8e7
    assert out[1:] == ["False", "False"]


def _no_mesh(monkeypatch):
    """Every mesher raises: a test that passes with this did not mesh."""
    from dolfinx_fretting import geometries, meshes, meshes_3d

    import dolfinx_fretting.simulation as simulation

    def refuse(function):
        @functools.wraps(function)  # the signature stays readable (sizes reads the meshers' defaults from it)
        def meshed(*args, **kwargs):
            raise AssertionError(f"a mesh was built ({function.__name__})")
        return meshed
    for module, name in ((meshes, "cylinder_on_flat"), (meshes, "half_cylinder"), (meshes, "rectangle"),
                         (meshes_3d, "sphere_on_flat"), (geometries, "build_scene_model"),
                         (simulation, "build_scene_model")):
        monkeypatch.setattr(module, name, refuse(getattr(module, name)))


def test_refusal_names_the_keys_and_the_numbers(tmp_path, monkeypatch):
    """contact_mesh_size 5e-5 (a typo for 5e-2) on cylinder-flat: refused before any mesh, output folder untouched."""
    from dolfinx_fretting.simulation import run_scene

    _no_mesh(monkeypatch)
    # a fixed reading: the machine's own moves between the run's reading and a second one here (other processes)
    available = 3 * 2**30
    monkeypatch.setattr(sizes, "available_memory", lambda: (available, "MemAvailable"))
    scene = load_scene("cylinder-flat", ["geometry.contact_mesh_size=5e-5"])
    out = tmp_path / "run"
    with pytest.raises(SizeError) as info:
        run_scene(scene, out, COMM, quiet=True)
    text = str(info.value)
    assert "geometry.contact_mesh_size = 5e-05" in text
    assert "--ignore-size" in text and "ignore_size=True" in text
    assert f"{available / 2**30:.3g} GB available" in text
    size = estimate(scene)
    assert f"peak memory ~{size.total_bytes / 2**30:.3g} GB" in text
    assert "factor" in text and "W_build" in text  # the breakdown
    assert not out.exists()  # refused before the folder was claimed


def test_contact_mesh_size_1e_5_is_refused_before_meshing():
    """The issue's typo (1e-5): the scene's own bound on the refined zone's elements refuses it first."""
    with pytest.raises(SceneError, match=r"geometry.contact_mesh_size = 1e-05"):
        load_scene("cylinder-flat", ["geometry.contact_mesh_size=1e-5"])


class _Rank1Comm:
    """A two-rank communicator seen from rank 1: its broadcast returns rank 0's value."""

    size, rank = 2, 1

    def __init__(self, root_value):
        self.root_value = root_value

    def bcast(self, obj, root=0):
        return self.root_value


def test_every_rank_decides_with_rank_0s_reading(monkeypatch):
    """Rank 1 reads plenty of memory, rank 0 little: rank 1 refuses too (rank 0's reading is broadcast)."""
    scene = load_scene("hertz")
    monkeypatch.setattr(sizes, "available_memory", lambda: (10**15, "MemAvailable"))
    check_size(scene, _Rank1Comm((10**15, "MemAvailable")))
    with pytest.raises(SizeError, match="1 MB available"):
        check_size(scene, _Rank1Comm((2**20, "MemAvailable")))


def test_override_lets_a_small_run_through(tmp_path, monkeypatch):
    """With 1 MB 'available' a small hertz run is refused; ignore_size=True runs it and records the estimate."""
    from dolfinx_fretting.simulation import run_scene

    monkeypatch.setattr(sizes, "available_memory", lambda: (2**20, "test"))
    scene = load_scene("hertz", ["geometry.contact_mesh_size=0.04", "loading.tangential_increments=2", *QUIET])
    with pytest.raises(SizeError):
        run_scene(scene, tmp_path / "refused", COMM, quiet=True)
    summary = run_scene(scene, tmp_path / "run", COMM, quiet=True, ignore_size=True)
    recorded = json.loads((tmp_path / "run" / "summary.json").read_text())["size_estimate"]
    assert recorded == json.loads(json.dumps(estimate(scene, COMM.size).as_dict()))
    assert recorded["contacts"] == summary["contacts"]
    assert recorded["dofs"] == pytest.approx(summary["dofs"], rel=0.10)  # gmsh mesh: see the first test


def test_cli_refuses_with_exit_2_and_no_traceback(tmp_path, monkeypatch, capsys):
    """`run` and `study` refuse the typo with exit code 2 and a message; --ignore-size is accepted by both."""
    import dolfinx_fretting.study as study

    _no_mesh(monkeypatch)
    monkeypatch.setattr(study, "run_study", lambda *a, **k: pytest.fail("the study started"))
    typo = ["--set", "geometry.contact_mesh_size=5e-5"]
    assert main(["run", "cylinder-flat", "--out", str(tmp_path / "run"), *typo]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dolfinx-fretting: the model would need") and "Traceback" not in err
    assert "geometry.contact_mesh_size = 5e-05" in err
    # the study's default reference halves the contact elements: the reference of 1e-4 is refused at 5e-5
    assert main(["study", "cylinder-flat", "--out", str(tmp_path / "study"), "--set",
                 "geometry.contact_mesh_size=1e-4"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("dolfinx-fretting study: the model would need") and "Traceback" not in err
    assert "geometry.contact_mesh_size = 5e-05" in err


def test_cli_prints_the_estimate_and_ignore_size_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sizes, "available_memory", lambda: (2**20, "test"))
    args = ["run", "hertz", "--out", str(tmp_path / "run"), "--set", "geometry.contact_mesh_size=0.04",
            "--set", "loading.tangential_increments=2", *[x for s in QUIET for x in ("--set", s)]]
    assert main(args) == 2
    capsys.readouterr()
    assert main([*args, "--ignore-size"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("[hertz] size estimate: ~") and "contacts" in first


def _square_msh(path: Path, version: float, binary: bool) -> int:
    """A small gmsh mesh written in the given format; returns gmsh's node count."""
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(2, [1], 1)
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.1)
        gmsh.model.mesh.generate(2)
        gmsh.option.setNumber("Mesh.MshFileVersion", version)
        gmsh.option.setNumber("Mesh.Binary", int(binary))
        gmsh.write(str(path))
        return len(gmsh.model.mesh.getNodes()[0])
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("version,binary", [(4.1, False), (4.1, True), (2.2, False), (2.2, True)])
def test_msh_header_node_count(tmp_path, version, binary):
    """The node count read from a .msh file's $Nodes header, without reading the nodes, is gmsh's."""
    if COMM.rank != 0:
        pytest.skip("gmsh writes on rank 0")
    path = tmp_path / "square.msh"
    nodes = _square_msh(path, version, binary)
    assert nodes > 100
    assert msh_node_count(path) == nodes
    (tmp_path / "bad.msh").write_text("not a mesh")
    assert msh_node_count(tmp_path / "bad.msh") is None


@pytest.mark.skipif(COMM.size > 1, reason="serial: the measured arrays are one rank's")
def test_memory_terms_are_their_closed_forms():
    """The dense contact algebra's terms against the arrays they count, measured on the built models (nc contacts,
    m = 2 nc rows): ``W`` is W itself plus the compiled loop's transposed copy (their nbytes: 2 x 8 m^2 on one
    rank), ``cycle_cache`` the pattern cache's LU blocks of a whole cycle (80 increments of the Stromberg block),
    and ``W_build`` the selected inverse's working set 32 s^2 + 8 m s, s the dofs H touches (counted in H: the
    slave's and, against an elastic flat, about as many of the master's; 15 %: the master's segments under 17
    contacts here hold 19 nodes, s = 72 against the estimate's 2 m = 68, (72 / 68)^2 = 1.12). The peak holds
    everything but the W build's working set and the cycle cache, plus the larger of the two (the working set is
    freed before the cycles start)."""
    from dolfinx_fretting.simulation import ContactModel

    block = load_scene("stromberg-block", ["geometry.nx=25", "geometry.ny=20"])
    size = estimate(block, 1)
    model = ContactModel(block, COMM)
    try:
        operators = model.problem.operators
        n = block.loading.increments_per_cycle
        transposed, _, cache = operators.kernel_data(n)
        assert size.memory["W"] == operators.W.nbytes + transposed.nbytes
        assert size.memory["cycle_cache"] == cache.lu.nbytes == 8 * n * operators.W.shape[0] ** 2
    finally:
        model.problem.destroy()
    rest = sum(v for k, v in size.memory.items() if k not in ("W_build", "cycle_cache"))
    assert size.total_bytes == rest + max(size.memory["W_build"], size.memory["cycle_cache"])
    assert size.total_bytes < sum(size.memory.values())

    two_bodies = load_scene("cylinder-flat", ["geometry.contact_mesh_size=0.04"])
    size = estimate(two_bodies, 1)
    model = ContactModel(two_bodies, COMM)
    try:
        H = model.contact.H
        m, s = H.shape[0], np.unique(H.indices).size
    finally:
        model.problem.destroy()
    assert size.contacts * 2 == m
    assert size.memory["W_build"] == pytest.approx(32 * s * s + 8 * m * s, rel=0.15)


def test_replicated_memory_terms_grow_with_the_ranks():
    """Every rank counted: from 1 to 3 ranks the interpreter (baseline) and the surface compliance of finite sliding
    (kept on every rank) triple, W doubles (W on each rank plus one transposed copy: (3 + 1) / (1 + 1)), the
    factor of the default 'owned' route (a whole factor on each rank besides the distributed one) quadruples, and
    the mesh (distributed) stays."""
    scene = load_scene("cylinder-flat", ["geometry.contact_mesh_size=0.02", "contact.sliding='finite'"])
    one, three = estimate(scene, 1).memory, estimate(scene, 3).memory
    ratio = {key: three[key] / one[key] for key in one}
    expected = {"baseline": 3.0, "surface_compliance": 3.0, "W": 2.0, "factor": 4.0, "mesh": 1.0}
    for key, value in expected.items():
        assert ratio[key] == pytest.approx(value, rel=1e-5), key   # each term is int(): 1 byte in >= 1e5


def test_the_schur_routes_second_factor_is_counted(monkeypatch):
    """W by the Schur route needs a second MUMPS factor, of [[K, H^T], [H, 0]], beside K's while it builds: counted as
    SCHUR_FACTOR_RATIO times K's factor whenever the route is taken (asked for, or ``"auto"``'s choice by the same
    rule W's build follows), its build's working set then three dense Schur complements (3 x 8 m^2 bytes); not
    counted when another route builds W (auto below the rule's size, or under MPI)."""
    from dolfinx_fretting.geometries.sphere import Sphere

    today = Sphere.mesh_options
    # the depth-graded mesh at a/h = 10: ~53 dofs of K per row of H, 1560 rows: "auto" takes the Schur route there
    monkeypatch.setattr(Sphere, "mesh_options", lambda self, scene: {
        **today(self, scene), "depth_growth": 1.5, "coarsening": 2, "field_cell": 0.25})
    scene = load_scene("sphere-flat", ["geometry.contact_mesh_size=0.0187"])
    serial, two_ranks = estimate(scene, 1), estimate(scene, 2)
    rows = 3 * serial.contacts
    assert sizes.auto_route(1, rows, serial.dofs) == "schur"
    # both terms are int() of one float: a few bytes in 1e9
    assert serial.memory["schur_factor"] == pytest.approx(sizes.SCHUR_FACTOR_RATIO * serial.memory["factor"],
                                                          rel=1e-8)
    assert serial.memory["W_build"] == 3 * 8 * rows * rows  # MUMPS's Schur block, PETSc's copy, the package's
    assert "schur_factor" not in two_ranks.memory  # MPI: the owned route
    asked = estimate(load_scene("sphere-flat", ["geometry.contact_mesh_size=0.0187",
                                                "solver.delassus_method='selected_inverse'"]), 1)
    assert "schur_factor" not in asked.memory and asked.memory["W_build"] > 8 * rows * rows
    monkeypatch.setattr(Sphere, "mesh_options", today)
    # the uniform cubes (the mesh below GRADED_FROM elements across a): ~129 dofs of K per row of H, so "auto" keeps
    # the selected inverse; asked for, counted
    monkeypatch.setattr(sphere_module, "GRADED_FROM", math.inf)
    uniform = estimate(load_scene("sphere-flat", ["geometry.contact_mesh_size=0.0117"]), 1)
    assert 3 * uniform.contacts >= delassus_routes.AUTO_SCHUR_ROWS and "schur_factor" not in uniform.memory
    forced = estimate(load_scene("sphere-flat", ["geometry.contact_mesh_size=0.0117",
                                                 "solver.delassus_method='schur'"]), 1)
    assert forced.memory["schur_factor"] == pytest.approx(sizes.SCHUR_FACTOR_RATIO * forced.memory["factor"],
                                                          rel=1e-8)


def test_auto_counts_the_selected_inverse_where_the_schur_factor_does_not_fit(monkeypatch):
    """sphere-flat's default mesh for 10^5 cycles: "auto"'s size rule takes the Schur route, whose second factor
    brings the peak to ~21 GB (the selected inverse's ~7 GB). With less memory available than that peak the build
    takes the selected inverse (compliance: the factor would not fit), and the estimate counts what it will build:
    the same terms as the selected inverse asked for; with enough, the Schur route as before."""
    cycles = ["loading.cycles=100000", "wear.cycle_jump=true"]
    scene = load_scene("sphere-flat", cycles)
    pure = estimate(scene)
    assert "schur_factor" in pure.memory
    asked = estimate(load_scene("sphere-flat", [*cycles, "solver.delassus_method='selected_inverse'"]))
    assert asked.total_bytes < 0.5 * pure.total_bytes
    tight = estimate(scene, 1, available=pure.total_bytes - 1)
    assert tight.memory == asked.memory
    assert estimate(scene, 1, available=pure.total_bytes).memory == pure.memory
    # check_size lets it through on a machine that holds the selected inverse's peak, not the Schur route's
    monkeypatch.setattr(sizes, "available_memory", lambda: (asked.total_bytes, "test"))
    assert check_size(scene).memory == asked.memory
    monkeypatch.setattr(sizes, "available_memory", lambda: (asked.total_bytes - 1, "test"))
    with pytest.raises(SizeError):
        check_size(scene)


def test_the_schur_factor_ratio_covers_every_measured_point():
    """SCHUR_FACTOR_RATIO is the envelope of the measured ratio of the Schur route's factor to K's (MUMPS INFOG(22),
    the columns "MUMPS Schur" and "MUMPS K" of benchmarks/results/schur_setup.md: 1.2-2.9): at least every point,
    and not more than 1.5 times the largest (an envelope, not a guess far above the measurements)."""
    table = (Path(__file__).resolve().parents[1] / "benchmarks" / "results" / "schur_setup.md").read_text()
    header = next(line for line in table.splitlines() if line.startswith("| stack | mesh |"))
    columns = [cell.strip() for cell in header.strip("|").split("|")]
    k_column, schur_column = columns.index("MUMPS K (MB)"), columns.index("MUMPS Schur (MB)")
    ratios = []
    for line in table.splitlines():
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        if len(cells) == len(columns) and cells[columns.index("route")] == "schur":
            ratios.append(float(cells[schur_column]) / float(cells[k_column]))
    assert len(ratios) >= 8
    assert max(ratios) <= sizes.SCHUR_FACTOR_RATIO <= 1.5 * max(ratios)
