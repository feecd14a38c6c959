"""A scene that points at the user's own mesh file (``geometry.kind = "file"``) gives the Python API's answer.

The mesh: a flat punch with rounded edges (the demo_plugin body, coarser) written by gmsh with named physical
groups. The same model is solved twice: by a user's script on the public API (its own mesh reading, form and
clamp) and by ``run_scene`` on a scene file naming the groups; both must agree to 1e-10 (the same K, contact
set and local problems: only the route through the code differs).
"""

from pathlib import Path

import gmsh
import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402
from petsc4py import PETSc  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting.materials import LinearElastic  # noqa: E402
from dolfinx_fretting.scenes import SceneError, load_scene  # noqa: E402
from dolfinx_fretting.simulation import run_scene  # noqa: E402
from support.mesh_files import shared_folder, write_msh  # noqa: E402

COMM = MPI.COMM_WORLD
E, NU, B, R, P = 210000.0, 0.3, 0.5, 10.0, 3000.0


def write_punch(path: Path, h: float = 0.04, half_width: float = 6.0, height: float = 12.0) -> None:
    """The punch of demos/demo_plugin.py with physical groups "face", "top" (curves) and "punch"."""
    def build():
        g = gmsh.model.geo
        theta = np.arcsin((half_width - B) / R)
        c_r, c_l = g.addPoint(B, R, 0), g.addPoint(-B, R, 0)
        y_side = R * (1 - np.cos(theta))
        p = [g.addPoint(x, y, 0, 0.5) for x, y in [(-B, 0), (B, 0), (half_width, y_side), (half_width, height),
                                                    (-half_width, height), (-half_width, y_side)]]
        face = [g.addLine(p[0], p[1]), g.addCircleArc(p[1], c_r, p[2])]
        sides = [g.addLine(p[2], p[3]), g.addLine(p[3], p[4]), g.addLine(p[4], p[5])]
        face.append(g.addCircleArc(p[5], c_l, p[0]))
        g.addPlaneSurface([g.addCurveLoop([face[0], face[1], *sides, face[2]])])
        g.synchronize()
        for dim, tags, tag, name in ((1, face, 1, "face"), (1, [sides[1]], 2, "top"), (2, [1], 1, "punch")):
            gmsh.model.addPhysicalGroup(dim, tags, tag)
            gmsh.model.setPhysicalName(dim, tag, name)
        dist = gmsh.model.mesh.field.add("Distance")
        gmsh.model.mesh.field.setNumbers(dist, "CurvesList", face)
        thr = gmsh.model.mesh.field.add("Threshold")
        for key, value in (("InField", dist), ("SizeMin", h), ("SizeMax", 1.0), ("DistMin", 0.02), ("DistMax", 5.0)):
            gmsh.model.mesh.field.setNumber(thr, key, value)
        gmsh.model.mesh.field.setAsBackgroundMesh(thr)
        for opt in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(opt, 0)
    write_msh(path, build)


@pytest.fixture(scope="module")
def punch_file(tmp_path_factory):
    path = shared_folder(tmp_path_factory, "punch") / "punch.msh"
    write_punch(path)
    return path


def read_punch(path: Path):
    """The user's own reading of the .msh file: (mesh, facet tags)."""
    if COMM.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
    msh, _, facet_tags = dfx.model_to_mesh(gmsh.model, COMM, 0, gdim=2)
    if COMM.rank == 0:
        gmsh.finalize()
    return msh, facet_tags


def api_answer(path: Path, increments: int = 4, window: float = 1.2) -> dict[str, float]:
    """The user's script: read the mesh, write the model, press by a force through the API."""
    msh, facet_tags = read_punch(path)
    V = dfx.vector_space(msh, 1)
    lmbda, mu = LinearElastic(E, NU).lame
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(2) + 2.0 * mu * eps(u), eps(v)) * ufl.dx
    bcs = [fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), fem.locate_dofs_topological(V, 1, facet_tags.find(2)),
                           V)]
    contact = dfr.Contact(V, (facet_tags, 1), dfr.RigidPlane([0.0, 0.0], [0.0, 1.0]), mu=0.0, bcs=bcs, window=window)
    problem = dfr.FrettingProblem(a, contact, bcs)
    state = problem.initial_state()
    for i in range(1, increments + 1):
        state = problem.commit(state, problem.solve(state, normal=dfr.Force(P * i / increments),
                                                    tangential=dfr.Displacement(0.0)))
    answer = {k: state.record[k] for k in ("normal_force", "max_pressure", "contact_width", "n_stick", "n_slip")}
    answer["contacts"] = contact.nc
    problem.destroy()
    return answer


def scene_dict(path: Path, **contact) -> dict:
    return {"name": "punch", "geometry": {"kind": "file", "path": str(path)},
            "boundary": {"fixed": ["top"]},
            "material": {"E": E, "nu": NU},
            "contact": {"mu": 0.0, "surface": "face", "candidate_half_width": 1.2, **contact},
            "loading": {"normal_force": P, "normal_increments": 4},
            "output": {"xdmf": False, "plots": False, "progress": False}}


