"""Mesh files (``geometry.kind = "file"``) get the scene's plausibility checks before any solve, and every fault of
a mesh file is one line naming the file and exit 2 (issue 27's fault sweep, as tests).

Each case is a fault a user makes with their own mesh: a mesh written in metres for a scene in N, mm and MPa; a
candidate window narrower than the contact; a mesh mixing triangles and quadrilaterals (DOLFINx crashed: exit 59); a
path that is missing, empty or a folder, a relative path given by ``--set``, a ``.msh`` without physical groups or of
a 3D body, an ``.xdmf`` without its ``.h5``; a name given to two groups, two markers named alike, a group with two
roles (clamped and in contact), a contact surface inside the body. The meshes are small gmsh models written here; the
runs go through ``dolfinx-fretting run`` (in process, or in a child where the old code crashed the process or where
the exit code of ``mpirun`` matters).
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import gmsh
import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting.cli import main  # noqa: E402
from dolfinx_fretting.scenes import SceneError, load_scene  # noqa: E402
from support.mesh_files import shared_folder, write_msh  # noqa: E402

COMM = MPI.COMM_WORLD
pytestmark = pytest.mark.skipif(COMM.size > 1, reason="runs the command line serially (and under mpirun itself)")
ROOT = Path(__file__).resolve().parents[1]
WIDTH, HEIGHT, H = 2.0, 1.0, 0.25   # the block (mm) and its element size
P = 100.0                           # its normal force (N/mm): a mean strain P / (2 mm x E') = 3.8e-4 in mm
R, PAD_P = 10.0, 500.0              # the curved pad's radius (mm) and force (N/mm): Hertz half-width 0.166 mm


def block(scale: float = 1.0, recombine_right: bool = False, groups: bool = True, inner: bool = False):
    """gmsh model of the block [0, 2] x [0, 1] (times ``scale``) in two halves, with groups "floor" (y = 0), "top"
    and "block"; ``recombine_right``: the right half in quadrilaterals (a mixed mesh); ``inner``: a group "inner",
    the line between the halves (inside the body)."""
    def build():
        g = gmsh.model.geo
        corners = [(0, 0), (1, 0), (2, 0), (2, 1), (1, 1), (0, 1)]
        p = [g.addPoint(scale * x, scale * y, 0, scale * H) for x, y in corners]
        lines = [g.addLine(p[i], p[(i + 1) % 6]) for i in range(6)]
        middle = g.addLine(p[1], p[4])
        left = g.addPlaneSurface([g.addCurveLoop([lines[0], middle, lines[4], lines[5]])])
        right = g.addPlaneSurface([g.addCurveLoop([lines[1], lines[2], lines[3], -middle])])
        g.synchronize()
        if recombine_right:
            gmsh.model.mesh.setRecombine(2, right)
        if groups:
            named = [(1, [lines[0], lines[1]], 1, "floor"), (1, [lines[3], lines[4]], 2, "top"),
                     (2, [left, right], 1, "block")] + ([(1, [middle], 3, "inner")] if inner else [])
            for dim, tags, tag, name in named:
                gmsh.model.addPhysicalGroup(dim, tags, tag)
                gmsh.model.setPhysicalName(dim, tag, name)
    return build


def cube():
    """A unit cube of tetrahedra with a "floor", a "top" and a "block": a 3D mesh."""
    gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    for dim, tags, tag, name in ((2, [5], 1, "floor"), (2, [6], 2, "top"), (3, [1], 1, "block")):
        gmsh.model.addPhysicalGroup(dim, tags, tag)
        gmsh.model.setPhysicalName(dim, tag, name)


def pad():
    """A curved pad: the lower 30 degrees of a circle of radius R on either side of its lowest point (0, 0), closed
    by a flat top at y = 3 ("top"; the arc: "arc"), 0.05 mm elements at the lowest point."""
    g = gmsh.model.geo
    angle = np.radians(30.0)
    centre, bottom = g.addPoint(0, R, 0), g.addPoint(0, 0, 0, 0.05)
    x, y = R * np.sin(angle), R * (1 - np.cos(angle))
    left, right, top_right, top_left = (g.addPoint(a, b, 0, 0.5) for a, b in [(-x, y), (x, y), (x, 3), (-x, 3)])
    arc = [g.addCircleArc(left, centre, bottom), g.addCircleArc(bottom, centre, right)]
    sides = [g.addLine(right, top_right), g.addLine(top_right, top_left), g.addLine(top_left, left)]
    g.addPlaneSurface([g.addCurveLoop([*arc, *sides])])
    g.synchronize()
    for dim, tags, tag, name in ((1, arc, 1, "arc"), (1, [sides[1]], 2, "top"), (2, [1], 1, "pad")):
        gmsh.model.addPhysicalGroup(dim, tags, tag)
        gmsh.model.setPhysicalName(dim, tag, name)
    distance = gmsh.model.mesh.field.add("Distance")
    gmsh.model.mesh.field.setNumbers(distance, "PointsList", [bottom])
    threshold = gmsh.model.mesh.field.add("Threshold")
    for key, value in (("InField", distance), ("SizeMin", 0.05), ("SizeMax", 0.5), ("DistMin", 0.5),
                       ("DistMax", 3.0)):
        gmsh.model.mesh.field.setNumber(threshold, key, value)
    gmsh.model.mesh.field.setAsBackgroundMesh(threshold)
    for option in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(option, 0)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The folder of the meshes: block.msh (mm), block_m.msh (the same in metres), mixed.msh, nogroups.msh,
    inner.msh, cube.msh, twice.msh (the name "top" given to two curve groups), pad.msh."""
    folder = shared_folder(tmp_path_factory, "meshes")
    write_msh(folder / "block.msh", block())
    write_msh(folder / "block_m.msh", block(scale=1e-3))
    write_msh(folder / "mixed.msh", block(recombine_right=True))
    write_msh(folder / "nogroups.msh", block(groups=False))
    write_msh(folder / "inner.msh", block(inner=True))
    write_msh(folder / "cube.msh", cube, dim=3)
    write_msh(folder / "pad.msh", pad)
    # gmsh keeps one name per group when it writes; a file written by hand (or another tool) may name two alike
    text = (folder / "inner.msh").read_text().replace('1 3 "inner"', '1 3 "top"')
    (folder / "twice.msh").write_text(text)
    return folder


