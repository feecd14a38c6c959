"""From a validated scene to results: mesh, K, contact set, W, then the increments.

Each increment solves the local problem x = W r + q on the replicated contact set (paper eq. 28):
the normal rows of x are gaps, the tangential rows slip increments, so

    q_n = g_0 + g_w - n.D,     q_t = -t.D - y_t(previous),

where D is the obstacle's rigid displacement and ``y = W r + q_abs`` the total relative position of the
last converged increment. K is factorised once, W built once; an increment costs local solves only,
plus one back-substitution when fields are written.

The local problem is solved on rank 0 and its result broadcast, so every rank holds the same contact
state whatever the partition.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from . import local_solvers
from .analytic import hertz_line_contact
from .contact import ContactSet, RigidPlane, find_candidates
from .loading import LoadControlError, LoadStep, find_displacement, monotonic_path
from .scenes import Scene

__all__ = ["ContactModel", "IncrementState", "SimulationError", "run_scene"]


class SimulationError(RuntimeError):
    """An increment could not be solved; the message says which, and why."""


@dataclass
class IncrementState:
    """Converged state of an increment (replicated on every rank)."""

    increment: int
    stage: str
    r: np.ndarray            #: Contact forces, (n, t...) per contact.
    x: np.ndarray            #: Local solution: gaps (normal rows), slip increments (tangential rows).
    y: np.ndarray            #: Total relative position W r + q_abs (tangential rows: total slip).
    D: np.ndarray            #: Obstacle displacement (global coordinates).
    iterations: int = 0
    error: float = 0.0
    load_solves: int = 0
    states: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int8))


class ContactModel:
    """The discretised scene: body, stiffness, contact set and Delassus matrix. Collective to build.

    Args:
        scene: A validated scene.
        comm: MPI communicator.
    """

    def __init__(self, scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD):
        from . import meshes
        from .materials import LinearElastic
        from .mechanics import ElasticProblem

        self.scene = scene
        self.comm = comm
        self.timings: dict[str, float] = {}
        g = scene.geometry
        t0 = time.perf_counter()
        if g.kind == "half_cylinder":
            self.body = meshes.half_cylinder(comm, g.radius, contact_mesh_size=g.contact_mesh_size,
                                             contact_half_width=g.refined_half_width,
                                             coarse_mesh_size=g.coarse_mesh_size, quadrilateral=g.quadrilateral)
            fixed = ["top"]
        else:
            self.body = meshes.rectangle(comm, g.width, g.height, g.nx, g.ny, quadrilateral=g.quadrilateral)
            fixed = ["top"]
        self.timings["mesh_s"] = time.perf_counter() - t0

        surface = scene.contact.surface
        if surface not in self.body.tags:
            raise SimulationError(f"contact.surface = {surface!r} is not a boundary of the "
                                  f"{g.kind} mesh; allowed: {', '.join(sorted(self.body.tags))}")
        self.obstacle = RigidPlane(np.array(scene.contact.plane_point), np.array(scene.contact.plane_normal))

        material = LinearElastic(scene.material.E, scene.material.nu)
        t0 = time.perf_counter()
        self.problem = ElasticProblem(self.body, material, fixed=fixed,
                                      delassus_method=scene.solver.delassus_method,
                                      petsc_options=scene.solver.petsc_options)
        self.timings["assemble_s"] = time.perf_counter() - t0

        facets = self.body.facet_tags.find(self.body.tags[surface])
        half_width = scene.contact.candidate_half_width
        if half_width is None and g.kind == "half_cylinder":
            half_width = g.refined_half_width
        try:
            self.contact: ContactSet = find_candidates(self.problem.V, facets, self.obstacle, half_width,
                                                       exclude_nodes=self.problem.fixed_nodes)
        except ValueError as exc:
            raise SimulationError(str(exc)) from None

        t0 = time.perf_counter()
        self.problem.delassus.factorize()
        self.timings["factorize_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        W = self.problem.delassus.build(self.contact.H)
        # One copy decides: the local solve must see identical input on every rank.
        self.W = comm.bcast(W if comm.rank == 0 else None, root=0)
        self.timings["delassus_s"] = time.perf_counter() - t0
        self.delassus_method = self.problem.delassus.method

    @property
    def n_dofs(self) -> int:
        V = self.problem.V
        return V.dofmap.index_map.size_global * V.dofmap.index_map_bs


class IncrementSolver:
    """Solves increments on the local problem, with displacement or force control of the obstacle."""

    def __init__(self, model: ContactModel):
        s = model.scene
        self.model = model
        self.cs = model.contact
        self.W = model.W
        self.dim = self.cs.dim
        self.mu = s.contact.mu
        self.tol = s.solver.local_tol
        self.max_iter = s.solver.local_max_iter
        self.method = s.solver.local_method
        self.force_tol = s.solver.force_tol
        self.frame = model.obstacle.frame
        self.G = self.cs.rigid_modes
        nrows = self.cs.nc * self.dim
        self.normal_rows = np.arange(nrows) % self.dim == 0
        self.gap = np.zeros(nrows)
        self.gap[self.normal_rows] = self.cs.gap0
        # Point stiffness of the closest node: a safe first guess of the load-displacement slope.
        k = int(np.argmin(self.cs.gap0))
        blk = slice(k * self.dim, (k + 1) * self.dim)
        self.stiffness = np.array([1.0 / self.W[blk, blk][0, 0], 1.0 / self.W[blk, blk][1, 1]])

    def initial_state(self) -> IncrementState:
        nrows = self.cs.nc * self.dim
        return IncrementState(0, "initial", np.zeros(nrows), self.gap.copy(), self.gap.copy(),
                              np.zeros(self.dim), states=np.zeros(self.cs.nc, dtype=np.int8))

    def _q(self, D: np.ndarray, prev: IncrementState) -> tuple[np.ndarray, np.ndarray]:
        q_abs = self.gap - self.G @ D
        q = q_abs.copy()
        q[~self.normal_rows] -= prev.y[~self.normal_rows]
        return q, q_abs

    def solve(self, step: LoadStep, prev: IncrementState) -> IncrementState:
        """Solve one increment from the converged state ``prev``; rank-local (call on one rank).

        Raises:
            SimulationError: local solver failure or unreachable prescribed force.
        """
        n, t = self.frame[0], self.frame[1]
        d = np.array([prev.D @ n, prev.D @ t])
        r_warm = prev.r.copy()
        count = {"solves": 0, "iterations": 0}
        last: dict[str, Any] = {}

        def local(dn: float, dt: float):
            nonlocal r_warm
            D = dn * n + dt * t
            q, q_abs = self._q(D, prev)
            res = local_solvers.solve(self.W, q, self.mu, self.dim, method=self.method, tol=self.tol,
                                      max_iter=self.max_iter, r0=r_warm)
            count["solves"] += 1
            count["iterations"] += res.iterations
            if not res.converged:
                raise SimulationError(f"increment {step.increment} ({step.stage}): local solver did not "
                                      f"converge: {res.message}")
            r_warm = res.r
            F = self.cs.total_force(res.r)
            last.update(res=res, D=D, q_abs=q_abs, F=np.array([F @ n, F @ t]))
            return last["F"]

        targets = np.array([step.normal, step.tangential])
        controlled = np.array([step.normal_force_controlled, step.tangential_force_controlled])
        d[~controlled] = targets[~controlled]
        try:
            F = local(*d)
            # Tolerance relative to the loads in play (a zero tangential target is held to the normal force).
            scale = max(np.abs(targets[controlled]).max(initial=0.0), np.abs(F).max(), 1e-300)
            ftol = self.force_tol * scale
            for _sweep in range(100):
                if np.all(np.abs(F - targets)[controlled] <= ftol):
                    break
                for k in np.flatnonzero(controlled):
                    def force_k(v: float, k: int = k) -> float:
                        dd = d.copy()
                        dd[k] = v
                        return local(*dd)[k]
                    d_old, F_old = d[k], F[k]
                    d[k], _, _ = find_displacement(force_k, targets[k], d[k], self.stiffness[k], ftol,
                                                   name=("loading.normal_force", "loading.tangential_force")[k])
                    F = last["F"]  # the root finder's last evaluation is at the returned d[k]
                    if d[k] != d_old and F[k] != F_old:
                        self.stiffness[k] = abs((F[k] - F_old) / (d[k] - d_old))
            else:
                raise SimulationError(f"increment {step.increment}: prescribed forces not reached after 100 "
                                      f"sweeps (residual {np.abs(F - targets)[controlled]}, tolerance {ftol:.3g})")
        except LoadControlError as exc:
            raise SimulationError(f"increment {step.increment} ({step.stage}): {exc}") from None

        res = last["res"]
        y = self.W @ res.r + last["q_abs"]
        states = local_solvers.contact_states(res.r, res.x, self.mu, self.dim)
        return IncrementState(step.increment, step.stage, res.r.copy(), res.x.copy(), y, last["D"].copy(),
                              iterations=count["iterations"], error=res.error, load_solves=count["solves"],
                              states=states)


def _span(position: np.ndarray, mask: np.ndarray) -> float:
    return float(position[mask].max() - position[mask].min()) if mask.any() else 0.0


def contact_quantities(model: ContactModel, st: IncrementState) -> dict[str, Any]:
    """Nodal pressure, shear traction and slip; totals, widths and state counts of an increment."""
    cs, dim = model.contact, model.contact.dim
    rn, rt = st.r[0::dim], st.r[1::dim]
    frame = model.obstacle.frame
    F = cs.total_force(st.r)
    loaded = rn > 1e-12 * max(rn.max(initial=0.0), 1e-300)
    pressure = rn / cs.tributary
    return {
        "position": cs.abscissa, "gap": st.y[0::dim], "pressure": pressure, "shear": rt / cs.tributary,
        "slip": st.x[1::dim], "state": st.states,
        "normal_force": float(F @ frame[0]), "tangential_force": float(F @ frame[1]),
        "max_pressure": float(pressure.max(initial=0.0)),
        "contact_width": _span(cs.abscissa, loaded),
        "stick_width": _span(cs.abscissa, st.states == local_solvers.STICK),
        "n_open": int(np.sum(st.states == local_solvers.OPEN)),
        "n_stick": int(np.sum(st.states == local_solvers.STICK)),
        "n_slip": int(np.sum(st.states == local_solvers.SLIP)),
        "edge_loaded": bool(loaded[0] or loaded[-1]),
    }


def run_scene(scene: Scene, out_dir: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, quiet: bool = False
              ) -> dict[str, Any]:
    """Run a scene and write its outputs into ``out_dir``. Collective.

    Returns:
        The summary (also written to ``out_dir/summary.json``).

    Raises:
        SimulationError: when an increment fails; the outputs of the converged increments and a summary
            with ``converged = false`` and the diagnostic are on disk.
    """
    from .io import ResultWriter, plot_profiles

    t_start = time.perf_counter()
    rank0 = comm.rank == 0
    say = (lambda msg: print(msg, flush=True)) if (rank0 and not quiet) else (lambda msg: None)
    out = Path(out_dir)

    model = ContactModel(scene, comm)
    solver = IncrementSolver(model)
    say(f"[{scene.name}] {model.n_dofs} dofs, {model.contact.nc} contact candidates, "
        f"W by {model.delassus_method} in {model.timings['delassus_s']:.3f} s")
    writer = ResultWriter(out, comm, profiles=scene.output.contact_profiles)
    summary: dict[str, Any] = {
        "scene": scene.name, "dofs": model.n_dofs, "contacts": model.contact.nc,
        "delassus_method": model.delassus_method, **{k: round(v, 6) for k, v in model.timings.items()},
    }
    g = scene.geometry
    if g.kind == "half_cylinder":
        summary["hertz_reference"] = "rigid plane, frictionless: E* = E/(1-nu^2)"

    state = solver.initial_state()
    snapshots: list[tuple[str, dict[str, Any]]] = []
    total_iterations = 0
    error_message = None
    quantities: dict[str, Any] = {}
    increments = 0
    for step in monotonic_path(scene.loading):
        t_inc = time.perf_counter()
        new_state, failure = None, None
        if rank0:
            try:
                new_state = solver.solve(step, state)
            except SimulationError as exc:
                failure = str(exc)
        new_state, failure = comm.bcast((new_state, failure), root=0)
        if failure is not None:
            error_message = failure
            say(f"[{scene.name}] STOPPED: {failure}")
            break
        state = new_state
        increments += 1
        total_iterations += state.iterations
        quantities = contact_quantities(model, state)
        frame = model.obstacle.frame
        writer.history_row({
            "increment": step.increment, "stage": step.stage,
            "normal_displacement": float(state.D @ frame[0]), "tangential_displacement": float(state.D @ frame[1]),
            **{k: quantities[k] for k in ("normal_force", "tangential_force", "max_pressure", "contact_width",
                                           "stick_width", "n_open", "n_stick", "n_slip")},
            "local_iterations": state.iterations, "local_error": state.error, "load_solves": state.load_solves,
            "converged": True, "wall_time_s": round(time.perf_counter() - t_inc, 6),
        })
        writer.profile_rows(step.increment, *(quantities[k] for k in
                                              ("position", "gap", "pressure", "shear", "slip", "state")))
        if scene.output.xdmf:
            model.problem.solve_contact_response(model.contact.H, state.r)
            writer.fields(float(step.increment), [model.problem.u, model.problem.von_mises()])
        last_of_stage = step.stage == "normal" and step.increment == scene.loading.normal_increments
        if last_of_stage:
            snapshots.append((f"end of preload (inc {step.increment})", quantities))
        say(f"[{scene.name}] inc {step.increment:4d} {step.stage:10s} P = {quantities['normal_force']:.6g} "
            f"Q = {quantities['tangential_force']:.6g} p_max = {quantities['max_pressure']:.6g} "
            f"it = {state.iterations}")

    if quantities and quantities["edge_loaded"]:
        say(f"[{scene.name}] WARNING: the outermost contact candidate carries load: the contact may extend "
            "beyond the candidate window; widen contact.candidate_half_width")
    summary.update({
        "increments": increments, "converged": error_message is None, "local_iterations": total_iterations,
        "wall_time_s": round(time.perf_counter() - t_start, 6),
    })
    if quantities:
        summary.update({k: quantities[k] for k in ("normal_force", "tangential_force", "max_pressure",
                                                    "contact_width", "stick_width", "n_open", "n_stick",
                                                    "n_slip", "edge_loaded")})
    if g.kind == "half_cylinder" and quantities:
        a, p0 = hertz_line_contact(quantities["normal_force"], g.radius, scene.material.E / (1 - scene.material.nu**2))
        summary.update({"hertz_half_width": a, "hertz_max_pressure": p0})
    if error_message is not None:
        summary["error"] = error_message
    writer.summary(summary)
    writer.close()

    if scene.output.plots and rank0 and quantities:
        snapshots.append((f"final (inc {state.increment})", quantities))
        reference = None
        if g.kind == "half_cylinder":
            from .analytic import hertz_pressure
            P = snapshots[0][1]["normal_force"]
            xs = np.linspace(quantities["position"].min(), quantities["position"].max(), 400)
            reference = ("Hertz, frictionless, end of preload", xs,
                         hertz_pressure(xs, P, g.radius, scene.material.E / (1 - scene.material.nu**2)))
        plot_profiles(out / "profiles.png", quantities["position"],
                      [(label, q["pressure"], q["shear"]) for label, q in snapshots], reference,
                      title=f"{scene.name}: contact tractions")
    say(f"[{scene.name}] {'done' if error_message is None else 'FAILED'}: {increments} increments, "
        f"P = {summary.get('normal_force', 0):.6g} N/mm, Q = {summary.get('tangential_force', 0):.6g} N/mm, "
        f"p_max = {summary.get('max_pressure', 0):.6g} MPa, contact width = {summary.get('contact_width', 0):.4g} mm, "
        f"stick width = {summary.get('stick_width', 0):.4g} mm, {summary['wall_time_s']:.2f} s -> {out}")
    model.problem.destroy()
    if error_message is not None:
        raise SimulationError(error_message)
    return summary
