"""Mesh builders: geometry, refinement, tags, node sets, input checks and MPI distribution.

Areas and lengths are computed with numpy from the cell and facet vertices (no form compilation), summed
over owned entities only so that the same code gives global values under MPI (tests/support/mesh_measures.py).
"""

import json
import math
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from mpi4py import MPI
from support import mesh_measures as measure

from dolfinx_fretting import _dolfinx as dfx
from dolfinx_fretting import meshes

R = 6.0
COMM = MPI.COMM_WORLD


@pytest.fixture(scope="module", params=[True, False], ids=["quad", "tri"])
def cylinder(request):
    return meshes.half_cylinder(COMM, R, contact_mesh_size=0.02, quadrilateral=request.param)


@pytest.fixture(scope="module")
def cylinder_fine():
    return meshes.half_cylinder(COMM, R, contact_mesh_size=0.01, contact_half_width=0.4, coarse_mesh_size=0.6)


def test_cell_type(cylinder):
    from dolfinx.mesh import CellType

    quad = cylinder.mesh.topology.cell_type == CellType.quadrilateral
    tri = cylinder.mesh.topology.cell_type == CellType.triangle
    assert quad or tri
    assert dfx.geometry_dofmap(cylinder.mesh).shape[1] == (4 if quad else 3)  # first order


def test_area_is_the_inscribed_polygon(cylinder):
    # Every boundary node lies on the arc, so the mesh is the half-disk minus one circular segment per
    # arc facet: a chord of angle phi cuts R^2 (phi - sin phi) / 2 <= R^2 phi^3 / 12, and summed over
    # chords (sum phi = pi) the deficit lies in (0, pi R^2 phi_max^2 / 12]. The largest chord is set
    # by the coarse size (here R/10 = 0.6 mm; gmsh keeps edges within ~1.5x of the target size).
    exact = math.pi * R**2 / 2
    deficit = exact - measure.area(cylinder.mesh)
    chord = measure.max_chord(cylinder, "surface")
    assert chord <= 1.5 * 0.6
    phi = 2 * math.asin(chord / (2 * R))
    assert 0 < deficit <= math.pi * R**2 * phi**2 / 12 * (1 + 1e-9)
    assert deficit / exact < 3e-3  # the same bound with the coarse size: pi (1.5 H)^2 / 12 / (pi R^2 / 2)


def test_tags_cover_the_boundary_once(cylinder):
    from dolfinx.mesh import exterior_facet_indices

    msh = cylinder.mesh
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, fdim + 1)
    indices = cylinder.facet_tags.indices
    assert np.unique(indices).size == indices.size  # one tag per facet
    values = set().union(*COMM.allgather(set(np.unique(cylinder.facet_tags.values).tolist())))
    assert values == set(cylinder.tags.values())
    # Owned facets only: under MPI a rank also sees ghost facets on the partition boundary.
    n_owned = msh.topology.index_map(fdim).size_local
    tagged = np.sort(np.concatenate([cylinder.facets(n) for n in cylinder.tags]))
    exterior = np.sort(exterior_facet_indices(msh.topology))
    assert np.array_equal(tagged[tagged < n_owned], exterior[exterior < n_owned])
    # Lengths: the flat top is exact; the arc is a polygon inscribed in it, shorter by at most
    # pi R phi_max^2 / 24 (a chord of angle phi is 2 R sin(phi/2) >= R phi (1 - phi^2 / 24)).
    assert measure.length(cylinder, "top") == pytest.approx(2 * R, rel=1e-12)
    phi = 2 * math.asin(measure.max_chord(cylinder, "surface") / (2 * R))
    arc = measure.length(cylinder, "surface")
    assert math.pi * R * (1 - phi**2 / 24) <= arc < math.pi * R


def test_lowest_point_is_a_node(cylinder):
    x = cylinder.mesh.geometry.x
    assert COMM.allreduce(float(np.linalg.norm(x[:, :2], axis=1).min()), op=MPI.MIN) < 1e-12
    # ... and nothing lies below y = 0.
    assert COMM.allreduce(float(x[:, 1].min()), op=MPI.MIN) > -1e-12


