"""The sphere-on-flat model of tests/test_sphere.py, tests/test_parallel.py and tests/test_finite_sliding.py,
written as a DOLFINx user would (mesh, space, form, conditions), with the package's Contact and
FrettingProblem."""

import numpy as np
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting import meshes_3d as m3  # noqa: E402
from dolfinx_fretting.analytic import hertz_sphere, plane_strain_modulus  # noqa: E402

COMM = MPI.COMM_WORLD
E, NU, R, P = 210000.0, 0.3, 10.0, 100.0   # MPa, -, mm, N (the whole sphere's load)


def elasticity(V):
    lmbda, G = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    return ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * G * eps(u), eps(v)) * ufl.dx


def contact_modulus(flat):
    """E* of the sphere on an identical flat (``flat``) or on a rigid plane: the package's declaration."""
    return plane_strain_modulus(E, NU, E, NU) if flat else plane_strain_modulus(E, NU)


def sphere_model(a_over_h, extent, growth, *, flat, half=True, mu=0.0, wear=None, window=1.4, flat_mesh_size=None,
                 comm=COMM, sliding="small", reach=None, depth_growth=None, coarsening=0, field_cell=0.125,
                 formulation="node", solver=None, delassus_method="auto"):
    """The sphere's cap (top clamped) on a rigid plane z = 0 or on an identical flat (bottom clamped), sized
    from Hertz's a for P; a half model has rollers (u_y = 0) on y = 0; ``sliding`` and ``reach`` (in units of a)
    as :class:`~dolfinx_fretting.contact.ElasticBody`'s; ``depth_growth``, ``coarsening`` and ``field_cell`` as
    :func:`~dolfinx_fretting.meshes_3d.sphere_on_flat`'s (the depth-graded mesh); ``formulation`` the elastic flat's
    (``"node"`` or ``"mortar"``); ``solver`` a LocalSolver (None: the default); ``delassus_method`` as
    :class:`~dolfinx_fretting.FrettingProblem`'s. Returns (body, problem, a, p0, h)."""
    E_star = contact_modulus(flat)
    a, p0 = hertz_sphere(P, R, E_star)
    h = a / a_over_h
    body = m3.sphere_on_flat(comm, R, a, h, extent=extent, growth=growth, half=half, flat=flat,
                             flat_mesh_size=None if flat_mesh_size is None else a / flat_mesh_size,
                             depth_growth=depth_growth, coarsening=coarsening, field_cell=field_cell)
    V = dfx.vector_space(body.mesh, 1)
    clamp = [fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(V, 2, body.facets(name)), V)
             for name in (["top", "flat_bottom"] if flat else ["top"])]
    bcs = clamp
    if half:
        V1, _ = V.sub(1).collapse()
        sym = np.concatenate([body.facets(n) for n in body.tags if "symmetry" in n])
        bcs = clamp + [fem.dirichletbc(fem.Function(V1), fem.locate_dofs_topological((V.sub(1), V1), 2, sym),
                                       V.sub(1))]
    surface = (body.facet_tags, body.tags["surface"])
    obstacle = (dfr.ElasticBody((body.facet_tags, body.tags["flat_top"]), [0.0, 0.0, 1.0], sliding=sliding,
                                reach=None if reach is None else reach * a, formulation=formulation) if flat
                else dfr.RigidPlane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    contact = dfr.Contact(V, surface, obstacle, mu=mu, bcs=bcs, window=window * a + h)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs, wear=wear, solver=solver,
                                  delassus_method=delassus_method)
    return body, problem, a, p0, h


def pressed(problem, load):
    state = problem.initial_state()
    for f in (0.5, 1.0):
        state = problem.commit(state, problem.solve(state, normal=dfr.Force(f * load)))
    return state


def contact_radii(problem, state, half=True):
    """(equivalent radius of the loaded area sqrt(A/pi), largest radius of a loaded node, peak pressure)."""
    fields = problem.contact_fields(state)
    loaded = fields["pressure"] > 0
    area = problem.contact.contact_set.tributary[loaded].sum() * (2.0 if half else 1.0)
    r = np.linalg.norm(fields["coordinates"][:, :2], axis=1)
    return np.sqrt(area / np.pi), r[loaded].max(), fields["pressure"].max()
