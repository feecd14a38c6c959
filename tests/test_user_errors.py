"""What a user gets wrong at the seam, refused with a message that names the argument, the value and what is
allowed, before any expensive work; and the obstacle normal's length, which does not matter.

Small models the test owns: a unit square (4 x 4 cells, triangles) with facet tags 1 bottom, 2 right, 3 top (the
left side untagged). Every message is decided on sums over ranks, so these tests hold on any number of ranks.
"""

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import contact as contact_module  # noqa: E402
from dolfinx_fretting.compat import vector_space  # noqa: E402
from dolfinx_fretting.contact import tangent_frame  # noqa: E402

N = 4  # cells per side: the bottom has N + 1 vertices
SIDES = {1: lambda x: np.isclose(x[1], 0.0), 2: lambda x: np.isclose(x[0], 1.0), 3: lambda x: np.isclose(x[1], 1.0)}
PLANE = dfr.RigidPlane([0.0, -0.1], [0.0, 1.0])  # 0.1 below the bottom, normal into the square


def square(markers=SIDES):
    """(V, facet tags) of the unit square with the given sides tagged."""
    msh = mesh.create_unit_square(MPI.COMM_WORLD, N, N)
    found = {marker: mesh.locate_entities_boundary(msh, 1, where) for marker, where in markers.items()}
    facets = np.concatenate([f for f in found.values()] or [np.zeros(0, dtype=np.int32)]).astype(np.int32)
    values = np.concatenate([np.full(f.size, m, dtype=np.int32) for m, f in found.items()]
                            or [np.zeros(0, dtype=np.int32)])
    order = np.argsort(facets)
    return vector_space(msh, 1), mesh.meshtags(msh, 1, facets[order], values[order])


def clamp(V, tags, marker):
    dofs = fem.locate_dofs_topological(V, 1, tags.find(marker))
    return fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), dofs, V)


@pytest.fixture
def no_candidate_search(monkeypatch):
    """Refusals must come before the candidate search (the gathers, the tributary assembly)."""
    def searched(*args, **kwargs):
        raise AssertionError("the candidate search ran before the input was refused")
    monkeypatch.setattr(contact_module, "find_candidates", searched)
    monkeypatch.setattr(contact_module, "find_pairs", searched)


# A surface marker that tags nothing ------------------------------------------------------------------------------
def test_a_marker_the_tags_do_not_hold_is_named_with_the_markers_they_hold(no_candidate_search):
    V, tags = square()
    bcs = [clamp(V, tags, 3)]
    with pytest.raises(ValueError) as error:
        dfr.Contact(V, (tags, 7), PLANE, mu=0.3, bcs=bcs)
    assert str(error.value) == "Contact: surface marker 7 tags no facet; the facet tags hold markers [1, 2, 3]"


def test_empty_facet_tags_are_refused(no_candidate_search):
    V, tags = square(markers={})
    with pytest.raises(ValueError, match=r"^Contact: surface marker 1 tags no facet; the facet tags hold no marker$"):
        dfr.Contact(V, (tags, 1), PLANE, mu=0.3)


def test_a_master_marker_that_tags_nothing_is_refused(no_candidate_search):
    V, tags = square()
    master = dfr.ElasticBody((tags, 9), normal=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"^Contact: ElasticBody.surface marker 9 tags no facet; "
                                         r"the facet tags hold markers \[1, 2, 3\]$"):
        dfr.Contact(V, (tags, 1), master, mu=0.3, bcs=[clamp(V, tags, 3)])


def test_cell_tags_and_non_integer_markers_are_refused(no_candidate_search):
    V, tags = square()
    msh = V.mesh
    cells = np.arange(msh.topology.index_map(2).size_local, dtype=np.int32)
    cell_tags = mesh.meshtags(msh, 2, cells, np.ones(cells.size, dtype=np.int32))
    with pytest.raises(ValueError, match=r"surface: the tags are of entities of dimension 2; the facets of this 2D "
                                         r"mesh have dimension 1"):
        dfr.Contact(V, (cell_tags, 1), PLANE, mu=0.3)
    for marker in (1.0, "1", True, None):
        with pytest.raises(TypeError, match=rf"Contact: surface marker = {marker!r}: expected an integer facet tag"):
            dfr.Contact(V, (tags, marker), PLANE, mu=0.3)
    with pytest.raises(TypeError, match=r"Contact: surface\[0\] must be DOLFINx facet tags"):
        dfr.Contact(V, (tags.find(1), 1), PLANE, mu=0.3)
    with pytest.raises(TypeError, match=r"Contact: surface must be \(facet_tags, marker\)"):
        dfr.Contact(V, [tags, 1], PLANE, mu=0.3)