@pytest.fixture(autouse=True)
def in_files(files, monkeypatch):
    """Every run starts in the meshes' folder, as a user's in theirs: a relative path given by --set is taken from
    the working directory."""
    monkeypatch.chdir(files)


def child_env(base: dict | None = None) -> dict:
    """A child's environment that imports this checkout's package (run from the meshes' folder)."""
    env = dict(base or os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    return env


SCENE = """name = "{name}"
[geometry]
kind = "file"
path = "{path}"
[boundary]
fixed = ["top"]
[material]
E = 210000.0
nu = 0.3
[contact]
mu = 0.0
surface = "{surface}"
[loading]
{load}
normal_increments = 2
[output]
xdmf = false
plots = false
progress = false
"""


def scene_file(folder: Path, name: str = "block", path: str = "block.msh", surface: str = "floor",
               load: str = f"normal_force = {P}") -> Path:
    scene = folder / f"{name}.toml"
    scene.write_text(SCENE.format(name=name, path=path, surface=surface, load=load))
    return scene


def run(capsys, scene: Path, out: Path, *sets: str) -> tuple[int, str]:
    """``dolfinx-fretting run scene --out out --set ...`` in process: (exit code, stderr)."""
    args = ["run", str(scene), "--out", str(out), "--quiet"] + [a for s in sets for a in ("--set", s)]
    code = main(args)
    return code, capsys.readouterr().err


def assert_refused(code: int, err: str, *parts: str) -> None:
    """Exit 2 and one line (no traceback) that holds every one of ``parts``."""
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    for part in parts:
        assert part in lines[0], err


# A mesh in the wrong units ----------------------------------------------------------------------------------------
def test_a_mesh_in_metres_is_refused_naming_the_units(files, tmp_path, capsys):
    """The block written in metres (2 x 1 mm becomes 0.002 x 0.001) under the mm scene's P = 100 N/mm: the mean
    strain P / (L E') over the floor's length L = 0.002 is 0.38 > 0.1 (in mm, 3.8e-4, and the run goes). The same
    under an approach of 0.01 mm: 0.01 / (depth 0.001) = 10 > 0.1. Before the fix both ran and 'converged' with
    p_max far above E."""
    scene = scene_file(files)
    E_plane = 210000.0 / (1 - 0.3**2)
    code, err = run(capsys, scene, tmp_path / "metres", 'geometry.path="block_m.msh"')
    assert_refused(code, err, f"loading.normal_force = 100 is out of range on the mesh of {files / 'block_m.msh'}",
                   "is the mesh in metres?")
    # the estimate and its bound, from the block's floor length (0.002 mm, exact: the sum of its facets)
    assert f"= {P / (0.002 * E_plane):.3g} must stay <= 0.1" in err
    assert f"allowed: <= {0.1 * 0.002 * E_plane:.4g} N/mm" in err
    code, err = run(capsys, scene, tmp_path / "approach", 'geometry.path="block_m.msh"',
                    "loading.normal_force=none", "loading.normal_displacement=0.01")
    assert_refused(code, err, "loading.normal_displacement = 0.01 is out of range", "depth 0.001 mm",
                   "is the mesh in metres?")
    # the mesh in millimetres passes the check (and runs: the refusal is the units', not the scene's)
    code, err = run(capsys, scene, tmp_path / "mm")
    assert code == 0, err
    summary = json.loads((tmp_path / "mm" / "summary.json").read_text())
    # a clamped block pressed flat on a frictionless plane: the force control reaches P (force_tol 1e-8 of P)
    assert summary["converged"] is True and summary["normal_force"] == pytest.approx(P, rel=1e-7)


# The candidate window ---------------------------------------------------------------------------------------------
def test_a_narrow_window_on_a_mesh_file_grows_to_the_whole_answer(files, tmp_path, capsys):
    """A window of 0.05 mm on the pad, whose Hertz half-width is 0.166 mm: the contact reaches the window's edge and
    the window grows (as a built-in half-cylinder's does) until the contact fits, with a warning and the growths in
    the summary; the answer is the whole surface's (no window) to the local solver's tolerance (1e-10: 1e-8
    allowed). Before the fix the window was not watched at its edge (the run stopped, or went on truncated)."""
    scene = scene_file(files, "pad", "pad.msh", "arc", f"normal_force = {PAD_P}")
    code, err = run(capsys, scene, tmp_path / "whole")
    assert code == 0, err
    whole = json.loads((tmp_path / "whole" / "summary.json").read_text())
    code, err = run(capsys, scene, tmp_path / "narrow", "contact.candidate_half_width=0.05")
    assert code == 0, err
    narrow = json.loads((tmp_path / "narrow" / "summary.json").read_text())
    assert narrow["window_growths"] and narrow["contact_window"] > 0.166
    for key in ("max_pressure", "contact_width", "normal_force"):
        assert narrow[key] == pytest.approx(whole[key], rel=1e-8), key
    # the whole-surface answer itself: Hertz's peak 2P/(pi a) = 1917 MPa within the coarse mesh's 10 %
    E_star = 210000.0 / (1 - 0.3**2)
    a = np.sqrt(4 * PAD_P * R / (np.pi * E_star))
    assert whole["max_pressure"] == pytest.approx(2 * PAD_P / (np.pi * a), rel=0.1)


def test_a_window_wider_than_the_surface_lets_its_ends_carry_load(files, tmp_path, capsys):
    """The block's whole floor is in contact, its end nodes loaded: with a window wider than the floor those ends
    are the surface's, not the window's, and the run goes (the edge guard needs nodes outside the window)."""
    code, err = run(capsys, scene_file(files), tmp_path / "wide", "contact.candidate_half_width=5.0")
    assert code == 0, err
    summary = json.loads((tmp_path / "wide" / "summary.json").read_text())
    assert summary["window_growths"] == [] and summary["normal_force"] == pytest.approx(P, rel=1e-7)


# What the file must be --------------------------------------------------------------------------------------------
def test_a_mixed_mesh_is_refused_before_dolfinx_reads_it(files, tmp_path):
    """Triangles and quadrilaterals in one body: DOLFINx's reader crashed (PETSc SEGV, exit 59). Refused in one
    line naming the file and the cell counts, exit 2 (in a child: the old code killed the process)."""
    scene = scene_file(files)
    child = subprocess.run([sys.executable, "-m", "dolfinx_fretting", "run", str(scene), "--out",
                            str(tmp_path / "out"), "--quiet", "--set", 'geometry.path="mixed.msh"'],
                           capture_output=True, text=True, cwd=files, env=child_env(), timeout=600)
    assert_refused(child.returncode, child.stderr, f"geometry.path = '{files / 'mixed.msh'}': the body mixes",
                   "triangles and", "quadrilaterals")


@pytest.mark.parametrize("path, message", [
    ("missing.msh", "no such file"),
    ("folder.msh", "a folder, not a mesh file"),
    ("empty.msh", "the file is empty"),
    ("nogroups.msh", "the file has no physical surface (the body's cells) group"),
    ("cube.msh", "a 3D mesh (Tetrahedron 4 cells)"),
    ("twice.msh", "the name 'top' is given to 2 physical groups of dimension 1 (tags 2, 3)"),
])
def test_a_file_that_is_no_2d_mesh_is_named(files, tmp_path, capsys, path, message):
    """Each was a traceback that never named the file (an IndexError of DOLFINx's reader, a UFL error) or, for a
    name given to two groups, a run on one of them."""
    (files / "folder.msh").mkdir(exist_ok=True)
    (files / "empty.msh").write_text("")
    code, err = run(capsys, scene_file(files), tmp_path / "out", f'geometry.path="{path}"')
    assert_refused(code, err, f"geometry.path = '{files / path}': {message}")
    # the output folder is claimed (locked) before the file is read: the run created it and wrote nothing, so it
    # is gone again (an empty folder was left behind before)
    assert not (tmp_path / "out").exists()


def test_a_refused_file_keeps_a_folder_the_user_made(files, tmp_path, capsys):
    """--out made by the user (empty, or with the user's own file in it) stays as it was after a refusal."""
    (tmp_path / "empty").mkdir()
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "README").write_text("mine")
    for out in ("empty", "notes"):
        code, err = run(capsys, scene_file(files), tmp_path / out, 'geometry.path="missing.msh"')
        assert_refused(code, err, "no such file")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty", "notes"]
    assert not list((tmp_path / "empty").iterdir()) and [p.name for p in (tmp_path / "notes").iterdir()] == ["README"]


