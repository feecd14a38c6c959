"""The pressure a user reads, recovered from the nodal contact forces (dolfinx_fretting.pressure; issue 23).

References: the P1 surface mass matrix against DOLFINx's own assembly of ``int phi_j q ds`` for fields q in the
space (exact); the smoothing against an independent quadrature on an irregular triangulation (the edge-midpoint
rule, exact for the quadratic ``phi_j x``); Hertz (Johnson, *Contact Mechanics*, 1985, §4.2) for a sphere's cap
in unstructured tetrahedra on a rigid plane and on an identical elastic flat (tests/support/tet_sphere.py);
Cattaneo-Mindlin (Johnson §7.2) for its shear; the uniform stress of two stacked boxes of tetrahedra (the contact
patch test, tests/support/tet_boxes.py).
"""

import numpy as np
import pytest
import scipy.spatial
from mpi4py import MPI

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting.pressure import check_surface_cells, smoothed_tractions, surface_mass  # noqa: E402

from dolfinx_fretting.analytic import cattaneo_mindlin_sphere_traction  # noqa: E402
from support.tet_boxes import stacked_boxes  # noqa: E402
from support.tet_sphere import E_STAR_PAIR, P, R, hertz_errors, pressed, tet_cap_problem  # noqa: E402


def _assembled(V, tags, field) -> np.ndarray:
    """``int phi_j field ds`` over the facets tagged 1, per node of V's scalar P1 space (DOLFINx's assembly)."""
    msh = V.mesh
    Q = dfx.scalar_space(msh, "Lagrange", 1)
    ds = ufl.Measure("ds", domain=msh, subdomain_data=tags)
    b = fem.petsc.assemble_vector(fem.form(field(ufl.SpatialCoordinate(msh)) * ufl.TestFunction(Q) * ds(1)))
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    imap = Q.dofmap.index_map
    values = np.zeros(imap.size_global)
    owned = b.array[:imap.size_local]
    values[imap.local_to_global(np.arange(imap.size_local, dtype=np.int32))] = owned
    b.destroy()
    return MPI.COMM_WORLD.allreduce(values, op=MPI.SUM)


@pytest.mark.parametrize("cell", ["tetrahedron", "hexahedron", "triangle"])
def test_surface_mass_matches_dolfinx_assembly(cell):
    """The contact's surface mass matrix M applied to the nodal values of fields in the P1 (Q1) space of the contact
    facets gives DOLFINx's assembled ``int phi_j q ds`` at every contact, to rounding (1e-13 of the largest): q = 1
    (the tributary measures), x and y (on the hexahedra's quadrilaterals, not parallelograms here, x and y are in
    Q1 and the area element varies: the 2 x 2 Gauss rule is exact). The bottom of a box (a square) on a rigid
    plane, its interior nodes moved so that the facets are irregular."""
    comm = MPI.COMM_WORLD
    if cell == "triangle":
        msh = mesh.create_unit_square(comm, 5, 4, mesh.CellType.triangle)
    else:
        msh = mesh.create_box(comm, [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]], [4, 3, 2], getattr(mesh.CellType, cell))
    gdim = msh.geometry.dim
    x = msh.geometry.x
    inner = np.all((x[:, :gdim] > 1e-9) & (x[:, :gdim] < 1 - 1e-9), axis=1) if gdim == 2 else \
        np.all((x[:, :2] > 1e-9) & (x[:, :2] < 1 - 1e-9), axis=1)
    # a smooth map of the unit square onto itself, the bottom kept flat (y = 0 in 2D, z = 0 in 3D)
    x[inner, 0] += 0.07 * np.sin(3 * x[inner, 0] + 2 * x[inner, 1 if gdim == 3 else 1])
    if gdim == 3:
        x[inner, 1] += 0.05 * np.cos(2 * x[inner, 0] + 3 * x[inner, 1])
    V = dfx.vector_space(msh, 1)
    normal_axis = gdim - 1
    bottom = mesh.locate_entities_boundary(msh, gdim - 1, lambda p: np.isclose(p[normal_axis], 0.0))
    tags = mesh.meshtags(msh, gdim - 1, np.sort(bottom), np.full(bottom.size, 1, dtype=np.int32))
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane(np.zeros(gdim), np.eye(gdim)[normal_axis]), mu=0.0,
                          pressure_recovery="smoothed")
    contact_set = contact.contact_set
    M = contact_set.surface_mass
    coords = contact_set.coords
    fields = [lambda p: 1.0 + 0 * p[0], lambda p: p[0]]
    values = [np.ones(contact_set.nc), coords[:, 0]]
    if gdim == 3:
        fields.append(lambda p: p[1])
        values.append(coords[:, 1])
    for field, nodal in zip(fields, values):
        exact = _assembled(V, tags, field)[contact_set.global_nodes]
        assert np.abs(M @ nodal - exact).max() <= 1e-13 * np.abs(exact).max()
    assert np.allclose(np.asarray(M.sum(axis=1)).ravel(), contact_set.tributary, rtol=1e-13)