@pytest.mark.parametrize("h", [0.005, 0.01, 0.02])
def test_contact_zone_spacing_is_uniform_and_symmetric(h):
    body = meshes.half_cylinder(MPI.COMM_SELF, R, contact_mesh_size=h, contact_half_width=0.4)
    x = body.mesh.geometry.x[meshes.boundary_nodes(body, "contact_zone")]
    x = x[np.argsort(x[:, 0])]
    assert x[0, 0] == pytest.approx(-0.4, abs=1e-12) and x[-1, 0] == pytest.approx(0.4, abs=1e-12)
    # Nodes on the arc, spaced h within the rounding of R asin(a/R) / h to whole segments.
    assert np.allclose(np.linalg.norm(x[:, :2] - [0.0, R], axis=1), R, atol=1e-12)
    spacing = np.linalg.norm(np.diff(x[:, :2], axis=0), axis=1)
    assert np.all(np.abs(spacing / h - 1) <= 0.2), (spacing.min(), spacing.max())
    # Equal arcs give equal chords, mirrored about x = 0 (gmsh places curve nodes to ~1e-8 mm).
    assert spacing.max() - spacing.min() < 1e-6 * h
    assert np.allclose(x[:, 0] + x[::-1, 0], 0.0, atol=1e-6 * h)
    assert body.contact_mesh_size == h and body.contact_half_width == 0.4


def test_refinement_counts_and_grading(cylinder_fine):
    # The refined sector (|x| <= 0.4, 0.1 mm deep, h = 10 µm) alone needs ~2 * 40 * 10 cells; the
    # graded rest must stay small compared with it, and the far field must be coarse.
    n_cells = cylinder_fine.mesh.topology.index_map(2).size_global
    assert 800 <= n_cells <= 4000
    p = measure.cell_polygons(cylinder_fine.mesh)
    centre = p.mean(axis=1)
    size = np.sqrt(np.abs(measure.signed_areas(p)))
    near = np.linalg.norm(centre, axis=1) < 0.05
    far = centre[:, 1] > 4.0
    assert COMM.allreduce(float(size[near].max()) if near.any() else 0.0, op=MPI.MAX) < 1.3 * 0.01
    assert COMM.allreduce(float(size[far].min()) if far.any() else np.inf, op=MPI.MIN) > 0.3


def test_contact_zone_facets(cylinder_fine):
    zone = cylinder_fine.facets("contact_zone")
    assert np.all(np.isin(zone, cylinder_fine.facets("surface")))
    seg = measure.facet_segments(cylinder_fine, "contact_zone", owned_only=False)
    assert np.all(np.abs(seg[:, :, 0]) <= 0.4 + 1e-12)
    theta = math.asin(0.4 / R)
    assert measure.length(cylinder_fine, "contact_zone") == pytest.approx(2 * R * theta, rel=1e-6)
    assert "contact_zone" in cylinder_fine.names and "contact_zone" not in cylinder_fine.tags
    with pytest.raises(KeyError, match="allowed: top, surface, contact_zone"):
        cylinder_fine.facets("bottom")


def test_center_moves_the_body():
    body = meshes.half_cylinder(MPI.COMM_SELF, 2.0, contact_mesh_size=0.05, center=(1.0, 5.0))
    x = body.mesh.geometry.x
    assert np.linalg.norm(x[:, :2] - [1.0, 3.0], axis=1).min() < 1e-12
    assert x[:, 1].max() == pytest.approx(5.0, abs=1e-12)
    assert np.allclose(np.linalg.norm(measure.facet_segments(body, "surface").reshape(-1, 2) - [1.0, 5.0],
                                      axis=1), 2.0, atol=1e-12)