def test_reading_a_mesh_file_keeps_the_runs_signal_handlers(files, monkeypatch):
    """gmsh 4.11+ sets SIGINT to its default action (the process killed, no clean-up: no summary, a stale lock)
    when initialised, and 4.8 when imported; the mesh file is read with the run's handlers in place all along
    (while gmsh reads the file too), as the package's own meshes are. Fails on the current stack's gmsh without
    ``keep_handlers`` around the reader's initialisation."""
    import signal

    from dolfinx_fretting.scene_models import read_msh

    def handler(signum, frame):  # the run's (a stand-in)
        pass

    seen = []
    real_open = gmsh.open
    monkeypatch.setattr(gmsh, "open", lambda path: (seen.append(signal.getsignal(signal.SIGINT)), real_open(path)))
    previous = signal.signal(signal.SIGINT, handler)
    try:
        body, _ = read_msh(str(files / "block.msh"), MPI.COMM_WORLD)
        after = signal.getsignal(signal.SIGINT)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert {"floor", "top"} <= set(body.tags)  # the file was read
    if MPI.COMM_WORLD.rank == 0:  # gmsh reads on rank 0 only
        assert seen == [handler]
    assert after is handler


def test_a_relative_path_given_by_set_is_taken_from_the_working_directory(files, tmp_path, monkeypatch):
    """A scene file's own relative path is taken from its folder; one given by --set from the working directory
    (before, from the scene file's folder: for a built-in scene, inside the package)."""
    elsewhere = tmp_path / "work"
    elsewhere.mkdir()
    (elsewhere / "mine.msh").write_bytes((files / "block.msh").read_bytes())
    scene = scene_file(files)
    monkeypatch.chdir(elsewhere)
    assert load_scene(scene).geometry.path == str(files / "block.msh")
    assert load_scene(scene, ['geometry.path="mine.msh"']).geometry.path == str(elsewhere / "mine.msh")
    built_in = load_scene("stromberg-block", ["geometry.kind=file", 'geometry.path="mine.msh"', "geometry.nx=none",
                                              "geometry.ny=none", "geometry.width=none", "geometry.height=none",
                                              "geometry.quadrilateral=none", "boundary.fixed=['top']"])
    assert built_in.geometry.path == str(elsewhere / "mine.msh")


