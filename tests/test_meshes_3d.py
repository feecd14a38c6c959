"""The sphere-on-flat hexahedral mesh: grading, volumes, tags, symmetry and MPI distribution.

Volumes and areas are assembled (one-form integrals) and compared with closed forms: the flat is a box, the
cap's volume is the box minus the integral of the sphere's height f = R - sqrt(R^2 - x^2 - y^2) (SciPy
quadrature, independent of the mesh).
"""

import math

import numpy as np
import pytest
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402
from scipy.integrate import dblquad  # noqa: E402

from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting import meshes_3d as m3  # noqa: E402

COMM = MPI.COMM_WORLD
R, A = 10.0, 0.15


def integral(body, measure) -> float:
    one = fem.Constant(body.mesh, 1.0)
    return COMM.allreduce(fem.assemble_scalar(fem.form(one * measure)), op=MPI.SUM)


@pytest.fixture(scope="module", params=[True, False], ids=["half", "full"])
def body(request):
    return m3.sphere_on_flat(COMM, R, A, A / 3, extent=5.0, growth=1.5, half=request.param)


def test_graded_coordinates():
    x = m3.graded_coordinates(0.1, 0.25, 3.0, 1.3)
    steps = np.diff(x)
    assert x[0] == 0.0 and x[-1] == pytest.approx(3.0, rel=1e-14)
    assert np.allclose(steps[:3], 0.1, rtol=1e-14)           # 0.25 rounded up to three steps of h
    ratios = steps[3:] / steps[2:-1]
    assert np.allclose(ratios, ratios[0], rtol=1e-10)        # one geometric ratio
    assert abs(ratios[0] - 1.3) < 0.15                       # close to the one asked for
    assert np.allclose(m3.graded_coordinates(0.5, 1.0, 3.0, 1.0), np.arange(7) * 0.5)


def test_volumes_and_tag_areas(body):
    half = "symmetry" in body.tags
    L = 5.0 * A
    width = L if half else 2 * L
    dx = ufl.Measure("dx", domain=body.mesh, subdomain_data=body.cell_tags)
    ds = ufl.Measure("ds", domain=body.mesh, subdomain_data=body.facet_tags)
    flat = 2 * L * width * L
    # The flat is a box of trilinear cells: exact to rounding.
    assert integral(body, dx(body.regions["flat"])) == pytest.approx(flat, rel=1e-12)
    f_int = dblquad(lambda y, x: R - math.sqrt(R * R - x * x - y * y), -L, L, 0.0 if half else -L, L,
                    epsabs=1e-14, epsrel=1e-13)[0]
    # The cap: its lower face is bilinear between nodes on the sphere; the curvature error is ~h^2/(8 R) x area.
    h_max = np.diff(m3.graded_coordinates(A / 3, 1.5 * A, L, 1.5)).max()
    assert integral(body, dx(body.regions["sphere"])) == pytest.approx(2 * L * width * L - f_int,
                                                                        abs=h_max**2 / (8 * R) * 2 * L * width)
    for name in ("top", "flat_top", "flat_bottom"):
        assert integral(body, ds(body.tags[name])) == pytest.approx(2 * L * width, rel=1e-12), name
    if half:
        assert integral(body, ds(body.tags["flat_symmetry"])) == pytest.approx(2 * L * L, rel=1e-12)
    # Every exterior facet carries one tag: the tags' areas add up to the whole boundary.
    total = sum(integral(body, ds(v)) for v in body.tags.values())
    assert total == pytest.approx(integral(body, ufl.ds), rel=1e-12)


def test_contact_faces_lie_on_the_sphere_and_the_flat(body):
    msh = body.mesh
    for name, height in (("surface", lambda x, y: R - np.sqrt(R * R - x * x - y * y)), ("flat_top", None)):
        facets = body.facets(name)
        x = msh.geometry.x[dfx.entities_to_geometry(msh, 2, facets)].reshape(-1, 3)
        target = np.zeros(len(x)) if height is None else height(x[:, 0], x[:, 1])
        assert np.abs(x[:, 2] - target).max(initial=0.0) <= 1e-14
    # The uniform zone: cubes of edge h under the contact (node spacing h along x and y on the face).
    facets = body.zones["contact_zone"]
    x = msh.geometry.x[dfx.entities_to_geometry(msh, 2, facets)].reshape(-1, 4, 3)
    edges = np.linalg.norm(np.diff(x[:, [0, 1, 3, 2, 0], :2], axis=1), axis=2)
    assert np.allclose(edges, A / 3, rtol=1e-12)