def _irregular_patch(seed=5, n=7):
    """A flat irregular triangulation of [0, 1]^2 (a grid with its interior nodes moved, Delaunay)."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0, 1, n)
    points = np.array([(a, b) for a in s for b in s])
    inner = np.all((points > 0) & (points < 1), axis=1)
    points[inner] += rng.uniform(-0.3, 0.3, size=(inner.sum(), 2)) / (n - 1)
    triangles = scipy.spatial.Delaunay(points).simplices
    coords = np.column_stack([points, np.zeros(len(points))])
    faces = np.column_stack([triangles, np.full(len(triangles), -1)])
    return coords, faces


def test_smoothing_on_an_irregular_patch_against_a_quadrature():
    """On an irregular triangulation: one sweep of the smoothing maps the nodal values of a linear field q to
    ``int phi_j q / int phi_j`` (q at the hat function's centroid), computed here by the edge-midpoint rule (exact
    for the quadratic ``phi_j q``), to 1e-13; a uniform traction stays uniform to 1e-14 (the contact patch test);
    the M-weighted integral is kept; open nodes (r_n = 0) read 0; with a uniform mu, |shear| <= mu p holds after
    smoothing as before (positive weights)."""
    coords, faces = _irregular_patch()
    nc = len(coords)
    M = surface_mass(faces, coords, nc)
    tri = faces[:, :3]
    area = 0.5 * np.linalg.norm(np.cross(coords[tri[:, 1]] - coords[tri[:, 0]], coords[tri[:, 2]] - coords[tri[:, 0]]),
                                axis=1)
    q = lambda p: 2.0 + 3.0 * p[..., 0] - 1.5 * p[..., 1]  # noqa: E731
    moment, measure = np.zeros(nc), np.zeros(nc)
    for (i, j, k), A in zip(tri, area):
        mids = [(coords[i] + coords[j]) / 2, (coords[j] + coords[k]) / 2, (coords[k] + coords[i]) / 2]
        hats = {i: (0.5, 0.0, 0.5), j: (0.5, 0.5, 0.0), k: (0.0, 0.5, 0.5)}   # each hat at the three midpoints
        for node, phi in hats.items():
            moment[node] += A / 3 * sum(f * q(m) for f, m in zip(phi, mids))
            measure[node] += A / 3 * sum(phi)
    tributary = np.asarray(M.sum(axis=1)).ravel()
    assert np.allclose(tributary, measure, rtol=1e-13)
    forces = np.zeros((nc, 3))
    forces[:, 0] = q(coords) * tributary
    one_sweep = smoothed_tractions(forces, tributary, M, sweeps=1)[:, 0]
    assert np.abs(one_sweep - moment / measure).max() <= 1e-13 * np.abs(moment / measure).max()
    # the centroids differ from the nodes on this patch: the nodal values themselves are not reproduced
    assert np.abs(one_sweep - q(coords)).max() > 1e-3

    uniform = np.column_stack([3.0 * tributary, np.zeros((nc, 2))])
    assert np.abs(smoothed_tractions(uniform, tributary, M)[:, 0] / 3.0 - 1).max() <= 1e-14

    rng = np.random.default_rng(2)
    pressure = rng.uniform(0.5, 2.0, nc)
    pressure[:5] = 0.0                        # open contacts
    mu = 0.4
    shear = rng.normal(size=(nc, 2))
    shear *= (mu * pressure * rng.uniform(0, 1, nc) / np.linalg.norm(shear, axis=1))[:, None]
    forces = np.column_stack([pressure, shear]) * tributary[:, None]
    traction = smoothed_tractions(forces, tributary, M)
    loaded = pressure > 0
    assert np.all(traction[~loaded] == 0.0) and np.all(traction[loaded, 0] > 0)
    assert np.all(np.linalg.norm(traction[:, 1:], axis=1) <= mu * traction[:, 0] * (1 + 1e-14))
    block = M[np.flatnonzero(loaded)][:, np.flatnonzero(loaded)]
    kept = np.asarray(block.sum(axis=1)).ravel()
    assert (kept * traction[loaded, 0]).sum() == pytest.approx((kept * pressure[loaded]).sum(), rel=1e-14)


def test_pressure_recovery_is_checked_and_resolved():
    """``pressure_recovery``: a bad value refused before any work, naming the key, the value and the allowed ones;
    "auto" resolves to "smoothed" against a rigid plane on tetrahedra only (measured there), to "nodal" on
    hexahedra (within 0.1 % of Hertz: tests/test_sphere.py)."""
    msh = mesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 2, 2], mesh.CellType.tetrahedron)
    V = dfx.vector_space(msh, 1)
    bottom = mesh.locate_entities_boundary(msh, 2, lambda p: np.isclose(p[2], 0.0))
    tags = mesh.meshtags(msh, 2, np.sort(bottom), np.full(bottom.size, 1, dtype=np.int32))
    plane = dfr.RigidPlane([0, 0, 0], [0, 0, 1])
    with pytest.raises(ValueError, match=r"pressure_recovery = 'projected': allowed 'auto', 'nodal', 'smoothed'"):
        dfr.Contact(V, (tags, 1), plane, mu=0.0, pressure_recovery="projected")
    auto = dfr.Contact(V, (tags, 1), plane, mu=0.0)
    assert auto.pressure_recovery == "smoothed" and auto.contact_set.surface_mass is not None
    nodal = dfr.Contact(V, (tags, 1), plane, mu=0.0, pressure_recovery="nodal")
    assert nodal.pressure_recovery == "nodal" and nodal.contact_set.surface_mass is None
    assert auto.with_window(0.3).pressure_recovery == "smoothed"
    hexes = mesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 2, 2], mesh.CellType.hexahedron)
    V = dfx.vector_space(hexes, 1)
    bottom = mesh.locate_entities_boundary(hexes, 2, lambda p: np.isclose(p[2], 0.0))
    tags = mesh.meshtags(hexes, 2, np.sort(bottom), np.full(bottom.size, 1, dtype=np.int32))
    assert dfr.Contact(V, (tags, 1), plane, mu=0.0).pressure_recovery == "nodal"


@pytest.mark.parametrize("recovery", ["smoothed", "nodal"])
def test_a_mesh_of_mixed_facet_types_is_refused_naming_pressure_recovery(recovery):
    """Prisms (triangle and quadrilateral facets): refused by Contact before the surface is read, naming
    ``pressure_recovery``, its value, the facets found and those allowed (before: either recovery failed in
    DOLFINx's facet integrals (0.5.2: "Cell type prism not supported") or in its dof location (0.11: "Multiple
    entity types in mesh"), with no word of the key)."""
    prisms = mesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 2, 2], mesh.CellType.prism)
    V = dfx.vector_space(prisms, 1)
    prisms.topology.create_entities(2)
    # Which facets are tagged is not read (DOLFINx 0.11 cannot locate a prism mesh's boundary facets by a marker:
    # two facet types); the refusal comes first.
    facets = np.arange(4, dtype=np.int32)
    tags = mesh.meshtags(prisms, 2, facets, np.full(facets.size, 1, dtype=np.int32))
    with pytest.raises(ValueError, match=rf"pressure_recovery = '{recovery}' on a mesh of prism cells, whose facets "
                       r"are triangles and quadrilaterals: the contact surface must be of one facet type, segment, "
                       r"triangle, quadrilateral"):
        dfr.Contact(V, (tags, 1), dfr.RigidPlane([0, 0, 1], [0, 0, -1]), mu=0.3, pressure_recovery=recovery)