def test_bad_friction_values_are_refused_before_the_search(no_candidate_search):
    V, tags = square()
    for mu in (np.inf, np.nan, -0.1, "0.3", None, True, [0.1, -0.1], [[0.1]], [0.1, [0.2]]):
        with pytest.raises(ValueError, match=r"^Contact: mu = .*: expected a finite value >= 0 \(or one per contact\), "
                                             r"or a friction law \(dolfinx_fretting\.laws\.Coulomb\)$"):
            dfr.Contact(V, (tags, 1), PLANE, mu=mu)


def test_one_friction_value_per_contact_is_counted():
    V, tags = square()
    with pytest.raises(ValueError, match=rf"one per contact, {N + 1}"):
        dfr.Contact(V, (tags, 1), PLANE, mu=[0.3] * N)


# A surface with no free vertex ------------------------------------------------------------------------------------
def test_a_surface_whose_every_node_is_clamped_is_refused(no_candidate_search):
    V, tags = square()
    # The bottom clamped, and the right side (which shares the corner (1, 0)): every bottom node is fixed.
    with pytest.raises(ValueError, match=rf"^Contact: surface marker 1 has no free vertex: bcs fix every component "
                                         rf"of all its {N + 1} nodes"):
        dfr.Contact(V, (tags, 1), PLANE, mu=0.3, bcs=[clamp(V, tags, 1), clamp(V, tags, 2)])


def test_a_surface_with_some_nodes_clamped_keeps_the_others():
    V, tags = square()
    # The right side clamped: the bottom's corner (1, 0) is fixed, its other N nodes stay candidates.
    contact = dfr.Contact(V, (tags, 1), PLANE, mu=0.3, bcs=[clamp(V, tags, 2)])
    assert contact.nc == N
    assert np.all(contact.contact_set.coords[:, 0] < 1.0)


# The valid path ----------------------------------------------------------------------------------------------------
def test_the_valid_path_gives_the_bottom_nodes_their_gaps_and_frames():
    V, tags = square()
    contact = dfr.Contact(V, (tags, 1), PLANE, mu=0.3, bcs=[clamp(V, tags, 3)])
    cs = contact.contact_set
    # The bottom's N + 1 vertices, ordered along t1 = (1, 0): x = 0, 1/N, ..., 1 (exact: the mesh's own points,
    # to rounding of k / N).
    assert contact.nc == N + 1
    assert np.allclose(cs.coords, np.column_stack([np.linspace(0.0, 1.0, N + 1), np.zeros(N + 1)]), atol=1e-14)
    assert np.allclose(cs.gap0, 0.1, atol=1e-14)                       # the plane is 0.1 below y = 0
    assert np.allclose(cs.frames, [[0.0, 1.0], [1.0, 0.0]], atol=0)     # rows (n, t1 = (n_y, -n_x))
    assert cs.tributary.sum() == pytest.approx(1.0, rel=1e-12)         # lumped length of the bottom: 1
    assert np.allclose(contact.mu, 0.3)


# The obstacle normal's length ------------------------------------------------------------------------------------
def test_a_non_unit_normal_gives_the_unit_normal_s_gaps_and_frames():
    V, tags = square()
    bcs = [clamp(V, tags, 3)]
    unit = dfr.Contact(V, (tags, 1), PLANE, mu=0.3, bcs=bcs).contact_set
    long = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, -0.1], [0.0, 2.0]), mu=0.3, bcs=bcs).contact_set
    # Normalising a vector of length 2 is exact in binary: the same bits.
    assert np.array_equal(long.gap0, unit.gap0) and np.array_equal(long.frames, unit.frames)
    assert (long.H != unit.H).nnz == 0


