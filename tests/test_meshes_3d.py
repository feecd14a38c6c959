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