def test_surface_cells_allowed():
    """The cells whose facets the surface mass integrates pass; the others are refused by name."""
    for cell in ("triangle", "quadrilateral", "tetrahedron", "hexahedron"):
        check_surface_cells(cell, "smoothed")
    for cell, found in (("pyramid", "triangles and quadrilaterals"), ("interval", "points"),
                        ("polygon", "facets of an unknown type")):
        with pytest.raises(ValueError, match=f"pressure_recovery = 'auto' on a mesh of {cell} cells, whose "
                           f"facets are {found}"):
            check_surface_cells(cell, "auto")


def _both_recoveries(a_over_h, mesher):
    """The quarter cap pressed by P/4: Hertz errors of the smoothed pressure read (the default on tetrahedra) and of
    the nodal force over tributary area, from the same state."""
    problem, contact, a, p0, h = tet_cap_problem(a_over_h, mesher=mesher)
    assert contact.pressure_recovery == "smoothed"
    state = pressed(problem)
    fields = problem.contact_fields(state)
    contact_set = contact.contact_set
    nodal = state.forces[0::3] / contact_set.tributary
    errors = (hertz_errors(fields["coordinates"], fields["pressure"], a, p0),
              hertz_errors(contact_set.coords, nodal, a, p0))
    assert state.record["max_pressure"] == pytest.approx(fields["pressure"].max(), rel=1e-14)
    problem.destroy()
    return errors