def test_an_xdmf_file_without_its_h5_is_named(files, tmp_path, capsys):
    """The block as DOLFINx XDMF (mesh and facet markers), its .h5 removed: refused naming both files. Its markers
    named twice alike (geometry.groups) are refused by the schema."""
    from dolfinx.io import XDMFFile

    if COMM.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(files / "block.msh"))
    msh, _, facet_tags = dfx.model_to_mesh(gmsh.model, MPI.COMM_SELF, 0, gdim=2)
    gmsh.finalize()
    msh.name, facet_tags.name = "block", "block_facets"
    with XDMFFile(MPI.COMM_SELF, str(tmp_path / "block.xdmf"), "w") as xdmf:
        xdmf.write_mesh(msh)
        dfx.write_meshtags(xdmf, facet_tags, msh)
    (tmp_path / "block.h5").unlink()
    scene = scene_file(files)
    code, err = run(capsys, scene, tmp_path / "out", f'geometry.path="{tmp_path / "block.xdmf"}"',
                    "geometry.groups={floor = 1, top = 2}")
    assert_refused(code, err, f"geometry.path = '{tmp_path / 'block.xdmf'}': its data file "
                              f"'{tmp_path / 'block.h5'}' is missing")
    with pytest.raises(SceneError, match=r"geometry.groups.top = 1 is out of range; allowed: a marker no other name "
                                         r"has \(geometry.groups.floor = 1 too\)"):
        load_scene(scene, [f'geometry.path="{tmp_path / "block.xdmf"}"', "geometry.groups={floor = 1, top = 1}"])