def test_half_model_is_the_full_model_cut_at_y0():
    half = m3.sphere_on_flat_grid(R, A, A / 3, extent=5.0, growth=1.5, half=True)
    full = m3.sphere_on_flat_grid(R, A, A / 3, extent=5.0, growth=1.5, half=False)
    assert np.array_equal(full["y"], np.concatenate([-half["y"][:0:-1], half["y"]]))
    keep = full["points"][:, 1] >= 0
    assert np.array_equal(np.unique(full["points"][keep], axis=0), np.unique(half["points"], axis=0))


def test_rigid_plane_mesh_has_the_sphere_only():
    body = m3.sphere_on_flat(COMM, R, A, A / 2, extent=4.0, growth=1.6, flat=False)
    assert set(body.tags) == {"top", "surface", "symmetry", "sides"} and set(body.regions) == {"sphere"}
    assert body.contact_mesh_size == A / 2 and body.contact_half_width == pytest.approx(1.5 * A)


@pytest.mark.parametrize("kwargs, name", [
    ({"contact_radius": -1.0}, "contact_radius"), ({"contact_radius": 1.0}, "contact_radius"),
    ({"contact_mesh_size": 0.2}, "contact_mesh_size"), ({"growth": 3.0}, "growth"), ({"zone": 0.5}, "zone"),
    ({"extent": 1.2}, "extent"), ({"flat_mesh_size": 0.0}, "flat_mesh_size")])
def test_bad_input_is_refused(kwargs, name):
    args = dict(radius=R, contact_radius=A)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        m3.sphere_on_flat(COMM, **args)


# The depth-graded mesh (opt-in: depth_growth, coarsening, field_cell) ------------------------------------------
# a/h = 12 with field_cell 0.25: lateral 3:1 transitions both inside the field depth (3h <= a/4) and below it.
GRADED = dict(depth_growth=1.5, coarsening=2, field_cell=0.25)
_REFERENCE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]])
_FACES = np.array([[0, 1, 2, 3], [4, 5, 6, 7], [0, 1, 4, 5], [2, 3, 6, 7], [0, 2, 4, 6], [1, 3, 5, 7]])


def corner_jacobians(points, cells):
    """The trilinear map's Jacobian determinant at each of the 8 corners of each cell (the triple product of
    the three edges leaving the corner, signed for the reference corner's orientation)."""
    dets = []
    for v, corner in enumerate(_REFERENCE):
        edges = []
        for axis in range(3):
            other = corner.copy()
            other[axis] = 1 - other[axis]
            edges.append(points[cells[:, np.flatnonzero((_REFERENCE == other).all(1))[0]]] - points[cells[:, v]])
        sign = np.prod(1 - 2 * corner)
        dets.append(sign * np.einsum("ij,ij->i", edges[0], np.cross(edges[1], edges[2])))
    return np.array(dets)


def hexahedron_volumes(points, cells):
    """Exact volumes of trilinear hexahedra: 2 x 2 x 2 Gauss points (det J is of degree <= 2 in each
    reference coordinate, which the rule integrates exactly)."""
    g = 0.5 + np.array([-1, 1]) / (2 * np.sqrt(3))
    X = points[cells]  # (M, 8, 3)
    total = np.zeros(len(cells))
    for s in g:
        for t in g:
            for u in g:
                # derivatives of the tensor-product shape functions at (s, t, u)
                dN = np.array([[-(1 - t) * (1 - u), -(1 - s) * (1 - u), -(1 - s) * (1 - t)],
                               [(1 - t) * (1 - u), -s * (1 - u), -s * (1 - t)],
                               [-t * (1 - u), (1 - s) * (1 - u), -(1 - s) * t],
                               [t * (1 - u), s * (1 - u), -s * t],
                               [-(1 - t) * u, -(1 - s) * u, (1 - s) * (1 - t)],
                               [(1 - t) * u, -s * u, s * (1 - t)],
                               [-t * u, (1 - s) * u, (1 - s) * t],
                               [t * u, s * u, s * t]])
                J = np.einsum("mvi,vj->mij", X, dN)
                total += np.linalg.det(J) / 8
    return total