def test_sphere_on_a_rigid_plane_in_tetrahedra_a_over_h_8():
    """a/h = 8 (11 k dofs, ~10 s): the smoothed pressure's peak within 2 % of p0 and its RMS error within 0.8a within
    2 % (measured -0.80 % and 1.55 %, benchmarks/results/tet_pressure.md), at most half the nodal one's RMS
    (6.1 %, measured)."""
    smoothed, nodal = _both_recoveries(8, "delaunay")
    assert abs(smoothed["peak"]) < 0.02 and smoothed["rms"] < 0.02
    assert smoothed["rms"] < 0.5 * nodal["rms"]


@pytest.mark.slow
@pytest.mark.parametrize("mesher", ["frontal-delaunay", "delaunay"])
def test_sphere_on_a_rigid_plane_in_tetrahedra_converges(mesher):
    """Issue 23: a/h = 12 and 16 (19 k and 32 k dofs, ~1 min): the pressure read, peak and RMS error within 0.8a,
    within 3 % of Hertz (the issue's target), the RMS falling with h. Measured (benchmarks/results/tet_pressure.md),
    frontal-Delaunay / Delaunay: peak -0.04 / +0.24 % (12), -0.06 / +0.37 % (16); RMS 0.72 / 0.96 % (12), 0.57 /
    0.86 % (16); the nodal force over area: peak +4.6 / +5.2 % (12), +5.7 / +4.0 % (16)."""
    coarse, _ = _both_recoveries(12, mesher)
    fine, _ = _both_recoveries(16, mesher)
    for errors in (coarse, fine):
        assert abs(errors["peak"]) < 0.03 and errors["rms"] < 0.03
    assert fine["rms"] < coarse["rms"]


def test_scene_key_reaches_the_outputs(tmp_path):
    """``contact.pressure_recovery`` in a scene: a bad value refused naming the key; "smoothed" on the 2D ``hertz``
    scene (rigid plane, quadrilaterals: "auto" is "nodal" there) changes the pressure written, profiles and
    ``max_pressure`` alike (the profile's peak is the summary's to the CSV's digits), and keeps it within 1 % of
    Hertz's p0 (Johnson eq. 4.43; measured -0.42 %, the smoothing's bias at the peak; nodal +0.16 %, held to 1 % in
    tests/test_hertz.py)."""
    import csv

    from dolfinx_fretting.analytic import hertz_line_contact
    from dolfinx_fretting.scenes import SceneError, load_scene
    from dolfinx_fretting.simulation import run_scene

    with pytest.raises(SceneError, match="contact.pressure_recovery"):
        load_scene("hertz", ["contact.pressure_recovery='projected'"])
    E, NU, R, P = 115000.0, 0.342, 6.0, 100.0   # the hertz scene's material and radius (tests/test_hertz.py)
    a, p0 = hertz_line_contact(P, R, E / (1 - NU**2))
    peaks = {}
    for recovery in ("auto", "smoothed"):
        scene = load_scene("hertz", ["contact.mu=0.0", f"loading.normal_force={P}", "loading.tangential_force=0.0",
                                     "loading.normal_increments=1", "output.xdmf=false", "output.plots=false",
                                     f"contact.pressure_recovery='{recovery}'"])
        summary = run_scene(scene, tmp_path / recovery, quiet=True)
        with open(tmp_path / recovery / "contact_profiles.csv") as f:
            rows = [r for r in csv.DictReader(f) if int(r["increment"]) == summary["increments"]]
        profile_peak = max(float(r["pressure"]) for r in rows)
        assert profile_peak == pytest.approx(summary["max_pressure"], rel=1e-6)   # CSV digits
        assert summary["max_pressure"] == pytest.approx(p0, rel=0.01)
        peaks[recovery] = summary["max_pressure"]
    assert abs(peaks["smoothed"] / peaks["auto"] - 1) > 1e-6