# What the scene asks of the file ----------------------------------------------------------------------------------
@pytest.mark.parametrize("sets, message", [
    (["boundary.fixed=['floor', 'top']"], "boundary.fixed = 'floor' is also contact.surface = 'floor': one role "
                                          "per group of {file}"),
    (["boundary.fixed=['top', 'top']"], "boundary.fixed = 'top' is also boundary.fixed = 'top'"),
    (["contact.surface='lid'"], "contact.surface = 'lid' is not a physical group of {file}; the file's boundary "
                                "groups: floor, top"),
    (['geometry.path="inner.msh"', "contact.surface='inner'"],
     "contact.surface = 'inner': 4 of its 4 facets in {folder}/inner.msh lie inside the body"),
])
def test_every_group_is_checked_against_the_file(files, tmp_path, capsys, sets, message):
    """A group clamped and in contact ('has no free vertex', exit 1, or the zero-size reduction), a condition named
    twice, a name the file does not have, a contact surface inside the body (a ZeroDivisionError): one line naming
    the key, the group and the file, exit 2, before anything is assembled."""
    code, err = run(capsys, scene_file(files), tmp_path / "out", *sets)
    assert_refused(code, err, message.format(file=files / "block.msh", folder=files))


def test_two_contact_zones_on_one_group_are_refused(files, tmp_path, capsys):
    """Two [[contact]] tables naming the floor (the second zone's contacts were the first's: a run on doubled
    contacts), and a further zone on the clamped top: each refused naming both keys."""
    base = SCENE.format(name="zones", path="block.msh", surface="floor", load=f"normal_force = {P}")
    zone = '\n[[contact]]\nsurface = "{}"\nplane_point = [2.0, 0.0]\nplane_normal = [-1.0, 0.0]\nmu = 0.0\n'
    for surface, message in (("floor", "contact[1].surface = 'floor' is also contact.surface = 'floor'"),
                             ("top", "boundary.fixed = 'top' is also contact[1].surface = 'top'")):
        scene = files / f"zones_{surface}.toml"
        scene.write_text(base.replace("[contact]", "[[contact]]") + zone.format(surface))
        code, err = run(capsys, scene, tmp_path / surface)
        assert_refused(code, err, message, str(files / "block.msh"))



