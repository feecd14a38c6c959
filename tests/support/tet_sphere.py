"""A sphere's cap meshed by gmsh in unstructured tetrahedra, pressed on a rigid plane or on an identical elastic flat
through the public API (issue 23's convergence check of the pressure a user reads; benchmarks/bench_tet_pressure.py,
benchmarks/bench_tet_recovery.py and tests/test_pressure_recovery.py).

Quarter model: the ball of radius R centred at (0, 0, R) cut by x >= 0, y >= 0 and z <= 9a (top clamped), rollers
on x = 0 and y = 0 (the symmetric solution of the whole cap, which carries 4 times the quarter's load). A half model
(y >= 0 only, a roller on y = 0) for a tangential load along x, which x = 0 is no symmetry plane of. A cap of
height ~9a with its top clamped is within ~0.05 % of a much larger body in the peak pressure
(/work/shared/notes/3d-contact.md), so Hertz's half-space solution is the reference to that amount. The contact
zone (within 1.5a of the first point of contact) has the element size h = a / (a/h), growing to 1.5a at 8a.

The elastic flat (``flat_a_over_h``): a block 9a deep and 9a wide on each side of the axis under z = 0 (bottom
clamped, the same rollers), of the cap's material, meshed by gmsh in tetrahedra of its own size a / flat_a_over_h
within 1.5a of the first point of contact (the two faces never match: two unstructured triangulations).
"""

from __future__ import annotations

import gmsh
import numpy as np
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting.analytic import hertz_sphere, plane_strain_modulus  # noqa: E402
from dolfinx_fretting.compat import model_to_mesh, vector_space  # noqa: E402

E, NU, R, P = 210000.0, 0.3, 10.0, 100.0   # MPa, -, mm, N (the whole cap's load)
E_STAR = E / (1 - NU**2)                   # the sphere on a rigid plane
E_STAR_PAIR = plane_strain_modulus(E, NU, E, NU)   # the sphere on an identical flat: E / (2 (1 - nu^2))
SURFACE, SYMMETRY_X, SYMMETRY_Y, TOP, FLAT_TOP, FLAT_BOTTOM = 1, 2, 3, 4, 5, 6
#: gmsh's surface meshing algorithms (Mesh.Algorithm): two unstructured triangulations of the same surface
MESHERS = {"frontal-delaunay": 6, "delaunay": 5}
CAP_HEIGHT, ZONE, COARSE_AT, COARSE = 9.0, 1.5, 8.0, 1.5   # in units of a
FLAT_EXTENT = 9.0                                          # the flat's depth and half-width, in units of a


def hertz(flat: bool = False) -> tuple[float, float]:
    """(a, p0) of the whole cap's load P, on a rigid plane or on an identical flat (``flat``)."""
    return hertz_sphere(P, R, E_STAR_PAIR if flat else E_STAR)


def _size_field(h: float, a: float, point: int) -> int:
    """A gmsh size field: h within ZONE a of ``point``, growing to COARSE a at COARSE_AT a."""
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "PointsList", [point])
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    field.setNumber(threshold, "SizeMin", h)
    field.setNumber(threshold, "SizeMax", COARSE * a)
    field.setNumber(threshold, "DistMin", ZONE * a)
    field.setNumber(threshold, "DistMax", COARSE_AT * a)
    return threshold


def _field_above(inner: int, above: bool, a: float) -> int:
    """``inner`` on one side of z = 1e-6 a (the flat's top face, z = 0, below it), a size larger than any element
    on the other: the Max of ``inner`` and a Box field (Debian's gmsh 4.8 does not restrict fields to volumes)."""
    field = gmsh.model.mesh.field
    box = field.add("Box")
    far = 1e3 * R
    field.setNumber(box, "VIn", 0.0)
    field.setNumber(box, "VOut", far)
    for name, value in (("XMin", -far), ("XMax", far), ("YMin", -far), ("YMax", far),
                        ("ZMin", 1e-6 * a if above else -far), ("ZMax", far if above else 1e-6 * a)):
        field.setNumber(box, name, value)
    out = field.add("Max")
    field.setNumbers(out, "FieldsList", [inner, box])
    return out


