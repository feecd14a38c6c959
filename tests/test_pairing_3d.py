"""Node-to-face pairing in 3D and a 3D contact's measures, against closed forms (pure NumPy, no mesh).

References:
- A bilinear quadrilateral x(xi, eta) = (xi, eta, c xi eta) (a hyperbolic paraboloid, the simplest curved
  quadrilateral): its unit normal at (xi, eta) is (-c eta, -c xi, 1) / sqrt(1 + c^2 (xi^2 + eta^2)).
- A facet's size (the scale of finite sliding's re-pairing) is its mean edge length: a 3-4-5 triangle's is 4,
  a 1 x 2 rectangle's 1.5.
- A half model cut by its symmetry plane t2 = 0 (the nodes on the plane with half their tributary area) has the
  whole contact's areas, radii, extents and worn volume once divided by its model fraction 0.5.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from dolfinx_fretting.contact import MasterSurface, tangent_frame
from dolfinx_fretting.output import FrettingWriter, contact_measures

C = 0.4  # the warp of the curved quadrilateral


def _warped_quadrilateral():
    """(0,0,0) (1,0,0) (1,1,C) (0,1,0) in cyclic order, body below (z < 0)."""
    x = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, C], [0, 1, 0]]], dtype=float)
    return MasterSurface(np.array([[0, 1, 2, 3]]), x, np.array([4]), np.array([[0.5, 0.5, -1.0]]),
                         tangent_frame([0.0, 0.0, 1.0]))


def _exact(xi, eta):
    point = np.array([xi, eta, C * xi * eta])
    normal = np.array([-C * eta, -C * xi, 1.0])
    return point, normal / np.linalg.norm(normal)


@pytest.mark.parametrize("xi,eta", [(0.3, 0.6), (0.8, 0.15), (0.55, 0.9)])
def test_a_curved_quadrilateral_master_s_normal(xi, eta):
    """A point 0.02 above (xi, eta) along the normal pairs with (xi, eta) (1e-9: the closest-point iteration's
    tolerance) and gets the exact normal there (1e-9), both from the search and from the reference geometry at the
    pairing's weights (what the contact set's frames and gaps are made of). Its frame is orthonormal with n first
    and t1 in the plane of n and the obstacle's t1 (the facet is curved: t1 is not the obstacle's)."""
    surface = _warped_quadrilateral()
    point, normal = _exact(xi, eta)
    pairs = surface.pair((point + 0.02 * normal)[None])
    assert pairs["point"][0] == pytest.approx(point, abs=1e-9)
    assert pairs["normal"][0] == pytest.approx(normal, abs=1e-9)
    assert pairs["distance"][0] == pytest.approx(0.02, rel=1e-9)
    weights = pairs["weights"]
    assert weights[0] == pytest.approx([(1 - xi) * (1 - eta), xi * (1 - eta), xi * eta, (1 - xi) * eta], abs=1e-9)
    ref_point, ref_normal = surface.reference_geometry(np.array([0]), weights)
    assert ref_point[0] == pytest.approx(point, abs=1e-9) and ref_normal[0] == pytest.approx(normal, abs=1e-9)
    frame = surface.frames(ref_normal)[0]
    assert frame @ frame.T == pytest.approx(np.eye(3), abs=1e-14)
    assert frame[0] == pytest.approx(normal, abs=1e-9)
    t1 = np.array([1.0, 0.0, 0.0]) - normal[0] * normal                    # the obstacle's t1 = x projected
    assert frame[1] == pytest.approx(t1 / np.linalg.norm(t1), abs=1e-9)


def test_facet_sizes_are_the_mean_edge_of_triangles_and_quadrilaterals():
    """The re-pairing scale: a 3-4-5 right triangle's mean edge is 4, a 1 x 2 rectangle's 1.5 (exact), and in 2D a
    segment's length."""
    tri = [[0, 0, 0], [3, 0, 0], [0, 4, 0], [0, 4, 0]]                  # a triangle's fourth repeats its third
    rect = [[0, 0, 0], [1, 0, 0], [1, 2, 0], [0, 2, 0]]
    surface = MasterSurface(np.array([[0, 1, 2, -1], [3, 4, 5, 6]]), np.array([tri, rect], dtype=float),
                            np.array([3, 4]), np.array([[1.0, 1.0, -1.0], [0.5, 1.0, -1.0]]),
                            tangent_frame([0.0, 0.0, 1.0]))
    assert surface.sizes == pytest.approx([4.0, 1.5], rel=1e-15)
    segments = MasterSurface(np.array([[0, 1]]), np.array([[[0.0, 0.0], [0.3, 0.4]]]), np.array([2]),
                             np.array([[0.15, -1.0]]), tangent_frame([0.0, 1.0]))
    assert segments.sizes == pytest.approx([0.5], rel=1e-15)


