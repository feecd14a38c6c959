"""The routes that build the Delassus matrix W, and the one ``"auto"`` takes: pure, no PETSc.

:mod:`~dolfinx_fretting.compliance` builds W by these routes; :mod:`~dolfinx_fretting.sizes` reads the same rule to
count the memory of the route a scene will take before anything is built (the Schur route keeps a second factor).
"""

from __future__ import annotations

__all__ = ["ROUTES", "METHODS", "AUTO_SCHUR_ROWS", "AUTO_SCHUR_DOFS_PER_ROW", "SCHUR_FACTOR_RATIO", "auto_route",
           "schur_preferred"]

#: Routes that build W.
ROUTES = ("columns", "block", "selected_inverse", "owned", "schur")
#: Accepted values of ``method``.
METHODS = ROUTES + ("auto",)

# Route chosen by "auto", from benchmarks/results/delassus.md: the selected inverse beats the block
# solve by 1.3-14x and the column solves by 8-81x in serial, on meshes of 1k-206k dofs. Under mpirun -n 2
# (benchmarks/results/delassus_owned_np2.md) each rank factorising K alone for its own columns beats the
# shared distributed selected inverse, even counting its extra factorisation.
_AUTO_SERIAL = "selected_inverse"
_AUTO_PARALLEL = "owned"
#: Serial "auto" builds W by the Schur complement route from this many rows of H (contacts x dimension) up ...
#: benchmarks/results/schur_setup.md, CPU time of W on the two-body sphere-flat, depth-graded mesh (28-40 dofs of
#: K per row of H): the selected inverse 2.3x / 1.5x faster at 747 / 1110 rows, the Schur route 1.3x / 1.9x
#: faster at 1536 / 2658 rows (the crossover ~1350 rows); from 1500, since near the crossover the selected inverse
#: needs less memory (the Schur route's own factor is 1.2-2.9x K's). Measured in 3D only.
AUTO_SCHUR_ROWS = 1500
#: ... and when K has at most this many dofs per row of H: on today's uniform sphere-flat mesh (123 dofs per row at
#: 1536 rows) the selected inverse is 1.8x faster than the Schur route (36 against 65 s CPU), on the graded mesh
#: (38 dofs per row, the same rows) 1.3x slower. Between the two, not measured: the bound is ~their geometric
#: mean (68).
AUTO_SCHUR_DOFS_PER_ROW = 70


#: The Schur route's own factor of [[K, H^T], [H, 0]] (MUMPS INFOG(22), alive beside K's while W is built) over K's
#: factor: measured 1.2-2.9 on the graded and uniform sphere meshes of 148-1915 contacts
#: (benchmarks/results/schur_setup.md, columns "MUMPS Schur" / "MUMPS K"); the envelope, as the size estimate's
#: factor model is.
SCHUR_FACTOR_RATIO = 3.0


def auto_route(comm_size: int, rows: int, dofs: int, schur_fits: bool = True) -> str:
    """The route ``"auto"`` takes for an H of ``rows`` rows and a K of ``dofs`` dofs on ``comm_size`` ranks.

    ``schur_fits``: the Schur route's second factor (:data:`SCHUR_FACTOR_RATIO` times K's) fits in the memory
    available; if not, the selected inverse, which needs no second factor (sphere-flat at a/10 for 10^5 cycles:
    estimated 20.7 GB by the Schur route, 9.8 GB by the selected inverse, on a 23 GB machine)."""
    if comm_size > 1:
        return _AUTO_PARALLEL
    if schur_preferred(rows, dofs) and schur_fits:
        return "schur"
    return _AUTO_SERIAL


def schur_preferred(rows: int, dofs: int) -> bool:
    """The serial size rule of :func:`auto_route` alone: the Schur route is the faster for this size."""
    return rows >= AUTO_SCHUR_ROWS and dofs <= AUTO_SCHUR_DOFS_PER_ROW * rows