def meshed_volumes(grid):
    """The bodies' volumes in closed form: the flat is the box 2L x W x H; the cap is the box minus the
    bilinear interpolant of the sphere's height f on its contact face's grid (faces between nodes are bilinear;
    the sides and top are planes), i.e. the trapezoid rule of f on that grid."""
    R, H = 10.0, grid["height"]
    x, y = grid["x"], grid["y"]
    X, Y = np.meshgrid(x, y, indexing="ij")
    f = R - np.sqrt(R * R - X * X - Y * Y)
    mean = 0.25 * (f[:-1, :-1] + f[1:, :-1] + f[:-1, 1:] + f[1:, 1:])
    areas = np.outer(np.diff(x), np.diff(y))
    return float(np.sum(areas * (H - mean))), float((x[-1] - x[0]) * (y[-1] - y[0]) * H)


@pytest.fixture(scope="module", params=[True, False], ids=["half", "full"])
def graded_grid(request):
    return m3.sphere_on_flat_grid(R, A, A / 12, half=request.param, **GRADED)


def test_graded_grid_is_conforming_positive_and_exact_in_volume(graded_grid):
    grid = graded_grid
    points, cells, regions = grid["points"], grid["cells"], grid["regions"]
    assert grid["kinds"].count("x") == grid["kinds"].count("y") == 2    # both coarsenings happen
    # Every cell positively oriented at every corner (DOLFINx's order); measured min det / h^3 ~ 0.5.
    assert corner_jacobians(points, cells).min() > 0
    # Conforming: every face of a cell is shared with exactly one other cell or lies on the bodies' boundary
    # (a hanging node would leave an interior face used once).
    faces = np.sort(cells[:, _FACES].reshape(-1, 4), axis=1)
    unique, count = np.unique(faces, axis=0, return_counts=True)
    assert count.max() == 2
    L, H, half = grid["L"], grid["height"], grid["y"][0] == 0.0
    corners = points[unique[count == 1]]  # (F, 4, 3)
    X, Y, Z = corners[..., 0], corners[..., 1], corners[..., 2]
    tol = 1e-12 * L
    on_face = (np.all(np.abs(np.abs(X) - L) <= tol, axis=1) | np.all(np.abs(Y - L) <= tol, axis=1)
               | np.all(np.abs(Y if half else np.abs(Y) - L) <= tol, axis=1)
               | np.all(np.abs(np.abs(Z) - H) <= tol, axis=1) | np.all(np.abs(Z) <= tol, axis=1)
               | np.all(np.abs(Z - (R - np.sqrt(R * R - X * X - Y * Y))) <= tol, axis=1))
    assert on_face.all()
    # Volumes: exact integrals of the trilinear cells against the closed form, to rounding.
    cap, flat = meshed_volumes(grid)
    volumes = hexahedron_volumes(points, cells)
    assert volumes[regions == m3.SPHERE_ON_FLAT_REGIONS["sphere"]].sum() == pytest.approx(cap, rel=1e-12)
    assert volumes[regions == m3.SPHERE_ON_FLAT_REGIONS["flat"]].sum() == pytest.approx(flat, rel=1e-12)
    # The contact faces: a full grid of step h over the uniform zone on both bodies, as today's mesh.
    h, b = A / 12, grid["zone_half_width"]
    in_sphere = np.zeros(len(points), dtype=bool)  # the two bodies share the origin's position, not the node
    in_sphere[cells[regions == m3.SPHERE_ON_FLAT_REGIONS["sphere"]].ravel()] = True
    for face in (in_sphere & (np.abs(points[:, 2] - (R - np.sqrt(R * R - points[:, 0]**2 - points[:, 1]**2))) <= tol),
                 ~in_sphere & (np.abs(points[:, 2]) <= tol)):
        zone = face & (np.abs(points[:, 0]) <= b + tol) & (np.abs(points[:, 1]) <= b + tol)
        xs, ys = np.unique(np.round(points[zone, 0] / h, 9)), np.unique(np.round(points[zone, 1] / h, 9))
        assert np.array_equal(xs, np.arange(-round(b / h), round(b / h) + 1))
        assert np.array_equal(ys, np.arange(0 if half else -round(b / h), round(b / h) + 1))
        assert np.count_nonzero(zone) == xs.size * ys.size
    # The size estimate's count, without building, is the grid's.
    assert m3.grid_node_count(A, A / 12, half=half, **GRADED) == len(points)
    # The point: several times fewer nodes than today's mesh with the same contact face.
    today = m3.grid_node_count(A, A / 12, half=half)
    assert len(points) < today / 3


