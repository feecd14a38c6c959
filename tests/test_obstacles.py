"""The obstacle protocol: a new shape is one class (here, in the test) and one registry entry.

A shape written outside the package — a rigid plane given by its angle — plugs into a Contact and a problem
through :class:`~dolfinx_fretting.contact.Obstacle` alone, and gives the answer of the built-in plane it equals
(to the bit: the same search on the same plane).
"""

import dataclasses

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import compat  # noqa: E402
from dolfinx_fretting.contact import Obstacle, find_candidates  # noqa: E402
from dolfinx_fretting.obstacles import OBSTACLES, obstacle_kind  # noqa: E402
from dolfinx_fretting.output import OBSTACLE_TEXT  # noqa: E402


@dataclasses.dataclass(frozen=True)
class AnglePlane(Obstacle):
    """A rigid line through ``point`` whose normal makes ``angle`` (radians) with the y axis (a user's shape)."""

    point: tuple
    angle: float

    @property
    def normal(self) -> np.ndarray:
        return np.array([-np.sin(self.angle), np.cos(self.angle)])

    def candidates(self, V, facets, half_width, exclude_nodes):
        plane = dfr.RigidPlane(np.array(self.point, dtype=float), self.normal)
        return find_candidates(V, facets, plane, half_width, exclude_nodes=exclude_nodes)


def test_every_registered_shape_is_described_in_words():
    """One name per shape: the registry's names are the run description's kinds."""
    assert set(OBSTACLES) == set(OBSTACLE_TEXT)


def test_a_shape_written_outside_the_package_plugs_in():
    msh = mesh.create_rectangle(MPI.COMM_WORLD, [np.array([-1.0, 0.0]), np.array([1.0, 1.0])], [8, 4],
                                mesh.CellType.quadrilateral)
    V = compat.vector_space(msh, 1)
    bottom = mesh.locate_entities_boundary(msh, 1, lambda x: np.isclose(x[1], 0.0))
    tags = mesh.meshtags(msh, 1, np.sort(bottom), np.ones(bottom.size, dtype=np.int32))
    top = fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[1], 1.0))
    bcs = [fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), top, V)]
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    a = ufl.inner(ufl.grad(u), ufl.grad(v)) * 1e5 * ufl.dx
    answers = []
    for obstacle in (AnglePlane((0.0, -1e-3), 0.0), dfr.RigidPlane([0.0, -1e-3], [0.0, 1.0])):
        contact = dfr.Contact(V, (tags, 1), obstacle, mu=0.3, bcs=bcs)
        # the shape's own search made the candidates: every bottom node 1e-3 above its plane (rounding: 1e-15)
        assert np.allclose(contact.contact_set.gap0, 1e-3, rtol=0, atol=1e-15)
        problem = dfr.FrettingProblem(a, contact, bcs)
        state, _ = problem.advance(problem.initial_state(), normal=2e-3, tangential=1e-4)
        answers.append(state.forces)
    assert np.array_equal(answers[0], answers[1])
    with pytest.raises(ValueError, match="AnglePlane is not a registered shape"):
        obstacle_kind(AnglePlane((0.0, 0.0), 0.0))
    OBSTACLES["angle_plane"] = AnglePlane
    try:
        assert obstacle_kind(AnglePlane((0.0, 0.0), 0.0)) == "angle_plane"
    finally:
        del OBSTACLES["angle_plane"]
    with pytest.raises(TypeError, match="obstacle must be an Obstacle"):
        dfr.Contact(V, (tags, 1), object(), mu=0.3, bcs=bcs)