def tet_cap_mesh(a_over_h: float, comm: MPI.Comm = MPI.COMM_WORLD, mesher: str = "frontal-delaunay", *,
                 flat_a_over_h: float | None = None, half: bool = False):
    """(mesh, facet_tags) of the quarter cap (``half``: the half cap, y >= 0), tetrahedra, built on rank 0
    (``mesher``: gmsh's surface algorithm, a key of :data:`MESHERS`: another unstructured mesh at the same sizes);
    with ``flat_a_over_h``, on an elastic flat of that a/h in the contact zone (a the pair's Hertz radius)."""
    a, _ = hertz(flat=flat_a_over_h is not None)
    h = a / a_over_h
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("tet_cap")
        occ = gmsh.model.occ
        ball = occ.addSphere(0.0, 0.0, R, R)
        box = occ.addBox(-R if half else 0.0, 0.0, 0.0, 2 * R if half else R, R, CAP_HEIGHT * a)
        occ.intersect([(3, ball)], [(3, box)])
        occ.synchronize()
        cap_volumes = [v[1] for v in gmsh.model.getEntities(3)]
        flat_volumes = []
        if flat_a_over_h is not None:   # a separate volume: no boolean, so the two bodies share no node
            width = FLAT_EXTENT * a
            flat_volumes = [occ.addBox(-width if half else 0.0, 0.0, -width, 2 * width if half else width,
                                       width, width)]
            occ.synchronize()
        groups = {SURFACE: [], SYMMETRY_X: [], SYMMETRY_Y: [], TOP: [], FLAT_TOP: [], FLAT_BOTTOM: []}
        for volumes, is_flat in ((cap_volumes, False), (flat_volumes, True)):
            if not volumes:
                continue
            for _, tag in gmsh.model.getBoundary([(3, v) for v in volumes], oriented=False):
                x = occ.getCenterOfMass(2, tag)
                if not half and abs(x[0]) < 1e-9 * R:
                    groups[SYMMETRY_X].append(tag)
                elif abs(x[1]) < 1e-9 * R:
                    groups[SYMMETRY_Y].append(tag)
                elif is_flat and abs(x[2]) < 1e-9 * R:
                    groups[FLAT_TOP].append(tag)
                elif is_flat and abs(x[2] + FLAT_EXTENT * a) < 1e-9 * R:
                    groups[FLAT_BOTTOM].append(tag)
                elif is_flat:
                    continue   # the flat's free sides
                elif abs(x[2] - CAP_HEIGHT * a) < 1e-9 * R:
                    groups[TOP].append(tag)
                else:
                    groups[SURFACE].append(tag)
        for marker, tags in groups.items():
            if tags:
                gmsh.model.addPhysicalGroup(2, tags, marker)
        gmsh.model.addPhysicalGroup(3, cap_volumes, 1)
        if flat_volumes:
            gmsh.model.addPhysicalGroup(3, flat_volumes, 2)
        point = occ.addPoint(0.0, 0.0, 0.0)
        occ.synchronize()
        field = _size_field(h, a, point)
        if flat_a_over_h is not None:   # the cap's sizes above z = 0, the flat's below
            both = [_field_above(field, True, a), _field_above(_size_field(a / flat_a_over_h, a, point), False, a)]
            field = gmsh.model.mesh.field.add("Min")
            gmsh.model.mesh.field.setNumbers(field, "FieldsList", both)
        gmsh.model.mesh.field.setAsBackgroundMesh(field)
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


def tet_cap_problem(a_over_h: float, comm: MPI.Comm = MPI.COMM_WORLD, mesher: str = "frontal-delaunay", *,
                    flat_a_over_h: float | None = None, formulation: str = "node", half: bool = False, mu: float = 0.0,
                    **contact_options):
    """(problem, contact, a, p0, h) of the quarter cap (``half``: the half cap) on the rigid plane z = 0, or, with
    ``flat_a_over_h``, on the elastic flat (:func:`tet_cap_mesh`; the flat's top the master of an
    :class:`~dolfinx_fretting.contact.ElasticBody` of ``formulation``, its bottom clamped); Coulomb's ``mu``;
    ``contact_options`` go to :class:`~dolfinx_fretting.contact.Contact`. a and p0 are the pair's Hertz values."""
    flat = flat_a_over_h is not None
    a, p0 = hertz(flat)
    h = a / a_over_h
    msh, facet_tags = tet_cap_mesh(a_over_h, comm, mesher, flat_a_over_h=flat_a_over_h, half=half)
    V = vector_space(msh, 1)
    bcs = [fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(V, 2, facet_tags.find(marker)), V)
           for marker in ((TOP, FLAT_BOTTOM) if flat else (TOP,))]
    for axis, marker in ((1, SYMMETRY_Y),) if half else ((0, SYMMETRY_X), (1, SYMMETRY_Y)):
        Vi, _ = V.sub(axis).collapse()
        dofs = fem.locate_dofs_topological((V.sub(axis), Vi), 2, facet_tags.find(marker))
        bcs.append(fem.dirichletbc(fem.Function(Vi), dofs, V.sub(axis)))
    obstacle = dfr.ElasticBody((facet_tags, FLAT_TOP), [0.0, 0.0, 1.0], formulation=formulation) if flat else \
        dfr.RigidPlane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    contact = dfr.Contact(V, (facet_tags, SURFACE), obstacle, mu=mu, bcs=bcs, window=1.4 * a + h, **contact_options)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs)
    return problem, contact, a, p0, h


def pressed(problem, share: float = 0.25):
    """The model's share of the load (a quarter's P/4, a half's P/2) in two increments."""
    state = problem.initial_state()
    for fraction in (0.5, 1.0):
        state = problem.commit(state, problem.solve(state, normal=dfr.Force(fraction * share * P)))
    return state


def hertz_errors(coordinates: np.ndarray, pressure: np.ndarray, a: float, p0: float) -> dict[str, float]:
    """Peak error (max p / p0 - 1) and the RMS of p - p_Hertz over the nodes within 0.8a, over p0."""
    radius = np.linalg.norm(coordinates[:, :2], axis=1)
    exact = p0 * np.sqrt(np.clip(1 - (radius / a) ** 2, 0.0, None))
    inner = radius < 0.8 * a
    rms = float(np.sqrt(np.mean((pressure - exact)[inner] ** 2)) / p0)
    return {"peak": float(pressure.max() / p0 - 1), "rms": rms,
            "max_inner": float(np.abs(pressure - exact)[inner].max() / p0)}
