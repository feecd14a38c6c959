"""The two-body finite-sliding problem of tests/test_finite_sliding.py and tests/test_parallel.py: the cylinder-flat
scene's model (the cylinder R = 6 mm on a 20 x 10 mm flat, both deformable) as an API problem with
``ElasticBody(sliding=...)``, on any communicator."""

import dataclasses

from mpi4py import MPI

import dolfinx_fretting as dfr
from dolfinx_fretting.contact import Contact
from dolfinx_fretting.geometries import build_scene_model
from dolfinx_fretting.scenes import load_scene

P, MU = 199.24, 0.3


def cylinder_on_flat(comm: MPI.Comm = MPI.COMM_WORLD, mesh_size: float = 0.02):
    """The cylinder-flat scene's model with contact elements of ``mesh_size`` (mm) on ``comm``. Collective."""
    return build_scene_model(load_scene("cylinder-flat", [f"geometry.contact_mesh_size={mesh_size}"]), comm)


def sliding_problem(model, sliding_model: str, wear=None, reach: float = 0.3) -> dfr.FrettingProblem:
    """The API problem of ``model`` with the master body sliding ``sliding_model`` ("small" or "finite") within
    ``reach`` (mm), friction MU, candidate half-width 0.35 mm. Collective."""
    obstacle = dataclasses.replace(model.obstacle, sliding=sliding_model, reach=reach)
    contact = Contact(model.V, model.surface, obstacle, MU, model.bcs, 0.35)
    return dfr.FrettingProblem(model.form, contact, model.bcs, wear=wear)


def pressed(problem: dfr.FrettingProblem):
    """The initial state pressed to the normal force P in two increments."""
    state = problem.initial_state()
    for load in (0.5 * P, P):
        state = problem.commit(state, problem.solve(state, normal=dfr.Force(load)))
    return state