@pytest.mark.parametrize("args", [(1.0, 0.3, 0.5), (6.0, 0.05, 2.0), (6.0, 0.01, 2.0, 0.9)])
def test_quadrilaterals_for_awkward_sizes(args):
    # Size combinations where Blossom recombination leaves triangles in gmsh 4.8: the builder must
    # still return quadrilaterals with the node spacing rules.
    from dolfinx.mesh import CellType

    radius, h, a = args[:3]
    body = meshes.half_cylinder(MPI.COMM_SELF, *args)
    assert body.mesh.topology.cell_type == CellType.quadrilateral
    x = body.mesh.geometry.x[meshes.boundary_nodes(body, "contact_zone")]
    x = x[np.argsort(x[:, 0])]
    spacing = np.linalg.norm(np.diff(x[:, :2], axis=0), axis=1)
    assert np.all(np.abs(spacing / h - 1) <= 0.2), (spacing.min(), spacing.max())
    assert np.linalg.norm(x[:, :2] - [0.0, 0.0], axis=1).min() < 1e-12
    assert np.allclose(np.linalg.norm(measure.facet_segments(body, "surface").reshape(-1, 2) - [0.0, radius],
                                      axis=1), radius, atol=1e-12)


def test_node_sets_agree(cylinder_fine):
    V = dfx.vector_space(cylinder_fine.mesh, 1)
    for name in ("top", "surface", "contact_zone"):
        geo = cylinder_fine.mesh.geometry.x[meshes.boundary_nodes(cylinder_fine, name)]
        blocks = meshes.facet_dofs(V, cylinder_fine, name)
        dof = V.tabulate_dof_coordinates()[blocks]
        assert blocks.size == geo.shape[0]
        key = lambda p: np.lexsort((p[:, 1], p[:, 0]))  # noqa: E731
        assert np.allclose(geo[key(geo)], dof[key(dof)], atol=1e-14)
        owned = meshes.facet_dofs(V, cylinder_fine, name, owned_only=True)
        assert np.all(owned < V.dofmap.index_map.size_local) and np.all(np.isin(owned, blocks))
    # The contact zone holds 2 * 40 + 1 nodes (h = 10 µm over |x| <= 0.4 mm).
    n = COMM.allreduce(meshes.facet_dofs(V, cylinder_fine, "contact_zone", owned_only=True).size, op=MPI.SUM)
    assert n == 81


@pytest.mark.parametrize("quad", [True, False])
def test_rectangle(quad):
    from dolfinx.mesh import CellType, exterior_facet_indices

    body = meshes.rectangle(COMM, 3.0, 2.0, 6, 5, quadrilateral=quad, origin=(1.0, -2.0))
    msh = body.mesh
    assert msh.topology.cell_type == (CellType.quadrilateral if quad else CellType.triangle)
    assert msh.topology.index_map(2).size_global == 30 * (1 if quad else 2)
    assert measure.area(msh) == pytest.approx(6.0, rel=1e-12)
    for name, length, count, (axis, value) in [("bottom", 3.0, 6, (1, -2.0)), ("top", 3.0, 6, (1, 0.0)),
                                               ("left", 2.0, 5, (0, 1.0)), ("right", 2.0, 5, (0, 4.0))]:
        assert measure.length(body, name) == pytest.approx(length, rel=1e-12), name
        seg = measure.facet_segments(body, name)
        assert COMM.allreduce(len(seg), op=MPI.SUM) == count, name
        assert np.allclose(seg[:, :, axis], value), name
    msh.topology.create_connectivity(1, 2)
    n_owned = msh.topology.index_map(1).size_local
    tagged = np.sort(np.concatenate([body.facets(n) for n in body.tags]))
    exterior = np.sort(exterior_facet_indices(msh.topology))
    assert np.array_equal(tagged[tagged < n_owned], exterior[exterior < n_owned])
    assert body.contact_mesh_size == pytest.approx(0.5) and body.zones == {}