def one_facet_floor():
    """gmsh model of the unit square whose floor is one facet (its two nodes the corners), with groups "floor"
    (y = 0), "left" (x = 0), "right" (x = 1), "top" (y = 1) and "block": held at both sides, no floor node can
    move."""
    g = gmsh.model.geo
    p = [g.addPoint(x, y, 0, 0.5) for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)]]
    lines = [g.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    g.addPlaneSurface([g.addCurveLoop(lines)])
    g.synchronize()
    gmsh.model.mesh.setTransfiniteCurve(lines[0], 2)   # the floor: one facet
    for dim, tags, tag, name in ((1, [lines[0]], 1, "floor"), (1, [lines[1]], 2, "right"), (1, [lines[2]], 3, "top"),
                                 (1, [lines[3]], 4, "left"), (2, [1], 1, "block")):
        gmsh.model.addPhysicalGroup(dim, tags, tag)
        gmsh.model.setPhysicalName(dim, tag, name)


@pytest.mark.parametrize("sets, held", [
    (["boundary.fixed=['left', 'right']"], "left, right"),
    (["boundary.displacement={left = [0.0, 0.001], right = [0.0, 0.001]}"], "top, left, right"),
])
def test_a_contact_surface_held_at_every_node_is_refused(files, tmp_path, capsys, sets, held):
    """A floor of one facet whose two nodes lie on the held sides (clamped, or moved by a prescribed displacement:
    either holds a node) cannot move towards its plane: refused before any work, naming the group, every held group
    and the file (a contact whose nodes are all prescribed has nothing to solve)."""
    mesh = write_msh(files / "one_facet_floor.msh", one_facet_floor)
    code, err = run(capsys, scene_file(files), tmp_path / "out", f'geometry.path="{mesh}"', *sets)
    assert_refused(code, err, f"contact.surface = 'floor': every node of the group is held by boundary.fixed or "
                              f"boundary.displacement ({held}) in {mesh}: none can move towards the plane")

# Under MPI --------------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_faults_under_mpirun_give_one_line(files, tmp_path, mpirun_env):
    """``mpirun -n 2``: the mixed mesh (a SEGV before), a missing file (a traceback per rank) and the mesh in metres
    (a 'converged' run): each one line, once, exit 2."""
    scene = scene_file(files)
    for path, message in (("mixed.msh", "the body mixes"), ("missing.msh", "no such file"),
                          ("block_m.msh", "is the mesh in metres?")):
        child = subprocess.run([*dfx.mpiexec(2), sys.executable, "-m", "dolfinx_fretting", "run", str(scene),
                                "--out", str(tmp_path / path), "--quiet", "--set", f'geometry.path="{path}"'],
                               capture_output=True, text=True, cwd=files, env=child_env(mpirun_env),
                               timeout=600)
        ours = [line for line in child.stderr.splitlines() if line.startswith("dolfinx-fretting")]
        assert child.returncode == 2, child.stderr
        assert "Traceback" not in child.stderr and len(ours) == 1 and message in ours[0], child.stderr
