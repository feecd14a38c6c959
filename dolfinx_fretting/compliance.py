"""The Delassus (compliance) matrix W = H K^-1 H^T from one MUMPS factorisation of K.

K is factorised once (symbolic + numeric) by a ``preonly`` KSP with MUMPS; the factor then serves plain
solves ``K x = b`` and the construction of the small dense W by one of three routes:

``"columns"``
    One KSP solve per row h_i of H (y = K^-1 h_i), keeping only the entries at the dofs S touched by H:
    ``W[:, i] = H[:, S] y_S``. Simple, but each solve re-reads the whole factor.
``"block"``
    The same solves as one MUMPS multiple right-hand-side call (``MatMatSolve``) on a sparse RHS
    (``H^T``, given to PETSc as a transpose-wrapped AIJ matrix), in chunks that bound the dense
    solution block to ``block_memory_mb``.
``"selected_inverse"``
    MUMPS computes only the entries (K^-1)_{SS} (ICNTL(30), PETSc's ``MatMumpsGetInverse``, which
    petsc4py 3.18 does not wrap and which is therefore called through ctypes), and
    ``W = H[:, S] (K^-1)_{SS} H[:, S]^T``. Fastest by far (see ``benchmarks/results/delassus.md``).

``"owned"``
    For MPI: every rank gathers the whole K (``MatCreateSubMatrices``), factorises it alone (MUMPS on
    COMM_SELF, all ranks at once) and computes by entries of the inverse only the columns
    W[:, J] = H_S (K^-1)_{S, S_J} H_J^T of its share J of the rows of H; the columns are sent to rank 0, which
    broadcasts the whole W.
    No solve is shared between ranks; each rank holds a whole factor of K (memory x ranks). The
    distributed factor is still the one used for the displacement solves.

``"schur"``
    Serial only. A second MUMPS factorisation, of the saddle-point matrix A = [[K, H^T], [H, 0]] told to keep
    H's m rows for last (PETSc's ``MatFactorSetSchurIS``, MUMPS ICNTL(19); not wrapped by petsc4py 3.18 or 3.25,
    so through ctypes): MUMPS eliminates the K block only (SPD, so LDL^T without pivoting holds) and returns the
    dense Schur complement of A on those rows, 0 - H K^-1 H^T = -W, W itself whatever number of dofs each row of
    H touches (two bodies: both surfaces' nodes). No entries of the inverse, no dense factorisation. The
    factorisation is freed after the build while K has never been refactorised (an elastic body: a new H needs a
    new factor anyway), and kept from K's first :meth:`DelassusOperator.refactorize` on for later builds with the
    same H (a numeric refactorisation of the K block's new values: an elastic-plastic tangent). PETSc has no
    distributed Schur complement for MUMPS: under MPI the route is refused when the operator is made. Measured in
    ``benchmarks/results/schur_setup.md``.

``"auto"`` picks, serially, ``"schur"`` for an H of at least
:data:`~dolfinx_fretting.delassus_routes.AUTO_SCHUR_ROWS` rows on a K of at most
:data:`~dolfinx_fretting.delassus_routes.AUTO_SCHUR_DOFS_PER_ROW` dofs per row, where the Schur route's second factor
fits in the memory available then (K's factored), and ``"selected_inverse"`` otherwise (the measured crossover:
``benchmarks/results/schur_setup.md``; ``stats["auto_schur_skipped_for_memory"]`` says when memory decided), and
``"owned"`` under MPI
(``benchmarks/results/delassus.md``, ``benchmarks/results/delassus_owned_np2.md``).

Dirichlet conditions: DOLFINx assembles K with the constrained rows and columns zeroed and 1 on the
diagonal, so (K^-1)_{dd} = 1 at a constrained dof d, in the wrong units and unrelated to the mechanics.
H must therefore never touch a constrained dof; :func:`check_no_constrained_dofs` verifies it.

Dof numbering: H's columns are global PETSc indices of K (for a DOLFINx vector space with block size
bs: ``bs * global_node + component``), and H is replicated identically on every rank.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import os
import time
from contextlib import contextmanager
from typing import Iterator

import numpy as np
import petsc4py
import scipy.linalg as sla
import scipy.sparse as sp
from mpi4py import MPI
from petsc4py import PETSc

from .delassus_routes import _AUTO_PARALLEL, METHODS, ROUTES, SCHUR_FACTOR_RATIO, auto_route, schur_preferred
from .memory import available_memory

# the routes and "auto"'s rule are declared in delassus_routes (pure, read by sizes too)
__all__ = ["DelassusOperator", "DelassusError", "check_no_constrained_dofs"]

#: The largest message W's transfers send, in doubles (512 MiB): MPI counts are C ints, so a dense W of more than
#: 2^31 - 1 entries (m > 46 340 rows, ~15 400 3D contacts) cannot go in one message.
MPI_CHUNK = 2**26


def bcast_in_chunks(comm: MPI.Comm, array: np.ndarray) -> None:
    """Broadcast a C-contiguous float64 array from rank 0 in place, in messages of at most :data:`MPI_CHUNK`."""
    flat = array.reshape(-1)  # a view (C-contiguous): received in place
    for offset in range(0, flat.size, MPI_CHUNK):
        comm.Bcast(flat[offset:offset + MPI_CHUNK], root=0)


# MUMPS INFOG(1) codes worth a sentence of their own.
_MUMPS_HINTS = {
    -5: "not enough memory during analysis",
    -6: "K is structurally singular",
    -8: "integer workspace too small (raise mat_mumps_icntl_14)",
    -9: "real workspace too small (raise mat_mumps_icntl_14)",
    -10: "K is numerically singular: are enough Dirichlet conditions applied to remove rigid-body modes?",
    -13: "memory allocation failed",
    -47: "entries of the inverse requested with an incompatible solve setting (ICNTL(30))",
}


class DelassusError(RuntimeError):
    """A PETSc or MUMPS failure while factorising K or building W."""


def _check_route_fits(route: str, comm: MPI.Comm) -> None:
    """Refuse, before any work, a route that cannot run on ``comm``."""
    if route == "schur" and comm.size > 1:
        raise ValueError(f"delassus_method = 'schur' runs serially only (this run has {comm.size} MPI ranks): "
                         "PETSc's MUMPS interface computes no distributed Schur complement; use 'owned', "
                         "'selected_inverse' or 'auto' under MPI")


def check_no_constrained_dofs(H: sp.spmatrix, bc_dofs_global: np.ndarray) -> None:
    """Raise if H touches a Dirichlet-constrained dof of K.

    K assembled by DOLFINx carries an identity row and column at each constrained dof, so such a column
    of H would add a meaningless unit compliance to W.

    Args:
        H: Sparse (m, N) contact operator in global PETSc dof numbering.
        bc_dofs_global: Global PETSc indices of the constrained dofs (for a blocked DOLFINx space,
            ``bs * global_node + component``). Pass the union over ranks to check every dof.

    Raises:
        ValueError: Naming the offending dofs and the rows of H that touch them.
    """
    H = sp.csr_matrix(H)
    bc = np.unique(np.asarray(bc_dofs_global, dtype=np.int64).ravel())
    coo = H.tocoo()
    nonzero = coo.data != 0
    rows, cols = coo.row[nonzero], coo.col[nonzero]
    bad = np.isin(cols, bc)
    if bad.any():
        dofs = np.unique(cols[bad])
        hrows = np.unique(rows[bad])
        shown = ", ".join(str(d) for d in dofs[:20]) + (", ..." if dofs.size > 20 else "")
        raise ValueError(f"H touches {dofs.size} Dirichlet-constrained dof(s) of K (global dofs {shown}; "
                         f"rows of H {hrows[:20].tolist()}): K has identity rows there, so W would be "
                         "meaningless; exclude constrained nodes from the contact candidates")


# ------------------------------------------------------------------------------------------------------
# PETSc C API through ctypes (MatMumpsGetInverse is not wrapped by petsc4py 3.18)
# ------------------------------------------------------------------------------------------------------
def _loaded_petsc_paths() -> list[str]:
    """Paths of libpetsc objects already mapped into this process (Linux), best match first."""
    paths: list[str] = []
    try:
        with open("/proc/self/maps") as maps:
            for line in maps:
                path = line.split()[-1] if line.strip() else ""
                name = os.path.basename(path)
                if name.startswith("libpetsc") and ".so" in name and path not in paths:
                    paths.append(path)
    except OSError:
        pass
    return paths


@functools.lru_cache(maxsize=None)
def _petsc_c_api() -> ctypes.CDLL:
    """The libpetsc that petsc4py uses, with the prototypes we call.

    The petsc4py extension module is tried first: dlopen returns the already-loaded module and symbol
    lookup through its handle reaches the very libpetsc it is linked against (a second copy of PETSc
    would have its own global state). Then the libpetsc already mapped into the process, then the
    library of petsc4py's configuration.
    """
    candidates = [PETSc.__file__, *_loaded_petsc_paths()]
    try:
        cfg = petsc4py.get_config()
        libdir = os.path.join(cfg["PETSC_DIR"], cfg.get("PETSC_ARCH") or "", "lib")
        if os.path.isdir(libdir):
            candidates += sorted(os.path.join(libdir, f) for f in os.listdir(libdir)
                                 if f.startswith("libpetsc") and ".so" in f)
    except Exception:  # noqa: BLE001 - configuration lookup is best effort
        pass
    for name in ("petsc_real", "petsc"):
        found = ctypes.util.find_library(name)
        if found:
            candidates.append(found)
    tried = []
    for path in candidates:
        try:
            lib = ctypes.CDLL(path)
        except OSError as exc:
            tried.append(f"{path} ({exc})")
            continue
        if hasattr(lib, "MatMumpsGetInverse"):
            lib.MatMumpsGetInverse.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
            lib.MatMumpsGetInverse.restype = ctypes.c_int
            # The Schur complement route (PetscInt is 32-bit in both tested PETSc builds: checked below).
            pint = ctypes.POINTER(_PETSC_INT)
            for name, args in (("MatFactorSetSchurIS", [ctypes.c_void_p, ctypes.c_void_p]),
                               ("MatFactorCreateSchurComplement",
                                [ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p), ctypes.POINTER(ctypes.c_int)]),
                               ("MatGetSize", [ctypes.c_void_p, pint, pint]),
                               ("MatDenseGetLDA", [ctypes.c_void_p, pint]),
                               ("MatDenseGetArrayRead",
                                [ctypes.c_void_p, ctypes.POINTER(ctypes.POINTER(ctypes.c_double))]),
                               ("MatDenseRestoreArrayRead",
                                [ctypes.c_void_p, ctypes.POINTER(ctypes.POINTER(ctypes.c_double))]),
                               ("MatDestroy", [ctypes.POINTER(ctypes.c_void_p)])):
                if hasattr(lib, name):
                    getattr(lib, name).argtypes = args
                    getattr(lib, name).restype = ctypes.c_int
            return lib
        tried.append(f"{path} (no MatMumpsGetInverse)")
    raise DelassusError("cannot find MatMumpsGetInverse in the PETSc library used by petsc4py; tried: "
                        + "; ".join(tried))


#: PETSc's PetscInt as a ctypes type (32 or 64 bits, as petsc4py was built).
_PETSC_INT = ctypes.c_int64 if np.dtype(PETSc.IntType).itemsize == 8 else ctypes.c_int32


def _petsc_error_text(ierr: int) -> str:
    try:
        return str(PETSc.Error(ierr))
    except Exception:  # noqa: BLE001 - the code alone is still informative
        return f"error code {ierr}"


# ------------------------------------------------------------------------------------------------------
class DelassusOperator:
    """Factorisation of K (MUMPS through a ``preonly`` KSP) and the Delassus matrix W = H K^-1 H^T.

    All methods except :meth:`destroy` and the attributes are collective on ``comm``.

    The factorisation defaults to MUMPS Cholesky with K flagged symmetric positive definite (MUMPS
    SYM=1, LDL^T without pivoting): for our elasticity K it is about as fast to factorise as LU, and
    each solve reads half the factor. ``petsc_options`` override it DOLFINx-style (keys without the
    prefix, e.g. ``{"pc_type": "lu"}`` or ``{"mat_mumps_icntl_14": 50}``); they are set under
    ``options_prefix`` only while the KSP reads them and removed from the global options database after.

    Args:
        K: Assembled stiffness matrix (symmetric; SPD once Dirichlet conditions are applied).
        comm: Communicator of K (default: K's).
        method: Route for :meth:`build`: ``"columns"``, ``"block"``, ``"selected_inverse"``, ``"owned"``,
            ``"schur"`` (serial only) or ``"auto"`` (by :func:`~dolfinx_fretting.delassus_routes.auto_route` for
            each H).
        petsc_options: Options for the KSP/PC/MUMPS (without the prefix).
        options_prefix: Options prefix of the KSP.
        spd: Declare K SPD so that Cholesky uses MUMPS SYM=1 (set False for a symmetric indefinite K:
            SYM=2, with pivoting).
        block_memory_mb: Bound on the dense solution block of the ``"block"`` route (per call; the RHS
            columns are processed in chunks that fit).
        symmetrize: Return (W + W^T)/2 (the raw asymmetry is recorded in ``stats``).

    Attributes:
        method: The route of :meth:`build`: as given, except ``"auto"`` under MPI, resolved to ``"owned"``
            (serially ``"auto"`` stays: the route depends on H's size and the memory available;
            ``stats["last_build_route"]`` says which).
        factorization: ``"cholesky"`` or ``"lu"`` (after options).
        last_build_time: Wall time (s) of the last :meth:`build`.
        last_factorize_time: Wall time (s) of the last :meth:`factorize` or :meth:`refactorize`.
        stats: Counters and timings (factorisations, solves, MUMPS memory, asymmetry of the last W).
    """

    def __init__(self, K: PETSc.Mat, comm: MPI.Comm | None = None, method: str = "auto",
                 petsc_options: dict | None = None,
                 options_prefix: str = "dolfinx_fretting_delassus_", *, spd: bool = True,
                 block_memory_mb: float = 256.0, symmetrize: bool = True):
        if method not in METHODS:
            raise ValueError(f"unknown Delassus method {method!r}; choose one of {', '.join(METHODS)}")
        self.K = K
        self.comm: MPI.Comm = comm if comm is not None else K.getComm().tompi4py()
        if self.comm.size != K.getComm().getSize():
            raise ValueError("comm must be the communicator of K")
        self.requested_method = method
        _check_route_fits(method, self.comm)
        if method == "auto" and self.comm.size > 1:
            method = _AUTO_PARALLEL
        self.method: str = method
        self.petsc_options = dict(petsc_options or {})
        self.options_prefix = options_prefix
        self.spd = spd
        self.block_memory_mb = float(block_memory_mb)
        self.symmetrize = symmetrize
        self.factorization: str | None = None
        self.ksp: PETSc.KSP | None = None
        #: Dofs kept for last in the factorisation (the "schur" route's own operator), else None.
        self._schur_dofs: np.ndarray | None = None
        self.last_build_time = 0.0
        self.last_factorize_time = 0.0
        self.stats: dict[str, float | int | str] = {
            "factorizations": 0, "refactorizations": 0, "solves": 0, "builds": 0,
            "factorize_time": 0.0, "refactorize_time": 0.0, "last_build_time": 0.0,
        }

    # Options ------------------------------------------------------------------------------------------
    @contextmanager
    def _options(self) -> Iterator[None]:
        """User options in the global database under our prefix, only while PETSc reads them."""
        opts = PETSc.Options()
        opts.prefixPush(self.options_prefix)
        try:
            for key, value in self.petsc_options.items():
                opts[key] = value
        finally:
            opts.prefixPop()
        try:
            yield
        finally:
            for key in self.petsc_options:
                name = self.options_prefix + key
                if opts.hasName(name):
                    opts.delValue(name)

    # Factorisation ------------------------------------------------------------------------------------
    @property
    def factor(self) -> PETSc.Mat:
        """The MUMPS factor matrix F (after :meth:`factorize`)."""
        self._require_factor()
        return self.ksp.getPC().getFactorMatrix()

    def _require_factor(self) -> None:
        if self.ksp is None:
            raise DelassusError("K is not factorised: call factorize() first")

    def factorize(self) -> None:
        """Symbolic and numeric factorisation of K (a fresh KSP; any previous factor is dropped)."""
        t0 = time.perf_counter()
        cpu0 = time.process_time()
        self._drop_own_factor()
        if self.ksp is not None:
            self.ksp.destroy()
        ksp = PETSc.KSP().create(self.K.getComm())
        ksp.setOperators(self.K)
        ksp.setOptionsPrefix(self.options_prefix)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("mumps")
        ksp.setErrorIfNotConverged(True)
        with self._options():
            ksp.setFromOptions()
            ptype = pc.getType()
            if ptype not in ("cholesky", "lu"):
                raise ValueError(f"pc_type {ptype!r}: the Delassus operator needs a direct factorisation "
                                 "(cholesky or lu) with MUMPS")
            if pc.getFactorSolverType() != "mumps":
                raise ValueError(f"pc_factor_mat_solver_type {pc.getFactorSolverType()!r}: MUMPS is "
                                 "required (multiple right-hand sides, entries of the inverse)")
            if ptype == "cholesky" and self.spd:
                # MUMPS reads the flag when the factor is created: SYM=1 (no pivoting) instead of SYM=2.
                self.K.setOption(PETSc.Mat.Option.SPD, True)
            pc.setFactorSetUpSolverType()  # creates F so that MUMPS reads the prefixed options
            if self._schur_dofs is not None:
                self._set_schur_dofs(pc.getFactorMatrix())
            # A failed factorisation must not leave a PC that silently returns Inf.
            pc.setReusePreconditioner(True)
            self.ksp = ksp
            self._setup("factorize")
        self.factorization = ptype
        self.last_factorize_time = time.perf_counter() - t0
        self.stats["factorizations"] += 1
        self.stats["factorize_time"] = self.last_factorize_time
        # CPU time of this process (MUMPS on one thread): on a shared machine less sensitive than the wall time
        self.stats["factorize_cpu_time"] = time.process_time() - cpu0

    def refactorize(self) -> None:
        """Numeric-only refactorisation after K's values changed (same sparsity pattern).

        Raises:
            DelassusError: if :meth:`factorize` was not called, or MUMPS fails.
        """
        self._require_factor()
        t0 = time.perf_counter()
        self._own_stale = True  # K's values changed: the "owned" route refreshes its copy when next used
        self._schur_stale = True  # and so does the "schur" route its factor
        pc = self.ksp.getPC()
        # Reuse is on so that solves never refactorise behind the caller's back; lift it for this call.
        # KSPSetUp alone returns at once on a set-up KSP: setOperators marks the operator changed, and
        # PCSetUp then sees the same nonzero pattern and runs the numeric phase only.
        pc.setReusePreconditioner(False)
        try:
            self.ksp.setOperators(self.K)
            try:
                pc.setUp()
            except PETSc.Error as exc:
                raise DelassusError(f"MUMPS refactorize failed: {self._mumps_status()} ({exc})") from exc
            self._setup("refactorize")
        finally:
            pc.setReusePreconditioner(True)
        self.last_factorize_time = time.perf_counter() - t0
        self.stats["refactorizations"] += 1
        self.stats["refactorize_time"] = self.last_factorize_time

    def _setup(self, what: str) -> None:
        try:
            self.ksp.setUp()
        except PETSc.Error as exc:
            raise DelassusError(f"MUMPS {what} failed: {self._mumps_status()} ({exc})") from exc
        infog1 = self.factor.getMumpsInfog(1)
        if infog1 < 0:  # INFOG is global: every rank raises together
            raise DelassusError(f"MUMPS {what} failed: {self._mumps_status()}")
        F = self.factor
        # INFOG(29): entries in the factors (negative: millions); INFOG(22): total MB used.
        nz = F.getMumpsInfog(29)
        self.stats["factor_entries"] = nz if nz >= 0 else -nz * 1_000_000
        self.stats["mumps_memory_mb"] = F.getMumpsInfog(22)

    def _schur_factor_fits(self) -> bool:
        """The Schur route's second factor, :data:`~dolfinx_fretting.delassus_routes.SCHUR_FACTOR_RATIO` times K's
        (MUMPS INFOG(22), K's factor already resident), fits in the memory available now (unknown: it fits, as
        :func:`~dolfinx_fretting.sizes.check_size` lets a run through)."""
        available, _ = available_memory()
        need = SCHUR_FACTOR_RATIO * self.stats.get("mumps_memory_mb", 0) * 2**20
        return available <= 0 or need <= available

    def _mumps_status(self) -> str:
        try:
            F = self.ksp.getPC().getFactorMatrix()
            g1, g2 = F.getMumpsInfog(1), F.getMumpsInfog(2)
        except PETSc.Error:
            return "no MUMPS factor"
        hint = _MUMPS_HINTS.get(g1, "")
        return f"INFOG(1)={g1}, INFOG(2)={g2}" + (f": {hint}" if hint else "")

    # Solves -------------------------------------------------------------------------------------------
    def solve(self, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """Solve K x = b with the existing factor (no refactorisation, even if K changed)."""
        self._require_factor()
        try:
            self.ksp.solve(b, x)
        except PETSc.Error as exc:
            raise DelassusError(f"MUMPS solve failed: {self._mumps_status()} ({exc})") from exc
        self.stats["solves"] += 1

    def solve_many(self, rhs: np.ndarray) -> np.ndarray:
        """Solve K X = B for k right-hand sides at once with the existing factor: one multiple right-hand-side
        call (``MatMatSolve``; MUMPS solves the k columns in one pass over the factors). Collective.

        Args:
            rhs: (n_owned, k) this rank's rows of B (its rows of K, ``K.getOwnershipRange``).

        Returns:
            (n_owned, k) this rank's rows of X.

        Raises:
            DelassusError: on a PETSc/MUMPS failure.
        """
        self._require_factor()
        rhs = np.asarray(rhs, dtype=PETSc.ScalarType)
        comm_p = self.K.getComm()
        nloc, N = self.K.getLocalSize()[0], self.K.getSize()[0]
        if rhs.ndim != 2 or rhs.shape[0] != nloc:
            raise ValueError(f"solve_many: rhs of shape {rhs.shape}: expected ({nloc}, k), this rank's rows of K")
        k = rhs.shape[1]
        B = PETSc.Mat().createDense(size=((nloc, N), (None, k)), comm=comm_p)
        X = PETSc.Mat().createDense(size=((nloc, N), (None, k)), comm=comm_p)
        try:
            B.setUp()
            X.setUp()
            B.getDenseArray()[:] = rhs   # (n_owned, k): every column's owned rows
            B.assemble()
            self.factor.matSolve(B, X)
            solution = X.getDenseArray().copy()
        except PETSc.Error as exc:
            raise DelassusError(f"MUMPS multiple-RHS solve failed: {self._mumps_status()} ({exc})") from exc
        finally:
            B.destroy()
            X.destroy()
        self.stats["solves"] += k
        return solution

    # W ------------------------------------------------------------------------------------------------
    def build(self, H: sp.spmatrix, method: str | None = None) -> np.ndarray:
        """Dense W = H K^-1 H^T, identical on every rank. Collective.

        Args:
            H: Sparse (m, N) contact operator in global PETSc dof numbering, identical on every rank;
                it must not touch Dirichlet-constrained dofs (see :func:`check_no_constrained_dofs`).
            method: Route for this call only (default: ``self.method``).

        Returns:
            W, shape (m, m), float64, symmetric if ``symmetrize``.

        Raises:
            ValueError: if H has the wrong number of columns.
            DelassusError: on a PETSc/MUMPS failure.
        """
        self._require_factor()
        route = self.method if method is None else method
        if route == "auto":  # H is replicated: the same rows on every rank (and serial for the memory reading)
            rows, dofs = H.shape[0], self.K.getSize()[0]
            fits = self.comm.size > 1 or not schur_preferred(rows, dofs) or self._schur_factor_fits()
            route = auto_route(self.comm.size, rows, dofs, fits)
            self.stats["auto_schur_skipped_for_memory"] = not fits
        if route not in ROUTES:
            raise ValueError(f"unknown Delassus route {route!r}; choose one of {', '.join(METHODS)}")
        _check_route_fits(route, self.comm)
        H = sp.csr_matrix(H, dtype=np.float64)
        N = self.K.getSize()[1]
        if H.shape[1] != N:
            raise ValueError(f"H has {H.shape[1]} columns, K has {N} (global) dofs")
        H.eliminate_zeros()
        t0, cpu0 = time.perf_counter(), time.process_time()
        m = H.shape[0]
        S = np.unique(H.indices).astype(np.int64)  # the few dofs touched by H
        if m == 0 or S.size == 0:
            W = np.zeros((m, m))
        else:
            HS = H[:, S].tocsr()
            if route == "selected_inverse":
                W = self._build_selected_inverse(HS, S)
            elif route == "owned":
                W = self._build_owned(H, HS, S)
            elif route == "schur":
                W = self._build_schur(H)
            else:
                Y = self._solve_columns(H, S) if route == "columns" else self._solve_block(H, S)
                W = HS @ Y if self.comm.rank == 0 else None
            W = self._finish(W, m)
        self.last_build_time = time.perf_counter() - t0
        self.stats["builds"] += 1
        self.stats["last_build_time"] = self.last_build_time
        self.stats["last_build_cpu_time"] = time.process_time() - cpu0
        self.stats["last_build_route"] = route
        return W

    def coupling(self, H_rows: sp.spmatrix, H_cols: sp.spmatrix) -> np.ndarray:
        """The dense block ``H_rows K^-1 H_cols^T`` (e.g. the contacts' forces seen at other nodes), identical on
        every rank. Collective.

        Whatever the route of W, the block is formed from entries of the inverse,
        ``H_rows[:, R] (K^-1)_{R, C} H_cols[:, C]^T`` with R and C the dofs each touches (ICNTL(30), as the
        ``"selected_inverse"`` route): MUMPS solves one sparse right-hand side per requested column, so the
        smaller of R and C is requested as columns (K^-1 is symmetric). Under MPI with the ``"owned"`` route,
        rank 0 takes the entries from its own whole factor (no shared solve), else from the distributed one.
        Neither H may touch a Dirichlet-constrained dof (as for :meth:`build`).
        """
        self._require_factor()
        H_rows, H_cols = (sp.csr_matrix(H, dtype=np.float64) for H in (H_rows, H_cols))
        for H in (H_rows, H_cols):
            H.eliminate_zeros()
        t0 = time.perf_counter()
        R = np.unique(H_rows.indices).astype(np.int64)
        C = np.unique(H_cols.indices).astype(np.int64)
        out = np.zeros((H_rows.shape[0], H_cols.shape[0]))
        if R.size and C.size:
            # _inverse_entries(rows, columns) solves for the columns and returns (K^-1)_{columns, rows}
            # (symmetry): the smaller set is requested as the columns.
            large, small = (R, C) if C.size <= R.size else (C, R)
            if self.method == "owned" and self.comm.size > 1:
                own = self._own_factor()
                inv = own._inverse_entries(large, small) if self.comm.rank == 0 else None
            else:
                inv = self._inverse_entries(large, small)
            if self.comm.rank == 0:
                X = inv if small is R else inv.T     # (|R|, |C|) = (K^-1)_{R, C}
                out[...] = H_rows[:, R] @ (H_cols[:, C] @ X.T).T
        bcast_in_chunks(self.comm, out)
        self.stats["last_coupling_time"] = time.perf_counter() - t0
        return out

    def _finish(self, W: np.ndarray | None, m: int) -> np.ndarray:
        """Symmetrise on rank 0 and broadcast: bitwise identical W on every rank."""
        out = np.empty((m, m), dtype=np.float64)
        if self.comm.rank == 0:
            W = np.asarray(W, dtype=np.float64)
            scale = np.abs(W).max() or 1.0
            self.stats["asymmetry"] = float(np.abs(W - W.T).max() / scale)
            out[...] = 0.5 * (W + W.T) if self.symmetrize else W
        bcast_in_chunks(self.comm, out)
        self.stats["asymmetry"] = self.comm.bcast(self.stats.get("asymmetry"), root=0)
        return out

    def _owned(self, S: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
        """(rstart, positions in S, local indices) of the entries of S owned by this rank."""
        rstart, rend = self.K.getOwnershipRange()
        pos = np.flatnonzero((S >= rstart) & (S < rend))
        return rstart, pos, (S[pos] - rstart).astype(np.int64)

    def _gather_rows(self, S: np.ndarray, pos: np.ndarray, local_rows: np.ndarray) -> np.ndarray | None:
        """Assemble Y_S (|S|, m) on rank 0 from each rank's owned rows."""
        parts = self.comm.gather((pos, local_rows), root=0)
        if self.comm.rank != 0:
            return None
        Y = np.empty((S.size, local_rows.shape[1]))
        for p, rows in parts:
            Y[p] = rows
        return Y

    def _solve_columns(self, H: sp.csr_matrix, S: np.ndarray) -> np.ndarray | None:
        """Y_S = (K^-1 H^T)_S by one KSP solve per row of H."""
        rstart, pos, loc = self._owned(S)
        rend = self.K.getOwnershipRange()[1]
        Hown = H[:, rstart:rend].tocsr()  # the owned part of each right-hand side
        m = H.shape[0]
        b, x = self.K.createVecs()
        Yloc = np.empty((pos.size, m))
        try:
            barr = b.getArray()
            for i in range(m):
                barr[:] = 0.0
                start, stop = Hown.indptr[i], Hown.indptr[i + 1]
                barr[Hown.indices[start:stop]] = Hown.data[start:stop]
                self.solve(b, x)
                Yloc[:, i] = x.getArray(readonly=True)[loc]
        finally:
            b.destroy()
            x.destroy()
        return self._gather_rows(S, pos, Yloc)

    def _solve_block(self, H: sp.csr_matrix, S: np.ndarray) -> np.ndarray | None:
        """Y_S = (K^-1 H^T)_S by MUMPS multiple sparse right-hand sides, in memory-bounded chunks."""
        F = self.factor
        comm_p = self.K.getComm()
        rank0 = self.comm.rank == 0
        N = self.K.getSize()[0]
        nloc = self.K.getLocalSize()[0]
        m = H.shape[0]
        rstart, pos, loc = self._owned(S)
        chunk = int(max(1, min(m, self.block_memory_mb * 2**20 // (8 * max(N, 1)))))
        self.stats["block_chunk"] = chunk
        Yloc = np.empty((pos.size, m))
        for c0 in range(0, m, chunk):
            c1 = min(m, c0 + chunk)
            k = c1 - c0
            # MUMPS takes a centralised sparse RHS from the host's diagonal block: rank 0 owns every
            # row and column of Bt = H[c0:c1] (rows = right-hand sides, columns = dofs).
            Hc = H[c0:c1].sorted_indices() if rank0 else sp.csr_matrix((0, N))
            Bt = PETSc.Mat().createAIJ(size=((Hc.shape[0], k), (N if rank0 else 0, N)),
                                       csr=(Hc.indptr.astype(PETSc.IntType), Hc.indices.astype(PETSc.IntType),
                                            Hc.data.astype(PETSc.ScalarType)), comm=comm_p)
            Bt.assemble()
            B = PETSc.Mat().createTranspose(Bt)
            X = PETSc.Mat().createDense(size=((nloc, N), (None, k)), comm=comm_p)
            X.setUp()
            try:
                F.matSolve(B, X)
                Yloc[:, c0:c1] = X.getDenseArray()[loc, :]
            except PETSc.Error as exc:
                raise DelassusError(f"MUMPS multiple-RHS solve failed: {self._mumps_status()} ({exc})") from exc
            finally:
                for obj in (X, B, Bt):
                    obj.destroy()
        return self._gather_rows(S, pos, Yloc)

    def _build_selected_inverse(self, HS: sp.csr_matrix, S: np.ndarray) -> np.ndarray | None:
        """W = H_S (K^-1)_{SS} H_S^T with (K^-1)_{SS} from MUMPS entries of the inverse (ICNTL(30))."""
        inv = self._inverse_entries(S, S)
        if inv is None:
            return None
        self.stats["selected_entries"] = int(inv.size)
        return HS @ (HS @ inv.T).T  # H_S Kinv_SS H_S^T with sparse H_S

    def _inverse_entries(self, S: np.ndarray, C: np.ndarray) -> np.ndarray | None:
        """(K^-1)_{S, C}, transposed (shape (|C|, |S|)), on rank 0 (``None`` elsewhere). Collective.

        PETSc 3.18's MatMumpsGetInverse takes the requested pattern (and returns the values) in the
        diagonal block of rank 0 only, and in parallel leaves ICNTL(21) = 0 (centralised solution)
        behind, which would corrupt every later distributed MatSolve: we restore ICNTL(30) = 0 and
        ICNTL(21) = 1 after each call.
        """
        lib = _petsc_c_api()
        F = self.factor
        comm_p = self.K.getComm()
        rank0 = self.comm.rank == 0
        N = self.K.getSize()[0]
        s, c = S.size, C.size
        # Bt (N x N): row j lists the rows i of column j of K^-1 wanted; rows C with columns S.
        if rank0:
            # The request pattern depends on S and C only: built once and reused by every later build.
            key = (N, S.tobytes(), C.tobytes())
            if getattr(self, "_pattern_key", None) != key:
                indptr = np.zeros(N + 1, dtype=PETSc.IntType)
                indptr[C + 1] = s
                self._pattern = (np.cumsum(indptr, dtype=PETSc.IntType), np.tile(S.astype(PETSc.IntType), c))
                self._pattern_key = key
            indptr, indices = self._pattern
            values = np.zeros(s * c, dtype=PETSc.ScalarType)
            nrows = N
        else:
            indptr = np.zeros(1, dtype=PETSc.IntType)
            indices = np.zeros(0, dtype=PETSc.IntType)
            values = np.zeros(0, dtype=PETSc.ScalarType)
            nrows = 0
        Bt = PETSc.Mat().createAIJ(size=((nrows, N), (nrows, N)), csr=(indptr, indices, values), comm=comm_p)
        Bt.assemble()
        spRHS = PETSc.Mat().createTranspose(Bt)
        ierr = 0
        try:
            ierr = int(lib.MatMumpsGetInverse(ctypes.c_void_p(F.handle), ctypes.c_void_p(spRHS.handle)))
        finally:
            F.setMumpsIcntl(30, 0)  # else the next solve fails with INFOG(1) = -47
            if self.comm.size > 1:
                F.setMumpsIcntl(21, 1)  # PETSc's MatSolve expects the distributed solution back
        # Every rank raises together if any rank failed.
        worst = self.comm.allreduce(abs(ierr), op=MPI.MAX)  # the same op on every rank
        bad = self.comm.allreduce(ierr != 0, op=MPI.LOR)
        try:
            if bad:
                code = ierr or worst
                raise DelassusError(f"MatMumpsGetInverse failed ({_petsc_error_text(code)}); "
                                    f"{self._mumps_status()}")
            if not rank0:
                return None
            ai, aj, av = Bt.getValuesCSR()
            # Rows C of Bt hold, in order, the s entries of columns S (PETSc keeps the sorted pattern we
            # gave): the c x s block is the values array itself.
            if av.size != s * c or not np.array_equal(aj[ai[C[0]]:ai[C[0]] + s], S):
                raise DelassusError("MatMumpsGetInverse returned an unexpected sparsity pattern")
            return av.reshape(c, s)
        finally:
            spRHS.destroy()
            Bt.destroy()

    def _own_factor(self) -> DelassusOperator:
        """This rank's sequential factor of the whole K. Collective.

        Gathered and factorised (symbolic + numeric) after :meth:`factorize`; after :meth:`refactorize` the
        copy's values are refreshed in place and refactorised numerically only.
        """
        own = getattr(self, "_own", None)
        error = None
        try:
            N = self.K.getSize()[0]
            rows = PETSc.IS().createStride(N, 0, 1, comm=PETSc.COMM_SELF) if self.comm.size > 1 else None
            if own is None:
                Kseq = self.K.createSubMatrices(rows)[0] if rows is not None else self.K
                own = DelassusOperator(Kseq, MPI.COMM_SELF, method="selected_inverse",
                                       petsc_options=self.petsc_options, options_prefix=self.options_prefix,
                                       spd=self.spd, symmetrize=False)
                own.factorize()
                self._own = own
            elif getattr(self, "_own_stale", False):
                if rows is not None:
                    self.K.createSubMatrices(rows, submats=[own.K])  # same pattern: values only
                    # The values are copied in place without a new object state: PCSetUp would see an
                    # unchanged matrix and keep the old factor (measured: W unchanged after K -> 2K).
                    own.K.stateIncrease()
                own.refactorize()
            self._own_stale = False
            if rows is not None:
                rows.destroy()
        except Exception as exc:  # noqa: BLE001 - re-raised below on every rank together
            error = f"{type(exc).__name__}: {exc}"
        errors = self.comm.allgather(error)
        if any(errors):
            self._drop_own_factor()
            raise DelassusError("own factorisation of K for the 'owned' route failed on rank(s) "
                                f"{[i for i, e in enumerate(errors) if e]}: {next(e for e in errors if e)}")
        return self._own

    def _drop_own_factor(self) -> None:
        own = getattr(self, "_own", None)
        if own is not None:
            Kseq = own.K
            own.destroy()
            if Kseq is not self.K:
                Kseq.destroy()
        self._own = None

    def _build_owned(self, H: sp.csr_matrix, HS: sp.csr_matrix, S: np.ndarray) -> np.ndarray:
        """W from each rank's columns W[:, J] = H_S (K^-1)_{S, S_J} H_J^T on its own factor, gathered on rank 0."""
        m = H.shape[0]
        size, rank = self.comm.size, self.comm.rank
        start, stop = (m * rank) // size, (m * (rank + 1)) // size
        t0 = time.perf_counter()
        own = self._own_factor()
        self.stats["own_factorize_time"] = time.perf_counter() - t0
        WJ = np.zeros((m, 0))
        error = None
        if stop > start:
            try:
                HJ = H[start:stop].tocsr()
                C = np.unique(HJ.indices).astype(np.int64)
                inv = own._inverse_entries(S, C)  # (|C|, |S|) = ((K^-1)_{S, C})^T
                WJ = HS @ (HJ[:, C] @ inv).T
            except Exception as exc:  # noqa: BLE001 - re-raised below on every rank together
                error = f"{type(exc).__name__}: {exc}"
        errors = self.comm.allgather(error)
        if any(errors):
            raise DelassusError(f"'owned' route failed: {next(e for e in errors if e)}")
        # Column blocks in rank order, gathered on rank 0 as rows of W^T (only rank 0 symmetrises; _finish
        # broadcasts), each in messages of at most MPI_CHUNK doubles: MPI counts are ints.
        block = np.ascontiguousarray(np.asarray(WJ).T).ravel()
        WT = np.empty(m * m) if rank == 0 else None
        for source in range(size):
            first, last = ((m * source) // size) * m, ((m * (source + 1)) // size) * m
            for offset in range(first, last, MPI_CHUNK):
                end = min(offset + MPI_CHUNK, last)
                if source == rank == 0:
                    WT[offset:end] = block[offset - first:end - first]
                elif rank == 0:
                    self.comm.Recv(WT[offset:end], source=source, tag=offset // MPI_CHUNK)
                elif rank == source:
                    self.comm.Send(block[offset - first:end - first], dest=0, tag=offset // MPI_CHUNK)
        return WT.reshape(m, m).T if rank == 0 else None

    # Schur complement route ----------------------------------------------------------------------------
    def _set_schur_dofs(self, F: PETSc.Mat) -> None:
        """Tell the (not yet factorised) MUMPS factor F to keep ``self._schur_dofs`` for last."""
        lib = _petsc_c_api()
        if not hasattr(lib, "MatFactorSetSchurIS"):
            raise DelassusError("this PETSc has no MatFactorSetSchurIS: the 'schur' route is not available")
        iset = PETSc.IS().createGeneral(self._schur_dofs.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        try:
            ierr = int(lib.MatFactorSetSchurIS(ctypes.c_void_p(F.handle), ctypes.c_void_p(iset.handle)))
        finally:
            iset.destroy()
        if ierr:
            raise DelassusError(f"MatFactorSetSchurIS failed ({_petsc_error_text(ierr)})")

    def _schur_complement(self) -> np.ndarray:
        """The dense Schur complement K_SS - K_SR K_RR^-1 K_RS of the last factorisation (a copy)."""
        lib = _petsc_c_api()
        F = self.factor
        Smat = ctypes.c_void_p()
        status = ctypes.c_int()
        ierr = int(lib.MatFactorCreateSchurComplement(ctypes.c_void_p(F.handle), ctypes.byref(Smat),
                                                      ctypes.byref(status)))
        if ierr:
            raise DelassusError(f"MatFactorCreateSchurComplement failed ({_petsc_error_text(ierr)}); "
                                f"{self._mumps_status()}")
        try:
            # PETSc factorises (1) or inverts (2) the Schur block in place for a solve through this factor;
            # only the unfactored block (0) is S_K. This operator never solves, so anything else is a bug.
            if status.value != 0:
                raise DelassusError(f"the Schur complement is no longer S_K (PETSc status {status.value}: "
                                    "factored or inverted by a solve through the factor)")
            rows, cols, lda = _PETSC_INT(), _PETSC_INT(), _PETSC_INT()
            lib.MatGetSize(Smat, ctypes.byref(rows), ctypes.byref(cols))
            lib.MatDenseGetLDA(Smat, ctypes.byref(lda))
            n = int(rows.value)
            if n != self._schur_dofs.size or int(cols.value) != n:
                raise DelassusError(f"MUMPS returned a {n} x {cols.value} Schur complement for "
                                    f"{self._schur_dofs.size} dofs")
            data = ctypes.POINTER(ctypes.c_double)()
            lib.MatDenseGetArrayRead(Smat, ctypes.byref(data))
            try:
                # Column-major with leading dimension lda: row j of this view is column j.
                columns = np.ctypeslib.as_array(data, shape=(n, int(lda.value)))[:, :n].copy() if n else \
                    np.zeros((0, 0))
            finally:
                lib.MatDenseRestoreArrayRead(Smat, ctypes.byref(data))
        finally:
            lib.MatDestroy(ctypes.byref(Smat))
        return columns.T

    def _augmented(self, H: sp.csr_matrix) -> sp.csr_matrix:
        """The saddle-point matrix [[K, H^T], [H, 0]] (serial), its (2, 2) block an explicit zero diagonal."""
        ai, aj, av = self.K.getValuesCSR()
        N, m = self.K.getSize()[0], H.shape[0]
        K = sp.csr_matrix((av, aj, ai), shape=(N, N))
        zero = sp.csr_matrix((np.zeros(m), np.arange(m), np.arange(m + 1)), shape=(m, m))
        A = sp.bmat([[K, H.T], [H, zero]], format="csr")  # COO concatenation keeps the explicit zeros
        A.sort_indices()
        return A

    def _schur_factor(self, H: sp.csr_matrix) -> DelassusOperator:
        """A factorisation of [[K, H^T], [H, 0]] with H's rows kept for last: made for a new H, refreshed
        numerically (the K block's values) after :meth:`refactorize`, else reused."""
        op = getattr(self, "_schur", None)
        key = (H.shape, H.indptr.tobytes(), H.indices.tobytes(), H.data.tobytes())
        if op is not None and self._schur_key != key:
            self._drop_schur()
            op = None
        if op is None:
            A = self._augmented(H)
            n = A.shape[0]
            matrix = PETSc.Mat().createAIJ(size=(n, n), csr=(A.indptr.astype(PETSc.IntType),
                                                               A.indices.astype(PETSc.IntType), A.data),
                                           comm=PETSc.COMM_SELF)
            matrix.assemble()
            matrix.setOption(PETSc.Mat.Option.SYMMETRIC, True)
            # MUMPS eliminates the K block only (SPD): LDL^T without pivoting (SYM=1) holds, as for K itself.
            op = DelassusOperator(matrix, MPI.COMM_SELF, method="selected_inverse", petsc_options=self.petsc_options,
                                  options_prefix=self.options_prefix, spd=self.spd, symmetrize=False)
            op._schur_dofs = np.arange(n - H.shape[0], n, dtype=np.int64)
            try:
                op.factorize()
            except Exception:
                op.destroy()
                matrix.destroy()
                raise
            self._schur, self._schur_key = op, key  # only a factorised operator is reused
        elif getattr(self, "_schur_stale", False):
            A = self._augmented(H)  # the same pattern: K's new values in place, then a numeric refactorisation
            op.K.setValuesCSR(A.indptr.astype(PETSc.IntType), A.indices.astype(PETSc.IntType), A.data)
            op.K.assemble()
            op.refactorize()
        self._schur_stale = False
        self.stats["schur_factorize_time"] = op.last_factorize_time
        self.stats["schur_memory_mb"] = op.stats["mumps_memory_mb"]
        return op

    def _drop_schur(self) -> None:
        op = getattr(self, "_schur", None)
        if op is not None:
            matrix = op.K
            op.destroy()
            matrix.destroy()
        self._schur = None

    def _build_schur(self, H: sp.csr_matrix) -> np.ndarray:
        """W = -(Schur complement of [[K, H^T], [H, 0]] on H's rows) = H K^-1 H^T (serial)."""
        W = self._schur_factor(H)._schur_complement()
        np.negative(W, out=W)  # in place: W is the largest array of the build (m^2)
        self.stats["schur_size"] = int(W.shape[0])
        if not self.stats["refactorizations"]:
            # An operator never refactorised builds W once per H (a new H, a new factor): its second factor,
            # 1.2-2.9x K's, would be held for nothing through the cycles. Once K's values have changed (an
            # elastic-plastic tangent) it is kept, so that the next build is a numeric refactorisation.
            self._drop_schur()
        return W

    # ------------------------------------------------------------------------------------------------
    def destroy(self) -> None:
        """Free the KSP and the factor (K belongs to the caller)."""
        self._drop_schur()
        self._drop_own_factor()
        if self.ksp is not None:
            self.ksp.destroy()
            self.ksp = None