@pytest.mark.parametrize("kwargs, name", [
    (dict(radius=0.0), "radius"),
    (dict(radius=-1.0), "radius"),
    (dict(radius=float("nan")), "radius"),
    (dict(radius=6.0, contact_mesh_size=0.0), "contact_mesh_size"),
    (dict(radius=6.0, contact_mesh_size=6.0), "contact_mesh_size"),
    (dict(radius=6.0, contact_half_width=0.005), "contact_half_width"),
    (dict(radius=6.0, contact_half_width=6.0), "contact_half_width"),
    (dict(radius=6.0, coarse_mesh_size=0.001), "coarse_mesh_size"),
    (dict(radius=6.0, coarse_mesh_size=7.0), "coarse_mesh_size"),
    (dict(radius=6.0, center=(0.0,)), "center"),
    (dict(radius=6.0, refined_depth=4.0), "refined_depth"),
    (dict(radius=6.0, growth=0.0), "growth"),
])
def test_half_cylinder_rejects_bad_input(kwargs, name):
    with pytest.raises(ValueError, match=rf"^{name} = .* out of range: "):
        meshes.half_cylinder(COMM, **kwargs)


@pytest.mark.parametrize("args, name", [
    ((0.0, 1.0, 2, 2), "width"), ((1.0, -1.0, 2, 2), "height"), ((1.0, 1.0, 0, 2), "nx"),
    ((1.0, 1.0, 2, 2.5), "ny"),
])
def test_rectangle_rejects_bad_input(args, name):
    with pytest.raises(ValueError, match=rf"^{name} = .* out of range: "):
        meshes.rectangle(COMM, *args)


_MPI_SCRIPT = textwrap.dedent("""
    import json, sys
    sys.path.insert(0, {tests!r})
    from mpi4py import MPI
    from dolfinx_fretting import _dolfinx as dfx, meshes
    from support import mesh_measures as measure

    comm = MPI.COMM_WORLD
    body = meshes.half_cylinder(comm, 6.0, contact_mesh_size=0.02)
    V = dfx.vector_space(body.mesh, 1)
    x = body.mesh.geometry.x
    out = dict(
        size=comm.size,
        cells=body.mesh.topology.index_map(2).size_global,
        nodes=body.mesh.geometry.index_map().size_global,
        local_cells=comm.allgather(body.mesh.topology.index_map(2).size_local),
        area=measure.area(body.mesh),
        top=measure.length(body, "top"), surface=measure.length(body, "surface"),
        zone_nodes=comm.allreduce(meshes.facet_dofs(V, body, "contact_zone", owned_only=True).size),
        zone_geometry_nodes=comm.allreduce(meshes.boundary_nodes(body, "contact_zone", owned_only=True).size),
        lowest=comm.allreduce(float(abs(x[:, :2]).sum(axis=1).min()), op=MPI.MIN),
    )
    if comm.rank == 0:
        print("RESULT " + json.dumps(out))
""")


@pytest.mark.mpi
def test_half_cylinder_under_mpi(tmp_path, mpirun_env):
    script = tmp_path / "mesh_mpi.py"
    script.write_text(_MPI_SCRIPT.format(tests=os.path.dirname(os.path.abspath(__file__))))
    proc = subprocess.run([*dfx.mpiexec(2), sys.executable, "-m", "mpi4py", str(script)],
                          capture_output=True, text=True, env=mpirun_env, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT ")]
    assert len(line) == 1, proc.stdout + proc.stderr
    par = json.loads(line[0][len("RESULT "):])

    body = meshes.half_cylinder(MPI.COMM_SELF, 6.0, contact_mesh_size=0.02)
    assert par["size"] == 2
    assert par["cells"] == body.mesh.topology.index_map(2).size_global
    assert par["nodes"] == body.mesh.geometry.index_map().size_global
    assert all(n > 0 for n in par["local_cells"])  # really distributed
    assert par["area"] == pytest.approx(measure.area(body.mesh), rel=1e-12)
    assert par["top"] == pytest.approx(2 * 6.0, rel=1e-12)
    assert par["surface"] == pytest.approx(measure.length(body, "surface"), rel=1e-12)
    n_zone = meshes.boundary_nodes(body, "contact_zone").size
    assert par["zone_nodes"] == par["zone_geometry_nodes"] == n_zone  # owned nodes counted once
    assert par["lowest"] < 1e-12