def test_graded_depth_and_kinds():
    depth = m3.graded_depth(1.0, 3.0, 10.0, 100.0, 1.5)
    steps = np.diff(depth)
    assert depth[0] == 0 and depth[-1] == pytest.approx(100.0, rel=1e-14)
    assert np.allclose(steps[:4], [1.0, 1.5, 2.25, 3.0])          # grows from h, capped at 3
    capped = depth[1:] <= 10.0 + 3.0
    assert np.all(steps[capped] <= 3.0 + 1e-12) and np.all(np.diff(steps) > -1e-12)
    kinds = m3.layer_kinds(depth, 1.0, 2, cap=3.0, capped_depth=10.0)
    # the first transition where a layer reaches COARSEN_AT = 2 steps (3h <= the cap), the second (9h > cap)
    # only below the capped depth
    first = kinds.index("x")
    assert kinds[first + 1] == "y" and steps[first] >= m3.COARSEN_AT and steps[first - 1] < m3.COARSEN_AT
    second = kinds.index("x", first + 2)
    assert depth[second] >= 10.0 and steps[second] >= 3 * m3.COARSEN_AT
    assert m3.lateral_levels(13, 2, 11, 2)[1].tolist() == [0, 1, 2, 5, 8, 11, 12]
    assert m3.lateral_levels(13, 2, 11, 2)[2].tolist() == [0, 1, 2, 11, 12]


@pytest.fixture(scope="module")
def graded_body():
    return m3.sphere_on_flat(COMM, R, A, A / 6, extent=5.0, **GRADED)


def test_graded_mesh_volumes_tags_and_contact_zone(graded_body):
    body = graded_body
    grid = m3.sphere_on_flat_grid(R, A, A / 6, extent=5.0, **GRADED)
    dx = ufl.Measure("dx", domain=body.mesh, subdomain_data=body.cell_tags)
    ds = ufl.Measure("ds", domain=body.mesh, subdomain_data=body.facet_tags)
    cap, flat = meshed_volumes(grid)
    # degree 4: det J of a trilinear cell is of degree <= 2 in each coordinate (the default may be lower)
    metadata = {"quadrature_degree": 4}
    assert integral(body, dx(body.regions["sphere"], metadata=metadata)) == pytest.approx(cap, rel=1e-12)
    assert integral(body, dx(body.regions["flat"], metadata=metadata)) == pytest.approx(flat, rel=1e-12)
    total = sum(integral(body, ds(v)) for v in body.tags.values())
    assert total == pytest.approx(integral(body, ufl.ds), rel=1e-12)
    L = 5.0 * A
    for name in ("top", "flat_top", "flat_bottom"):
        assert integral(body, ds(body.tags[name])) == pytest.approx(2 * L * L, rel=1e-12), name
    msh = body.mesh
    x = msh.geometry.x[dfx.entities_to_geometry(msh, 2, body.zones["contact_zone"])].reshape(-1, 4, 3)
    edges = np.linalg.norm(np.diff(x[:, [0, 1, 3, 2, 0], :2], axis=1), axis=2)
    assert np.allclose(edges, A / 6, rtol=1e-12)
    assert body.contact_half_width == pytest.approx(grid["zone_half_width"])
    assert COMM.allreduce(msh.geometry.index_map().size_local, op=MPI.SUM) == len(grid["points"])


@pytest.mark.parametrize("kwargs, name", [
    ({"depth_growth": 1.0}, "depth_growth"), ({"depth_growth": 2.5}, "depth_growth"),
    ({"coarsening": 1}, "coarsening"), ({"depth_growth": 1.5, "coarsening": 4}, "coarsening"),
    ({"depth_growth": 1.5, "coarsening": 1.0}, "coarsening"), ({"depth_growth": 1.5, "field_cell": 0.0}, "field_cell"),
    ({"depth_growth": 1.5, "field_cell": 1.5}, "field_cell")])
def test_bad_grading_is_refused(kwargs, name):
    with pytest.raises(ValueError, match=name):
        m3.sphere_on_flat(COMM, R, A, **kwargs)
