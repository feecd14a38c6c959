"""The pulled block of the fatigue tests (tests/test_fatigue.py, tests/test_parallel.py), written as a DOLFINx user
would: a unit square in plane strain under a cyclic uniform traction, its top the contact surface of a rigid plane
that it never reaches."""

import math

import numpy as np

import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import compat  # noqa: E402
from support.blocks import component, elasticity, tagged, unit_squares  # noqa: E402


def pulled_block(comm, n: int = 6, plasticity=None, gap: float = 0.1, graded: bool = False):
    """A unit square (n x n quadrilaterals, plane strain) pulled by a uniform traction on its left and right faces
    (the load "pull", 1 MPa per unit factor, self-balanced; ``graded``: y MPa at height y), rollers on the bottom
    face and u_x = 0 at its bottom-left corner (the top's nodes stay free to slide); its top is
    the contact surface, under a rigid plane ``gap`` above it (the default 0.1 is never reached: the contact stays
    open)."""
    msh = unit_squares([(0.0, 0.0)], n, comm)
    V = compat.vector_space(msh, 1)
    tags = tagged(msh, {1: lambda x: np.isclose(x[1], 1.0), 2: lambda x: np.isclose(x[0], 1.0),
                        3: lambda x: np.isclose(x[0], 0.0)})
    bcs = [component(V, 1, lambda x: np.isclose(x[1], 0.0)),
           component(V, 0, lambda x: np.isclose(x[0], 0.0) & np.isclose(x[1], 0.0))]
    v = ufl.TestFunction(V)
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
    height = ufl.SpatialCoordinate(msh)[1]
    traction = ufl.as_vector([height, 0.0]) if graded else fem.Constant(msh, np.array([1.0, 0.0]))
    pull = ufl.inner(traction, v) * ds(2) - ufl.inner(traction, v) * ds(3)
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, 1.0 + gap], [0.0, -1.0]), mu=0.5, bcs=bcs)
    return dfr.FrettingProblem(elasticity(V), contact, bcs, loads={"pull": pull}, plasticity=plasticity)


def block_cycle(problem, amplitude: float = 200.0, mean: float = 50.0, steps: int = 8):
    """The committed states of one load cycle, traction mean + amplitude sin(2 pi i / steps)."""
    state = problem.initial_state()
    states = []
    for i in range(1, steps + 1):
        state, _ = problem.advance(state, loads={"pull": mean + amplitude * math.sin(2 * math.pi * i / steps)})
        states.append(state)
    return states


def rubbed_cycle(problem, approach: float = 2e-4, stroke: float = 1e-3, amplitude: float = 100.0,
                 steps: int = 8):
    """The plane pressed by ``approach`` (a block made with gap=0), then one cycle of tangential motion
    stroke sin(2 pi i / steps) with the pull in phase, amplitude sin(...): the committed states of the cycle."""
    state, _ = problem.advance(problem.initial_state(), normal=approach)
    states = []
    for i in range(1, steps + 1):
        phase = math.sin(2 * math.pi * i / steps)
        state, _ = problem.advance(state, tangential=stroke * phase, loads={"pull": amplitude * phase})
        states.append(state)
    return states