def test_scene_file_gives_the_api_answer(punch_file, tmp_path_factory):
    folder = Path(COMM.bcast(str(tmp_path_factory.mktemp("run")) if COMM.rank == 0 else None, root=0))
    by_api = api_answer(punch_file)
    by_scene = run_scene(load_scene(scene_dict(punch_file)), folder, COMM, quiet=True)
    assert by_scene["contacts"] == by_api["contacts"]
    for key in ("normal_force", "max_pressure", "contact_width", "n_stick", "n_slip"):
        # the same K, contact set and local problems through two routes: equal to rounding
        assert by_scene[key] == pytest.approx(by_api[key], rel=1e-10, abs=1e-10), key
    # and the physics: P reached (force_tol 1e-8), the contact close to the half-plane width (0.80 mm for
    # this P, R and b; see demos/demo_plugin.py) within the coarse file mesh's element (0.04 mm) and a bit
    assert by_scene["normal_force"] == pytest.approx(P, rel=1e-8)
    assert abs(by_scene["contact_width"] / 2 - 0.7993) <= 0.06


def write_punch_xdmf(msh_path: Path, xdmf_path: Path) -> None:
    """The same punch as a DOLFINx XDMF file with its facet meshtags (markers 1 = face, 2 = top; no names)."""
    from dolfinx.io import XDMFFile

    msh, facet_tags = read_punch(msh_path)
    msh.name = "punch"
    facet_tags.name = "punch_facets"
    with XDMFFile(COMM, str(xdmf_path), "w") as xdmf:
        xdmf.write_mesh(msh)
        dfx.write_meshtags(xdmf, facet_tags, msh)


def test_xdmf_scene_file_gives_the_msh_answer(punch_file, tmp_path_factory):
    """The punch as an XDMF file with unnamed markers named by geometry.groups: the .msh scene's answer."""
    folder = Path(COMM.bcast(str(tmp_path_factory.mktemp("xdmf")) if COMM.rank == 0 else None, root=0))
    xdmf = folder / "punch.xdmf"
    write_punch_xdmf(punch_file, xdmf)
    by_msh = run_scene(load_scene(scene_dict(punch_file)), folder / "msh", COMM, quiet=True)
    scene = scene_dict(xdmf)
    scene["geometry"]["groups"] = {"face": 1, "top": 2}
    by_xdmf = run_scene(load_scene(scene), folder / "xdmf", COMM, quiet=True)
    assert by_xdmf["contacts"] == by_msh["contacts"]
    for key in ("normal_force", "max_pressure", "contact_width", "n_stick", "n_slip"):
        # the same mesh written and read back (coordinates exact in HDF5 doubles): equal to rounding
        assert by_xdmf[key] == pytest.approx(by_msh[key], rel=1e-10, abs=1e-10), key
    # unnamed markers go by their numbers, and a wrong name lists them
    scene = scene_dict(xdmf, surface="1")
    scene["boundary"] = {"fixed": ["2"]}
    assert run_scene(load_scene(scene), folder / "numbers", COMM, quiet=True)["contacts"] == by_msh["contacts"]
    with pytest.raises(SceneError, match=r"contact.surface = 'face' is not a physical group .* 1, 2 \(an XDMF"):
        run_scene(load_scene(scene_dict(xdmf)), folder / "bad", COMM, quiet=True)
    bad = scene_dict(xdmf)
    bad["geometry"]["groups"] = {"face": 7}
    with pytest.raises(SceneError, match=r"geometry.groups.face = 7 is not a facet marker .* 1, 2"):
        run_scene(load_scene(bad), folder / "bad7", COMM, quiet=True)


def test_scene_file_from_toml_with_relative_path(punch_file, tmp_path_factory):
    """A relative geometry.path is found from the scene file's folder."""
    folder = punch_file.parent
    if COMM.rank == 0:
        (folder / "punch.toml").write_text(
            'name = "punch"\n[geometry]\nkind = "file"\npath = "punch.msh"\n[boundary]\nfixed = ["top"]\n'
            '[contact]\nsurface = "face"\nmu = 0.0\n[loading]\nnormal_force = 10.0\nnormal_increments = 1\n')
    COMM.barrier()
    scene = load_scene(folder / "punch.toml")
    assert Path(scene.geometry.path) == punch_file.resolve()


def test_unknown_names_list_the_file_groups(punch_file, tmp_path_factory):
    folder = Path(COMM.bcast(str(tmp_path_factory.mktemp("bad")) if COMM.rank == 0 else None, root=0))
    with pytest.raises(SceneError, match=r"contact.surface = 'bottom' is not a physical group .* face, top"):
        run_scene(load_scene(scene_dict(punch_file, surface="bottom")), folder, COMM, quiet=True)
    bad = scene_dict(punch_file)
    bad["boundary"] = {"fixed": ["top", "lid"]}
    with pytest.raises(SceneError, match=r"boundary.fixed = 'lid' is not a physical group"):
        run_scene(load_scene(bad), folder, COMM, quiet=True)


def test_boundary_section_needs_a_mesh_file():
    with pytest.raises(SceneError, match="boundary.fixed"):
        load_scene("hertz", ["boundary.fixed=['top']"])
    with pytest.raises(SceneError, match="geometry.path"):
        load_scene({"geometry": {"kind": "file"}, "loading": {"normal_force": 1.0}})
    with pytest.raises(SceneError, match="geometry.groups"):  # names come from a .msh file itself
        load_scene({"geometry": {"kind": "file", "path": "a.msh", "groups": {"face": 1}},
                    "loading": {"normal_force": 1.0}})