@pytest.mark.parametrize("formulation", ["node", "mortar"])
def test_auto_reads_the_smoothed_pressure_against_an_elastic_body_on_tetrahedra(formulation):
    """Two boxes of tetrahedra pressed together (uniaxial stress sigma, the contact patch test): "auto" resolves to
    "smoothed" against an ElasticBody on tetrahedra, node-to-face or mortar (measured on the sphere below and in
    benchmarks/results/tet_pressure.md), and reads, of the same contact forces:

    - matching faces (4 cells on 4): sigma at every contact to 1e-8 (the local tolerance 1e-10; a uniform traction
      stays uniform under the smoothing to 1e-14);
    - non-matching faces (6 on 4): mortar passes the patch test, the read sigma to 1e-8; node-to-face does
      not (its nodal force over area -32 % ... +13 %, tests/test_api.py), and the smoothed read is within 10 % of
      sigma at every contact (measured -8.1 % ... +3.3 %) with less than half the nodal spread (0.25 measured)."""
    for upper_cells in (4, 6):
        problem, state, sigma = stacked_boxes(upper_cells, formulation)
        contact = problem.contact
        assert contact.pressure_recovery == "smoothed" and contact.contact_set.surface_mass is not None
        read = problem.contact_fields(state)["pressure"] / sigma - 1
        nodal = state.forces[0::3] / contact.contact_set.tributary / sigma - 1
        if upper_cells == 4:
            assert np.abs(read).max() < 1e-8 and np.abs(nodal).max() < 1e-8, (read, nodal)
        elif formulation == "mortar":   # measured 1.1e-9 (the nodal values 9.2e-9: tests/test_mortar_3d.py's)
            assert np.abs(read).max() < 1e-8, read
        else:
            assert np.abs(nodal).max() > 0.2, nodal   # node-to-face fails the patch test (the contrast)
            assert np.abs(read).max() < 0.1, read
            assert np.ptp(read) < 0.5 * np.ptp(nodal), (read, nodal)
        problem.destroy()


def _on_the_flat(a_over_h, formulation):
    """The quarter cap on the identical flat (the flat's a/h the cap's, two gmsh triangulations: the faces do not
    match) pressed by P/4 with "auto": the Hertz errors (the pair's E*) of the smoothed read and of the nodal force
    over tributary measure of the same state."""
    problem, contact, a, p0, h = tet_cap_problem(a_over_h, flat_a_over_h=a_over_h, formulation=formulation)
    assert contact.pressure_recovery == "smoothed"
    state = pressed(problem)
    assert problem.total_force(state)[0] == pytest.approx(P / 4, rel=1e-8)   # force control (LocalSolver.force_tol)
    fields = problem.contact_fields(state)
    assert state.record["max_pressure"] == pytest.approx(fields["pressure"].max(), rel=1e-14)
    contact_set = contact.contact_set
    errors = (hertz_errors(contact_set.coords, fields["pressure"], a, p0),
              hertz_errors(contact_set.coords, state.forces[0::3] / contact_set.tributary, a, p0))
    problem.destroy()
    return errors