def test_obstacle_normals_are_stored_as_unit_vectors():
    # The distance of (3, 4) from the line through 0 with normal (3, 4) is 5, whatever the normal's length.
    plane = dfr.RigidPlane([0.0, 0.0], [3.0, 4.0])
    assert np.allclose(plane.normal, [0.6, 0.8], rtol=1e-15)
    assert plane.gap(np.array([[3.0, 4.0]]))[0] == pytest.approx(5.0, rel=1e-15)
    assert np.allclose(dfr.RigidPlane([0, 0, 0], [0, 0, 5.0]).frame, dfr.RigidPlane([0, 0, 0], [0, 0, 1.0]).frame,
                       rtol=0, atol=0)
    assert np.allclose(dfr.ElasticBody((None, 1), [0.0, 3.0]).normal, [0.0, 1.0], rtol=0, atol=0)
    for bad in ([0.0, 0.0], [np.nan, 1.0], [np.inf, 1.0], [1.0]):
        with pytest.raises(ValueError, match=r"RigidPlane.normal = .*: expected a finite non-zero 2- or 3-vector"):
            dfr.RigidPlane(np.zeros(len(bad)), bad)
    for bad in ([0.0, np.inf], [0.0, 0.0, 0.0]):
        with pytest.raises(ValueError, match=r"RigidPlane.point = .*: expected 2 finite coordinates"):
            dfr.RigidPlane(bad, [0.0, 1.0])


# The frames as documented (docs/api.md, contact.tangent_frame) -----------------------------------------------
def test_the_3d_frame_is_built_as_documented():
    # n = z: the least aligned axis is x (the first of x, y): t1 = x, t2 = n x t1 = y.
    assert np.array_equal(tangent_frame([0.0, 0.0, 1.0]), [[0, 0, 1], [1, 0, 0], [0, 1, 0]])
    # n = y: t1 = x, t2 = y x x = -z.
    assert np.array_equal(tangent_frame([0.0, 1.0, 0.0]), [[0, 1, 0], [1, 0, 0], [0, 0, -1]])
    # n = x: the least aligned axes are y and z: t1 = y, t2 = x x y = z.
    assert np.array_equal(tangent_frame([1.0, 0.0, 0.0]), [[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    # n = (1, 1, 1)/sqrt 3: t1 = x orthogonalised, (2, -1, -1)/sqrt 6; t2 = n x t1 = (0, 1, -1)/sqrt 2 (by hand).
    frame = tangent_frame([1.0, 1.0, 1.0])
    assert np.allclose(frame, [np.ones(3) / np.sqrt(3), [2 / np.sqrt(6), -1 / np.sqrt(6), -1 / np.sqrt(6)],
                               [0.0, 1 / np.sqrt(2), -1 / np.sqrt(2)]], rtol=0, atol=1e-15)
    # Any normal: orthonormal and right-handed in 3D; in 2D t1 is n turned clockwise (det -1).
    rng = np.random.default_rng(22)
    for n in rng.normal(size=(20, 3)):
        frame = tangent_frame(n)
        assert np.allclose(frame @ frame.T, np.eye(3), atol=1e-14) and np.linalg.det(frame) == pytest.approx(1.0)
        assert np.allclose(frame[0], n / np.linalg.norm(n), atol=1e-15)
    assert np.linalg.det(tangent_frame([0.3, 0.7])) == pytest.approx(-1.0)



def test_friction_law_object_equals_its_coefficient():
    """Contact(mu=Coulomb(0.3)) holds the same per-contact coefficients as mu=0.3, and per-contact values must
    number the contacts (laws.Coulomb: the friction law the local solvers read through its coefficients)."""
    from dolfinx_fretting.laws import Coulomb

    V, tags = square()
    bcs = [clamp(V, tags, 3)]
    by_value = dfr.Contact(V, (tags, 1), PLANE, mu=0.3, bcs=bcs)
    by_law = dfr.Contact(V, (tags, 1), PLANE, mu=Coulomb(0.3), bcs=bcs)
    assert np.array_equal(by_law.mu, by_value.mu) and by_law.mu.shape == (N + 1,)
    assert by_value.friction == Coulomb(0.3) and by_law.friction.describe() == "Coulomb, mu = 0.3"
    ramp = np.linspace(0.1, 0.5, N + 1)
    assert np.array_equal(dfr.Contact(V, (tags, 1), PLANE, mu=Coulomb(ramp), bcs=bcs).mu, ramp)
    with pytest.raises(ValueError, match="mu"):
        dfr.Contact(V, (tags, 1), PLANE, mu=Coulomb(ramp[:-1]), bcs=bcs)
