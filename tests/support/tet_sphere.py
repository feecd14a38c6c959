"""A sphere's cap meshed by gmsh in unstructured tetrahedra, pressed on a rigid plane through the public API
(issue 23's convergence check of the pressure a user reads; benchmarks/bench_tet_pressure.py and
tests/test_pressure_recovery.py).

Quarter model: the ball of radius R centred at (0, 0, R) cut by x >= 0, y >= 0 and z <= 9a (top clamped), rollers
on x = 0 and y = 0 (the symmetric solution of the whole cap, which carries 4 times the quarter's load). A cap of
height ~9a with its top clamped is within ~0.05 % of a much larger body in the peak pressure
(/work/shared/notes/3d-contact.md), so Hertz's half-space solution is the reference to that amount. The contact
zone (within 1.5a of the first point of contact) has the element size h = a / (a/h), growing to 1.5a at 8a.
"""

from __future__ import annotations

import gmsh
import numpy as np
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting.analytic import hertz_sphere  # noqa: E402
from dolfinx_fretting.compat import model_to_mesh, vector_space  # noqa: E402

E, NU, R, P = 210000.0, 0.3, 10.0, 100.0   # MPa, -, mm, N (the whole cap's load)
E_STAR = E / (1 - NU**2)                   # the sphere on a rigid plane
SURFACE, SYMMETRY_X, SYMMETRY_Y, TOP = 1, 2, 3, 4
#: gmsh's surface meshing algorithms (Mesh.Algorithm): two unstructured triangulations of the same surface
MESHERS = {"frontal-delaunay": 6, "delaunay": 5}
CAP_HEIGHT, ZONE, COARSE_AT, COARSE = 9.0, 1.5, 8.0, 1.5   # in units of a


def hertz() -> tuple[float, float]:
    """(a, p0) of the whole cap's load P."""
    return hertz_sphere(P, R, E_STAR)


def tet_cap_mesh(a_over_h: float, comm: MPI.Comm = MPI.COMM_WORLD, mesher: str = "frontal-delaunay"):
    """(mesh, facet_tags) of the quarter cap, tetrahedra, built on rank 0 (``mesher``: gmsh's surface algorithm,
    a key of :data:`MESHERS`: another unstructured mesh at the same sizes)."""
    a, _ = hertz()
    h = a / a_over_h
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("tet_cap")
        occ = gmsh.model.occ
        ball = occ.addSphere(0.0, 0.0, R, R)
        box = occ.addBox(0.0, 0.0, 0.0, R, R, CAP_HEIGHT * a)
        occ.intersect([(3, ball)], [(3, box)])
        occ.synchronize()
        volumes = gmsh.model.getEntities(3)
        groups = {SURFACE: [], SYMMETRY_X: [], SYMMETRY_Y: [], TOP: []}
        for _, tag in gmsh.model.getEntities(2):
            x = occ.getCenterOfMass(2, tag)
            if abs(x[0]) < 1e-9 * R:
                groups[SYMMETRY_X].append(tag)
            elif abs(x[1]) < 1e-9 * R:
                groups[SYMMETRY_Y].append(tag)
            elif abs(x[2] - CAP_HEIGHT * a) < 1e-9 * R:
                groups[TOP].append(tag)
            else:
                groups[SURFACE].append(tag)
        for marker, tags in groups.items():
            gmsh.model.addPhysicalGroup(2, tags, marker)
        gmsh.model.addPhysicalGroup(3, [v[1] for v in volumes], 1)
        point = occ.addPoint(0.0, 0.0, 0.0)
        occ.synchronize()
        field = gmsh.model.mesh.field
        distance = field.add("Distance")
        field.setNumbers(distance, "PointsList", [point])
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        field.setNumber(threshold, "SizeMin", h)
        field.setNumber(threshold, "SizeMax", COARSE * a)
        field.setNumber(threshold, "DistMin", ZONE * a)
        field.setNumber(threshold, "DistMax", COARSE_AT * a)
        field.setAsBackgroundMesh(threshold)
        for option in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
            gmsh.option.setNumber(option, 0)
        gmsh.option.setNumber("Mesh.Algorithm", MESHERS[mesher])
        gmsh.model.mesh.generate(3)
    msh, _, facet_tags = model_to_mesh(gmsh.model, comm, 0, gdim=3)
    if comm.rank == 0:
        gmsh.finalize()
    return msh, facet_tags


def elasticity(V):
    lmbda, G = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    return ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * G * eps(u), eps(v)) * ufl.dx


def tet_cap_problem(a_over_h: float, comm: MPI.Comm = MPI.COMM_WORLD, mesher: str = "frontal-delaunay", **contact_options):
    """(problem, contact, a, p0, h) of the quarter cap on the rigid plane z = 0, frictionless; ``contact_options``
    go to :class:`~dolfinx_fretting.contact.Contact`."""
    a, p0 = hertz()
    h = a / a_over_h
    msh, facet_tags = tet_cap_mesh(a_over_h, comm, mesher)
    V = vector_space(msh, 1)
    bcs = [fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(V, 2, facet_tags.find(TOP)), V)]
    for axis, marker in ((0, SYMMETRY_X), (1, SYMMETRY_Y)):
        Vi, _ = V.sub(axis).collapse()
        dofs = fem.locate_dofs_topological((V.sub(axis), Vi), 2, facet_tags.find(marker))
        bcs.append(fem.dirichletbc(fem.Function(Vi), dofs, V.sub(axis)))
    contact = dfr.Contact(V, (facet_tags, SURFACE), dfr.RigidPlane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]), mu=0.0,
                          bcs=bcs, window=1.4 * a + h, **contact_options)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs)
    return problem, contact, a, p0, h


def pressed(problem):
    """The quarter's load P/4 in two increments."""
    state = problem.initial_state()
    for fraction in (0.5, 1.0):
        state = problem.commit(state, problem.solve(state, normal=dfr.Force(fraction * P / 4)))
    return state


def hertz_errors(coordinates: np.ndarray, pressure: np.ndarray, a: float, p0: float) -> dict[str, float]:
    """Peak error (max p / p0 - 1) and the RMS of p - p_Hertz over the nodes within 0.8a, over p0."""
    radius = np.linalg.norm(coordinates[:, :2], axis=1)
    exact = p0 * np.sqrt(np.clip(1 - (radius / a) ** 2, 0.0, None))
    inner = radius < 0.8 * a
    rms = float(np.sqrt(np.mean((pressure - exact)[inner] ** 2)) / p0)
    return {"peak": float(pressure.max() / p0 - 1), "rms": rms,
            "max_inner": float(np.abs(pressure - exact)[inner].max() / p0)}