def _grid_contact(half: bool, h=0.1, n=8):
    """A circular contact on a grid of spacing h in the plane z = 0 (frames (n, t1, t2) = (z, x, y)): loaded within
    r <= 0.55, sticking within r <= 0.3 (not symmetric along x, so that extents along and across differ); the half
    model keeps y >= 0 with half the tributary area on y = 0."""
    g = (np.arange(-n, n + 1)) * h
    x, y = (v.ravel() for v in np.meshgrid(g, g))
    keep = y >= -1e-12 if half else np.ones(x.size, bool)
    x, y = x[keep], y[keep]
    tributary = np.full(x.size, h * h) * np.where(half & (np.abs(y) < 1e-12), 0.5, 1.0)
    r = np.hypot(x - 0.03, y)
    status = np.where(r <= 0.3, 1, np.where(r <= 0.55, 2, 0))
    wear = np.where(status > 0, 1e-4 * (1 - (r / 0.55) ** 2), 0.0)
    frames = np.broadcast_to(np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), (x.size, 3, 3))
    contact_set = SimpleNamespace(dim=3, coords=np.column_stack([x, y, np.zeros(x.size)]), frames=frames,
                                  tributary=tributary)
    problem = SimpleNamespace(contact=SimpleNamespace(contact_set=contact_set),
                              worn_measure=lambda state: float((wear * tributary).sum()))
    return problem, SimpleNamespace(status=status)


def test_a_half_model_s_measures_are_the_whole_contact_s():
    """contact_measures of the half model (model_fraction 0.5) equal those of the whole contact (rounding: 1e-12);
    the stick area is scaled like the loaded area (a stick radius of the half area would be 1/sqrt(2) of it)."""
    whole = contact_measures(*_grid_contact(half=False))
    half_problem, half_state = _grid_contact(half=True)
    half = contact_measures(half_problem, half_state, model_fraction=0.5)
    assert whole["stick_radius"] > 0 and whole["contact_extent_across"] > 0
    assert set(half) == set(whole)
    for key, value in whole.items():
        assert half[key] == pytest.approx(value, rel=1e-12), key
    # and the whole contact's own numbers, by hand: the loaded and sticking nodes' count times h^2
    problem, state = _grid_contact(half=False)
    loaded, sticking = (state.status > 0).sum(), (state.status == 1).sum()
    assert whole["contact_radius"] == pytest.approx(np.sqrt(loaded * 0.01 / np.pi), rel=1e-12)
    assert whole["stick_radius"] == pytest.approx(np.sqrt(sticking * 0.01 / np.pi), rel=1e-12)


def test_a_half_model_s_history_areas_are_the_whole_contact_s():
    """The history's sums of a half model (contact and stick areas, forces) are written as the whole contact's:
    the half grid's loaded and sticking tributary areas, divided by the model fraction 0.5, are the whole grid's
    (1e-12); its intensive columns (the largest pressure) are left as they are."""
    areas = {}
    for half in (True, False):
        problem, state = _grid_contact(half=half)
        tributary = problem.contact.contact_set.tributary
        areas[half] = {"contact_area": float(tributary[state.status > 0].sum()),
                       "stick_area": float(tributary[state.status == 1].sum()), "max_pressure": 900.0}
    writer = SimpleNamespace(description=SimpleNamespace(model_fraction=0.5))
    whole = FrettingWriter._whole(writer, areas[True])
    assert whole["stick_area"] > 0
    for key, value in areas[False].items():
        assert whole[key] == pytest.approx(value, rel=1e-12), key