@pytest.mark.slow
@pytest.mark.parametrize("formulation", ["node", "mortar"])
def test_sphere_on_an_elastic_flat_in_tetrahedra(formulation):
    """Issue 23, two bodies: the quarter cap in gmsh tetrahedra on an identical flat in gmsh tetrahedra (non-matching
    faces), node-to-face and mortar, a/h = 8 and 12 (17 k and 33 k dofs; 10-16 s idle, ~1 min loaded). Hertz with the
    pair's E* (Johnson eqs 3.39, 4.22-4.23). Measured (frontal-Delaunay, benchmarks/results/tet_pressure.md, peak /
    RMS within 0.8a): node-to-face smoothed +0.01 / 2.16 % (8), -0.08 / 1.43 % (12), its nodal force over area
    +15.3 / 7.3 % and +13.1 / 4.8 %; mortar smoothed -1.00 / 1.21 % (8), -0.34 / 0.81 % (12), nodal +3.3 / 3.7 %
    and +3.3 / 2.9 %.
    Asserted: the smoothed read (the default) within 3 % of Hertz at the peak and in RMS at a/h = 12 (the issue's
    target) and within 2 % at the peak and 3 % in RMS at 8; its RMS falling with h and below half the nodal one's."""
    coarse, coarse_nodal = _on_the_flat(8, formulation)
    fine, fine_nodal = _on_the_flat(12, formulation)
    assert abs(coarse["peak"]) < 0.02 and coarse["rms"] < 0.03, coarse
    assert abs(fine["peak"]) < 0.03 and fine["rms"] < 0.03, fine
    assert fine["rms"] < coarse["rms"]
    for smoothed, nodal in ((coarse, coarse_nodal), (fine, fine_nodal)):
        assert smoothed["rms"] < 0.5 * nodal["rms"], (smoothed, nodal)


@pytest.mark.slow
def test_smoothed_shear_on_an_elastic_flat_in_tetrahedra():
    """Cattaneo-Mindlin on tetrahedra: the half cap (a roller on y = 0) on the identical flat, mortar, a/h = 8 (31 k
    dofs; 12 s idle, ~1 min loaded), mu = 0.5, P/2 then Q = 0.5 mu P/2 along x by force (identical bodies: Dundurs' beta
    = 0, Mindlin's traction the reference, ``analytic.cattaneo_mindlin_sphere_traction``). Measured (benchmarks/
    results/tet_pressure.md), the x traction's error over mu p0 within 0.8a, RMS / largest: smoothed 3.8 / 10.4 %,
    nodal 9.7 / 26.6 %; the smoothed peak sits 8.9 % of mu p0 under Mindlin's (the cusp at the stick radius
    averaged over its neighbours), the nodal one 6.2 % over it.
    Asserted: the tangential force to 1e-8 Q; the smoothed RMS within 6 % and below half the nodal one; Coulomb's
    |shear| <= mu p at every loaded node after smoothing (to 1e-12: the same positive weights on shear and
    pressure) as before it."""
    mu, phi = 0.5, 0.5
    problem, contact, a, p0, h = tet_cap_problem(8, flat_a_over_h=8, formulation="mortar", half=True, mu=mu)
    assert contact.pressure_recovery == "smoothed"
    state = pressed(problem, share=0.5)
    Q = phi * mu * P
    for fraction in (0.5, 1.0):
        state = problem.commit(state, problem.solve(
            state, tangential=(dfr.Force(fraction * Q / 2), dfr.Displacement(0.0))))
    assert problem.total_force(state)[1] == pytest.approx(Q / 2, rel=1e-8)
    contact_set = contact.contact_set
    fields = problem.contact_fields(state)
    local = {"smoothed": np.column_stack([fields["pressure"], fields["shear"]]),
             "nodal": state.forces.reshape(-1, 3) / contact_set.tributary[:, None]}
    r = np.linalg.norm(contact_set.coords[:, :2], axis=1)
    expected = cattaneo_mindlin_sphere_traction(r, Q, mu, P, R, E_STAR_PAIR)
    inner = r < 0.8 * a
    rms = {}
    for name, traction in local.items():
        loaded = traction[:, 0] > 0
        assert np.all(np.linalg.norm(traction[loaded, 1:], axis=1) <= mu * traction[loaded, 0] * (1 + 1e-12)), name
        along_x = np.einsum("ik,ik->i", traction, contact_set.frames[:, :, 0])
        rms[name] = np.sqrt(np.mean(((along_x - expected) / (mu * p0))[inner] ** 2))
    assert rms["smoothed"] < 0.06 and rms["smoothed"] < 0.5 * rms["nodal"], rms
    problem.destroy()
