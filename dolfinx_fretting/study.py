"""The speed-vs-accuracy trade study: a fine reference run of a scene and a sweep of its numerics.

``dolfinx-fretting study SCENE --out DIR`` runs the scene once with fine numerics (the *reference*) and once
per sweep point, each point changing one numerics key of the reference (or several, ``--point``), then
compares every point's outputs with the reference's:

* ``err_max_wear``: relative error of the maximum wear depth at the end of the run (``summary.json``);
* ``err_wear_l2``: relative L2 error of the worn profile (wear gap along the surface at the end of the
  last cycle, ``contact_profiles.csv``), both profiles interpolated linearly on the union of their node
  positions and taken as zero outside their own contact window, integrated by the trapezoid rule; for a 3D
  contact the worn map over the contact plane (:func:`map_l2_error`);
* ``err_peak_pressure``: relative error of the peak contact pressure, the largest nodal pressure over the
  kept increments of the last cycle (of the whole run for a monotonic scene);
* ``err_energy``: relative error of the energy dissipated over the *physical* cycles: preload energy plus
  ``wear.acceleration`` times the energy of the simulated cycles (``cycles.csv``).

Points are compared at **equal physical cycles**: a point with ``wear.acceleration = s`` simulates
``N / s`` cycles, N being the reference's physical cycle count (its ``loading.cycles`` times its
acceleration); N must be a multiple of s. Any other scene key may be swept (``--sweep section.key=v1,v2``);
it is applied as a ``--set`` override on top of the reference's, and ``equivalent_cycles`` of every point
is recorded in the table so that keys which change the physical cycle count (cycle jumps) show it.

Wall time is measured around :func:`dolfinx_fretting.simulation.run_scene` (mesh, factorisation, W and the
increments; pictures and XDMF are switched off for every run alike), after an untimed warm-up run that
loads the compiled kernels. Outputs in ``DIR``: ``study.csv`` (:data:`STUDY_FIELDS`), ``study.md`` (a
markdown table), ``study.png`` (wall time against each error, one colour per swept key, the Pareto
frontier over all points) and ``runs/<label>/`` (every run's own output folder).
"""

from __future__ import annotations

import math
import re
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from .geometries import GEOMETRIES
from .outdir import OutputFolderError, ensure_writable_folder
from .scenes import Scene, SceneError, load_scene
from .tables import cell_text, read_rows, write_table

__all__ = ["StudyPoint", "STUDY_FIELDS", "STUDY_FILES", "check_study_folder", "ERROR_FIELDS", "parse_sweep",
           "parse_point", "default_reference", "default_sweep", "sweep_entries", "plan_study", "check_on_rank0",
           "run_point", "run_study", "point_errors", "profile_l2_error", "write_study_table", "read_study_csv",
           "format_markdown", "plot_study", "map_l2_error", "wear_l2_error"]

#: Error columns of the study table (relative errors against the reference run).
ERROR_FIELDS = ("err_max_wear", "err_wear_l2", "err_peak_pressure", "err_energy")
#: Columns of ``study.csv``.
STUDY_FIELDS = ["label", "key", "value", "cycles", "equivalent_cycles", "wall_time_s", "speedup",
                *ERROR_FIELDS, "max_wear_depth", "peak_pressure", "dissipated_energy", "contacts",
                "converged", "error", "overrides"]
#: Overrides of every study run: no pictures, no XDMF, no progress bar, no per-increment history (the
#: tables the errors come from, ``cycles.csv`` and the last cycle's profiles, are always written).
QUIET_OUTPUT = ["output.contact_profiles=true", "output.xdmf=false", "output.plots=false", "output.progress=false",
                "output.history_every=100000000", "output.loop_cycles=[]", "output.track_positions=[]"]
#: Names of the error columns in the table and the plot.
ERROR_NAMES = {"err_max_wear": "max wear depth", "err_wear_l2": "wear profile (L2)",
               "err_peak_pressure": "peak pressure", "err_energy": "dissipated energy"}


@dataclass
class StudyPoint:
    """One run of the study.

    Attributes:
        label: Unique name (also its folder under ``runs/``).
        key: The swept key (``"reference"`` for the reference, ``"point"`` for a ``--point`` combination).
        value: The swept value as text.
        overrides: ``section.key=value`` overrides on the scene, in order (the reference's first).
        scene: The validated scene of this run.
    """

    label: str
    key: str
    value: str
    overrides: list[str]
    scene: Scene | None = field(default=None, repr=False)


# Planning ------------------------------------------------------------------------------------------------
def _split_assignment(item: str, option: str) -> tuple[str, str]:
    if "=" not in item:
        raise SceneError(f"{option} {item!r}: expected section.key=value")
    key, raw = item.split("=", 1)
    key = key.strip()
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)+", key):
        raise SceneError(f"{option} {item!r}: the key must be section.key (e.g. solver.local_tol)")
    return key, raw.strip()


def parse_sweep(items: Sequence[str]) -> list[tuple[str, list[str]]]:
    """``section.key=v1,v2,...`` strings as (key, values); values stay text (TOML syntax).

    A value that is a TOML array (``[1, 2]``) keeps its commas.

    Raises:
        SceneError: An item without ``=`` or a value, or a key swept twice.
    """
    out: list[tuple[str, list[str]]] = []
    for item in items:
        key, raw = _split_assignment(item, "--sweep")
        values = [v.strip() for v in re.split(r",(?![^\[]*\])", raw) if v.strip()]
        if not values:
            raise SceneError(f"--sweep {item!r}: no value")
        if any(k == key for k, _ in out):
            raise SceneError(f"--sweep: {key} is swept twice; give its values in one --sweep {key}=v1,v2")
        out.append((key, values))
    return out


def parse_point(text: str) -> list[str]:
    """A ``--point`` combination: ``"k1=v1 k2=v2"`` (spaces or semicolons between assignments)."""
    items = [t for t in re.split(r"[;\s]+", text.strip()) if t]
    if not items:
        raise SceneError(f"--point {text!r}: no section.key=value")
    for item in items:
        _split_assignment(item, "--point")
    return items


def _value_of(scene: Scene, key: str) -> Any:
    node: Any = scene
    for part in key.split("."):
        node = getattr(node, part)
    return node


def _physical_cycles(scene: Scene) -> float:
    return scene.loading.cycles * scene.wear.acceleration


def _force_controlled(scene: Scene) -> bool:
    return scene.loading.normal_force_controlled or scene.loading.tangential_force_controlled


def _tolerance(local_tol: float, scene: Scene) -> list[str]:
    """``solver.local_tol`` and, for a force-controlled load, ``solver.force_tol`` 100 times it: the force
    control cannot meet a force tolerance tighter than about 100 local tolerances (measured on
    cylinder-flat: local 1e-6 / force 1e-6 and local 1e-8 / force 1e-10 both stop at the preload)."""
    out = [f"solver.local_tol={local_tol:.3g}"]
    if _force_controlled(scene):
        out.append(f"solver.force_tol={min(100 * local_tol, 0.1):.3g}")
    return out


def default_reference(scene: Scene) -> list[str]:
    """Overrides that make the fine reference of ``scene``: contact elements halved (the geometry kind's
    ``finer``: the ``contact_mesh_size`` of a half-cylinder or a sphere halved, the ``nx`` and ``ny`` of a rectangle
    doubled, a mesh file's mesh kept), twice the increments per cycle, ``local_tol`` 1e-12 (or the scene's, if
    tighter; ``force_tol`` 100 times it under force control) and no wear acceleration (its cycles multiplied by it,
    so that the physical cycle count is the scene's)."""
    loading = scene.loading
    ref = GEOMETRIES[scene.geometry.kind].finer(scene)
    if loading.cycles > 0:
        ref.append(f"loading.increments_per_cycle={2 * loading.increments_per_cycle}")
    else:
        ref.append(f"loading.tangential_increments={2 * loading.tangential_increments}")
    ref += _tolerance(min(scene.solver.local_tol, 1e-12), scene)
    if scene.wear.acceleration != 1.0:
        n = _physical_cycles(scene)
        if abs(n - round(n)) > 1e-9:
            raise SceneError(f"wear.acceleration = {scene.wear.acceleration} times loading.cycles = {loading.cycles} "
                             "is not a whole number of physical cycles")
        ref += ["wear.acceleration=1", f"loading.cycles={int(round(n))}"]
    return ref


#: A planned point before validation: (swept key, value as text, overrides on top of the reference's).
Entry = tuple[str, str, list[str]]


def sweep_entries(sweep: Sequence[tuple[str, list[str]]]) -> list[Entry]:
    """One entry per value of each swept key (``--sweep``), one key changed at a time."""
    return [(key, v, [f"{key}={v}"]) for key, values in sweep for v in values]


def default_sweep(reference: Scene) -> list[Entry]:
    """The sweep when none is given, around the reference: contact elements 2x and 4x coarser (the geometry kind's
    ``coarser``: a half-cylinder's or a sphere's ``contact_mesh_size``; a rectangle's ``nx`` and ``ny`` together;
    none for a mesh file), a half and a quarter of the increments per cycle (multiples of 4; of the tangential
    increments for a monotonic load), ``local_tol`` 1e-10, 1e-8 and 1e-6 (with ``force_tol`` 100 times it under
    force control) and (cyclic scenes with wear) wear accelerations that divide the physical cycle count (up to
    three of 2, 5, 10, 20, 50, 100, ...)."""
    geometry, loading = GEOMETRIES[reference.geometry.kind], reference.loading
    coarser = [geometry.coarser(reference, factor) for factor in (2, 4)]
    entries: list[Entry] = [entry for entry in coarser if entry is not None]
    if loading.cycles > 0:
        ns = sorted({max(4, 4 * round(loading.increments_per_cycle / f / 4)) for f in (2, 4)}, reverse=True)
        entries += sweep_entries([("loading.increments_per_cycle",
                                   [str(n) for n in ns if n != loading.increments_per_cycle])])
    elif loading.tangential_increments > 1:  # a monotonic load: its tangential increments
        ns = sorted({max(1, loading.tangential_increments // f) for f in (2, 4)}, reverse=True)
        entries += sweep_entries([("loading.tangential_increments",
                                   [str(n) for n in ns if n != loading.tangential_increments])])
    for tol in (1e-10, 1e-8, 1e-6):
        entries.append(("solver.local_tol", f"{tol:g}", _tolerance(tol, reference)))
    if loading.cycles > 0 and reference.wear.law != "none":
        n = int(round(_physical_cycles(reference)))
        cands = [m * 10**e for e in range(0, 8) for m in (2, 5, 10) if m * 10**e <= n]
        accs = [s for s in dict.fromkeys(cands) if n % s == 0][:3]
        entries += sweep_entries([("wear.acceleration", [str(s) for s in accs])])
    return entries


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.=+-]+", "_", text).strip("_")[:80] or "point"


def _cycles_override(scene: Scene, physical: float, label: str) -> list[str]:
    """``loading.cycles`` so that ``scene`` covers ``physical`` cycles at its wear acceleration."""
    if scene.loading.cycles == 0:
        return []
    acc = scene.wear.acceleration
    n = physical / acc
    if n < 1 - 1e-9 or abs(n - round(n)) > 1e-9 * max(1.0, n):
        raise SceneError(f"{label}: wear.acceleration = {acc:g} does not divide the reference's "
                         f"{physical:g} physical cycles (loading.cycles x wear.acceleration); allowed: a "
                         "divisor of it")
    return [f"loading.cycles={int(round(n))}"]


def plan_study(source: str | Path | dict, base_overrides: Sequence[str] | None = None,
               reference: Sequence[str] | None = None, sweep: Sequence[tuple[str, list[str]]] | None = None,
               points: Sequence[Sequence[str]] | None = None,
               entries: Sequence[Entry] | None = None) -> list[StudyPoint]:
    """Validate every run of a study before any of them starts.

    Args:
        source: The scene (built-in name, TOML file or dict).
        base_overrides: ``--set`` overrides applied to the scene first (e.g. a reduced cycle count).
        reference: Overrides making the reference; ``None``: :func:`default_reference`.
        sweep: (key, values) to sweep one at a time around the reference (each value a single override);
            ``None``: :func:`default_sweep`.
        points: Extra combinations, each a list of overrides on top of the reference's.
        entries: Instead of ``sweep``: the points as (key, value, overrides) (e.g. :func:`default_sweep`'s
            entries, edited).

    Returns:
        The reference first, then one point per swept value and per combination, each with its validated
        scene (``loading.cycles`` set for equal physical cycles).

    Raises:
        SceneError: An invalid scene, override, key or value (named), or an acceleration that does not
            divide the physical cycle count.
    """
    base = list(base_overrides or [])
    scene = load_scene(source, base)
    ref_over = base + (list(reference) if reference is not None else default_reference(scene))
    ref_scene = load_scene(source, ref_over + QUIET_OUTPUT)
    physical = _physical_cycles(ref_scene)
    if entries is not None:
        entries = list(entries)
    else:
        entries = default_sweep(ref_scene) if sweep is None else sweep_entries(sweep)
    plan = [StudyPoint("reference", "reference", "", ref_over, ref_scene)]
    for combo in points or []:
        entries.append(("point", " ".join(combo), list(combo)))
    labels = {"reference"}
    for key, value, extra in entries:
        label = _slug(f"{key.split('.')[-1]}={value}" if key != "point" else value)
        while label in labels:
            label += "+"
        labels.add(label)
        over = ref_over + extra
        try:
            point_scene = load_scene(source, over + QUIET_OUTPUT)
        except SceneError as exc:
            raise SceneError(f"sweep point {' '.join(extra)}: {exc}") from None
        over = over + _cycles_override(point_scene, physical, f"sweep point {' '.join(extra)}")
        point_scene = load_scene(source, over + QUIET_OUTPUT
                                 + [f"output.snapshot_cycles=[{max(point_scene.loading.cycles, 1)}]"])
        plan.append(StudyPoint(label, key, value, over, point_scene))
    ref_scene = load_scene(source, ref_over + QUIET_OUTPUT
                           + [f"output.snapshot_cycles=[{max(ref_scene.loading.cycles, 1)}]"])
    plan[0].scene = ref_scene
    return plan


# Errors --------------------------------------------------------------------------------------------------
def _rel(value: float | None, ref: float | None) -> float:
    """|value - ref| / |ref|; 0 when both are 0; NaN when either is missing or only the reference is 0."""
    if value is None or ref is None or not (math.isfinite(value) and math.isfinite(ref)):
        return math.nan
    if ref == 0.0:
        return 0.0 if value == 0.0 else math.nan
    return abs(value - ref) / abs(ref)


def _trapezoid(y: np.ndarray, x: np.ndarray) -> float:
    """Trapezoid rule (numpy 2 renamed ``trapz`` to ``trapezoid``; numpy 1.24 has only the old name)."""
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def profile_l2_error(x: np.ndarray, w: np.ndarray, x_ref: np.ndarray, w_ref: np.ndarray) -> float:
    """Relative L2 distance of two profiles sampled at different nodes.

    Both are interpolated linearly on the sorted union of their abscissae (zero outside their own range:
    no contact node, no wear there) and integrated by the trapezoid rule: ||w - w_ref|| / ||w_ref||.
    Returns 0 when both are zero everywhere and NaN when only the reference is.
    """
    x, w, x_ref, w_ref = (np.asarray(a, dtype=float) for a in (x, w, x_ref, w_ref))
    o, oref = np.argsort(x), np.argsort(x_ref)
    grid = np.union1d(x, x_ref)
    a = np.interp(grid, x[o], w[o], left=0.0, right=0.0)
    b = np.interp(grid, x_ref[oref], w_ref[oref], left=0.0, right=0.0)
    return _relative(math.sqrt(_trapezoid((a - b) ** 2, grid)), math.sqrt(_trapezoid(b * b, grid)))


def _relative(difference: float, reference: float) -> float:
    """difference / reference: 0 when both are zero, NaN when only the reference is."""
    if reference == 0.0:
        return 0.0 if difference == 0.0 else math.nan
    return difference / reference


def map_l2_error(xy: np.ndarray, w: np.ndarray, xy_ref: np.ndarray, w_ref: np.ndarray, n: int = 301) -> float:
    """Relative L2 distance of two maps sampled at different points of a plane (a 3D contact's wear).

    Both are interpolated linearly on a Delaunay triangulation of their own points (zero outside their hull:
    no contact node, no wear there) and compared on one ``n x n`` grid over the bounding box of all points:
    ||w - w_ref|| / ||w_ref||. Returns 0 when both are zero everywhere and NaN when only the reference is.

    Args:
        xy, xy_ref: Point coordinates, shape (m, 2) and (m_ref, 2).
        w, w_ref: Values at the points.
        n: Grid points per side.
    """
    from scipy.interpolate import LinearNDInterpolator  # lazy: scipy.interpolate takes ~0.1 s to import

    xy, xy_ref = np.asarray(xy, dtype=float), np.asarray(xy_ref, dtype=float)
    lower = np.minimum(xy.min(axis=0), xy_ref.min(axis=0))
    upper = np.maximum(xy.max(axis=0), xy_ref.max(axis=0))
    gx, gy = np.meshgrid(np.linspace(lower[0], upper[0], n), np.linspace(lower[1], upper[1], n))
    grid = np.column_stack([gx.ravel(), gy.ravel()])
    a = LinearNDInterpolator(xy, np.asarray(w, dtype=float), fill_value=0.0)(grid)
    b = LinearNDInterpolator(xy_ref, np.asarray(w_ref, dtype=float), fill_value=0.0)(grid)
    return _relative(math.sqrt(float(np.sum((a - b) ** 2))), math.sqrt(float(np.sum(b * b))))


def wear_l2_error(position: np.ndarray, wear: np.ndarray, position_ref: np.ndarray, wear_ref: np.ndarray) -> float:
    """The worn profile's relative L2 error: :func:`profile_l2_error` along a 2D contact (positions of shape
    (m,)), :func:`map_l2_error` over a 3D contact's plane (positions of shape (m, 2))."""
    if np.ndim(position) == 2 and np.ndim(position_ref) == 2:
        return map_l2_error(position, wear, position_ref, wear_ref)
    return profile_l2_error(position, wear, position_ref, wear_ref)


@dataclass
class _Outcome:
    """What the errors are computed from, read back from a run's output folder."""

    max_wear_depth: float | None
    peak_pressure: float | None
    energy: float | None
    position: np.ndarray | None
    wear: np.ndarray | None
    cycles: int
    equivalent_cycles: float | None
    contacts: int | None
    converged: bool
    error: str


def _outcome(folder: Path) -> _Outcome:
    from .compare import _number, load_run  # lazy: compare imports numba (output -> state -> wear), ~0.4 s

    run = load_run(folder)
    s = run.summary
    acc = _number(s.get("wear_acceleration")) or 1.0
    # simulated cycles: the rows of cycles.csv (a cycle-jump run's summary counts the jumped ones too)
    cyc_col = run.cycles.get("cycle")
    cycles = int(cyc_col.size) if cyc_col is not None else int(_number(s.get("cycles")) or 0)
    total = _number(s.get("dissipated_energy"))
    energy = total
    cyc_e = run.cycles.get("dissipated_energy")
    if total is not None and cyc_e is not None and cyc_e.size:
        in_cycles = float(np.sum(cyc_e))
        # preload once, each simulated cycle acc times; a cycle-jump run's total already holds its jumped
        # cycles (and its acceleration is 1), so the same formula gives it back unchanged
        energy = (total - in_cycles) + acc * in_cycles
    position = wear = None
    peak = None
    prof = run.profiles
    if prof is not None:
        last_cycle = int(prof.cycles.max())
        rows = prof.rows_of_cycle(last_cycle) if last_cycle > 0 else np.arange(prof.increments.size)
        pressure = prof.values["pressure"][rows]
        # np.max, not nanmax: a NaN pressure must show (it makes the point non-finite, below)
        peak = float(np.max(pressure)) if pressure.size else None
        # 3D: the nodes' (t1, t2) positions on the contact plane (the wear is a map, not a profile along t1)
        position = prof.position if prof.position_2 is None else np.column_stack([prof.position, prof.position_2])
        wear = prof.values["wear"][rows[-1]]
    converged, error = s.get("converged") is True, str(s.get("error", ""))
    # Never a converged point with a non-finite number: the summary's own flag (written as null), the values
    # the errors come from, and the worn profile.
    bad = list(s.get("non_finite_keys") or [])
    bad += [name for name, v in (("max_wear_depth", s.get("max_wear_depth")),
                                 ("dissipated_energy", s.get("dissipated_energy"))) if _number(v) is None]
    if peak is not None and not math.isfinite(peak):
        bad.append("contact_profiles.csv pressure")
    if wear is not None and not np.all(np.isfinite(wear)):
        bad.append("contact_profiles.csv wear")
    if converged and bad:
        converged, error = False, f"non-finite results: {', '.join(bad)}"
    return _Outcome(_number(s.get("max_wear_depth")), peak if peak is None or math.isfinite(peak) else None, energy,
                    position, wear, cycles, _number(s.get("equivalent_cycles")), s.get("contacts"), converged, error)


def point_errors(folder: str | Path, reference_folder: str | Path) -> dict[str, Any]:
    """The errors of one run against the reference run, from their output folders (see the module doc).

    Returns:
        The :data:`ERROR_FIELDS` (relative errors; NaN when undefined) and the point's own values
        ``max_wear_depth``, ``peak_pressure``, ``dissipated_energy`` (physical cycles), ``cycles``,
        ``equivalent_cycles``, ``contacts``, ``converged``, ``error``.
    """
    p, r = _outcome(Path(folder)), _outcome(Path(reference_folder))
    l2 = math.nan
    if p.wear is not None and r.wear is not None:
        l2 = wear_l2_error(p.position, p.wear, r.position, r.wear)
    return {"err_max_wear": _rel(p.max_wear_depth, r.max_wear_depth), "err_wear_l2": l2,
            "err_peak_pressure": _rel(p.peak_pressure, r.peak_pressure), "err_energy": _rel(p.energy, r.energy),
            "max_wear_depth": p.max_wear_depth, "peak_pressure": p.peak_pressure, "dissipated_energy": p.energy,
            "cycles": p.cycles, "equivalent_cycles": p.equivalent_cycles, "contacts": p.contacts,
            "converged": p.converged, "error": p.error}


# Running -------------------------------------------------------------------------------------------------
#: Files a study writes into its folder (besides ``runs/``).
STUDY_FILES = ("study.csv", "study.md", "study.png")


def check_study_folder(out: str | Path, overwrite: bool = False) -> Path:
    """Check a study's output folder before any run: a writable folder (created), holding no study unless
    ``overwrite``. Serial.

    Raises:
        OutputFolderError: naming the folder and the reason.
    """
    folder = ensure_writable_folder(out)
    held = [name for name in STUDY_FILES if (folder / name).exists()]
    if held and not overwrite:
        raise OutputFolderError(f"--out {folder} already holds a study ({', '.join(held)}); replace it with "
                                "--overwrite, or choose another folder")
    return folder


def _warm_up(point: StudyPoint, out: Path, comm, ignore_size: bool = False) -> None:
    """An untimed short run (one cycle) so that the first timed run does not pay for loading the kernels."""
    from .simulation import SimulationError, run_scene  # lazy: the runner imports DOLFINx and petsc4py (PETSc)

    scene = point.scene.model_copy(deep=True)
    if scene.loading.cycles > 0:
        scene.loading.cycles = 1
        scene.output.snapshot_cycles = [1]
    try:
        run_scene(scene, out / "warmup", comm, quiet=True, overwrite=True, ignore_size=ignore_size)
    except SimulationError:
        pass  # a warm-up only loads code; the real runs report their own failures


def check_on_rank0(check: Callable[[Path, bool], Any], out: Path, overwrite: bool, comm) -> None:
    """A sweep's folder check (:func:`check_study_folder`, the map's) on rank 0 only, its refusal raised on every
    rank (collective), so that all ranks stop before any run."""
    problem = None
    if comm.rank == 0:
        try:
            check(out, overwrite)
        except OutputFolderError as exc:
            problem = str(exc)
    problem = comm.bcast(problem, root=0)
    if problem is not None:
        raise OutputFolderError(problem)


def run_point(scene: Scene, folder: Path, comm, ignore_size: bool = False) -> tuple[str, float]:
    """Run one point of a sweep (the study's, the fretting map's) with the scene runner, quietly, in ``folder``
    (the sweep owns it: an earlier run there is replaced). Collective.

    Returns:
        The point's failure message (``""`` when its run finished) and its wall time in seconds (rank 0's clock,
        on every rank). Any failure of the run (a solver's, a check that needs the mesh, PETSc's or MUMPS's, a bug)
        is the point's result, so that the sweep's finished points are never lost.

    Raises:
        OutputFolderError: ``folder`` is locked by another run (not a result of this point).
        RunInterrupted: SIGINT or SIGTERM stopped the run: the user stops the sweep.
    """
    # Lazy: this imports petsc4py and DOLFINx (PETSc initialised); planning a sweep, and the CLI's checks before
    # it, need neither
    from .simulation import RunInterrupted, SimulationError, run_scene

    comm.barrier()
    start = time.perf_counter()
    failure = ""
    try:
        run_scene(scene, folder, comm, quiet=True, overwrite=True, ignore_size=ignore_size)
    except (OutputFolderError, RunInterrupted):
        raise
    except Exception as exc:  # noqa: BLE001 - see Returns
        failure = str(exc) if isinstance(exc, SimulationError) else f"{type(exc).__name__}: {exc}"
    return failure, comm.bcast(time.perf_counter() - start, root=0)


def run_study(plan: Sequence[StudyPoint], out: str | Path, comm=None, quiet: bool = False,
              warm_up: bool = True, overwrite: bool = False, ignore_size: bool = False) -> list[dict[str, Any]]:
    """Run every point of ``plan`` (reference first), compute the errors and write the table and plot.

    Collective: every rank runs every scene; files are written and errors computed on rank 0 and the rows
    broadcast. A point whose run fails (whatever the exception: a solver's, a check that needs the mesh, PETSc's,
    a bug), or whose results are not finite, is kept in the table and the picture with ``converged = False``, its
    error message and NaN errors, and the study goes on; a failed reference stops the study (no errors can be
    computed without it). SIGINT or SIGTERM during a run (:class:`~dolfinx_fretting.simulation.RunInterrupted`)
    stops the study.

    Args:
        plan: From :func:`plan_study`.
        out: Output folder.
        comm: Communicator (default ``MPI.COMM_WORLD``).
        quiet: Print nothing but the final table.
        warm_up: Run the reference's first cycle once, untimed, before the timed runs.
        overwrite: Replace the study ``out`` holds (its runs are rerun in place).
        ignore_size: Run each scene even if its size estimate exceeds the memory available
            (:func:`dolfinx_fretting.sizes.check_size`); otherwise such a run fails like any other.

    Returns:
        The rows of ``study.csv`` (:data:`STUDY_FIELDS`), reference first.

    Raises:
        OutputFolderError: before any run: ``out`` is a file, not writable, or holds a study and not
            ``overwrite``.
        RuntimeError: The reference run failed (its message included).
        RunInterrupted: A signal stopped a run.
    """
    comm = comm or MPI.COMM_WORLD
    rank0 = comm.rank == 0
    out = Path(out)
    check_on_rank0(check_study_folder, out, overwrite, comm)
    runs_dir = out / "runs"
    say = (lambda m: print(m, flush=True)) if (rank0 and not quiet) else (lambda m: None)
    if warm_up:
        _warm_up(plan[0], runs_dir, comm, ignore_size)
    rows: list[dict[str, Any]] = []
    ref_folder = runs_dir / plan[0].label
    ref_time = math.nan
    for i, point in enumerate(plan):
        folder = runs_dir / point.label
        say(f"[study {i + 1}/{len(plan)}] {point.label}: {point.scene.loading.cycles} cycles ...")
        failure, wall = run_point(point.scene, folder, comm, ignore_size)
        if i == 0:
            if failure:
                raise RuntimeError(f"the reference run failed: {failure}")
            ref_time = wall
        row: dict[str, Any] = {}
        if rank0:
            row = {"label": point.label, "key": point.key, "value": point.value, "wall_time_s": wall,
                   "speedup": ref_time / wall if wall > 0 else math.nan, "overrides": " ".join(point.overrides)}
            try:
                row.update(point_errors(folder, ref_folder))
            except ValueError as exc:  # the run stopped before writing anything to read back: only its message
                failure = failure or f"its outputs cannot be read back: {exc}"
                row.update({k: math.nan for k in ERROR_FIELDS}, converged=False)
            if failure:
                row.update(converged=False, error=failure)
            if not row["converged"]:  # a failed or non-finite point has no error to plot or rank
                row.update({k: math.nan for k in ERROR_FIELDS})
            say(f"    {wall:.2f} s (x{row['speedup']:.3g}), " + (f"FAILED: {row['error']}" if not row["converged"] else
                "errors: " + ", ".join(f"{ERROR_NAMES[k]} {row[k]:.3g}" for k in ERROR_FIELDS)))
        rows.append(row)
    rows = comm.bcast(rows, root=0)
    if rank0:
        write_study_table(rows, out)
        try:
            plot_study(rows, out / "study.png", title=f"{plan[0].scene.name}: wall time against error "
                                                      f"(reference: {rows[0]['wall_time_s']:.1f} s)")
        except Exception as exc:  # noqa: BLE001 - a failed picture must not lose the table (written above)
            print(f"dolfinx-fretting study: warning: study.png not drawn: {type(exc).__name__}: {exc}",
                  file=sys.stderr, flush=True)
    comm.barrier()
    return rows


# Tables and picture --------------------------------------------------------------------------------------
def write_study_table(rows: Sequence[dict[str, Any]], out: str | Path) -> tuple[Path, Path]:
    """Write ``study.csv`` and ``study.md`` into ``out``; returns their paths."""
    return write_table(out, "study", rows, STUDY_FIELDS, format_markdown(rows))


def read_study_csv(path: str | Path) -> list[dict[str, Any]]:
    """``study.csv`` back as rows (numbers as floats, blank cells as NaN)."""
    return read_rows(path, text={"label", "key", "value", "error", "overrides"}, flags={"converged"})


def _pct(v: Any) -> str:
    if v is None or not isinstance(v, (int, float, np.floating)) or not math.isfinite(v):
        return "–"
    if v == 0:
        return "0"
    return f"{100 * v:.2g} %" if v >= 1e-4 else f"{v:.1e}"


def format_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """The study as a markdown table: relative errors as percentages (below 1e-4 as plain numbers)."""
    head = ["point", "cycles (physical)", "wall time (s)", "speed-up", "max wear", "wear profile L2",
            "peak pressure", "dissipated energy", "contacts"]
    lines = ["| " + " | ".join(head) + " |", "| --- |" + " ---: |" * (len(head) - 1)]
    for r in rows:
        name = "**reference**" if r.get("key") == "reference" else f"`{r.get('key')} = {r.get('value')}`"
        if r.get("key") == "point":
            name = f"`{r.get('value')}`"
        if not r.get("converged", True):
            name += " (failed: " + str(r.get("error", ""))[:80] + ")"
        cyc = f"{cell_text(r.get('cycles'))} ({cell_text(r.get('equivalent_cycles'))})"
        lines.append("| " + " | ".join([name, cyc, f"{r.get('wall_time_s', math.nan):.2f}",
                                        f"{r.get('speedup', math.nan):.2f}",
                                        *(_pct(r.get(k)) for k in ERROR_FIELDS), cell_text(r.get("contacts"))]) + " |")
    return "\n".join(lines)


def _pareto(t: np.ndarray, e: np.ndarray) -> np.ndarray:
    """Indices of the points no other point beats in both time and error, by increasing time."""
    idx = [i for i in np.argsort(t, kind="stable") if math.isfinite(t[i]) and math.isfinite(e[i])]
    front, best = [], math.inf
    for i in idx:
        if e[i] < best:
            front.append(i)
            best = e[i]
    return np.array(front, dtype=int)


def plot_study(rows: Sequence[dict[str, Any]], path: str | Path, title: str = "") -> Path:
    """Wall time against each relative error (log-log), one panel per error, one colour per swept key,
    each point labelled with its value; the reference's time as a dashed line (its error is zero) and the
    Pareto frontier of the points in grey. Errors below 1e-16 are drawn at 1e-16."""
    # Lazy: matplotlib is heavy and only the picture needs it; plots imports numba (through output)
    from matplotlib import ticker

    from .plots import _figure, _save

    keys = list(dict.fromkeys(r["key"] for r in rows if r.get("key") != "reference"))
    colours = ["tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange", "tab:brown", "tab:pink",
               "tab:olive", "tab:cyan", "tab:gray"]
    markers = ["o", "s", "^", "v", "D", "P", "X", "*", "<", ">"]
    fig = _figure((12.0, 9.6))
    axes = fig.subplots(2, 2, gridspec_kw=dict(left=0.08, right=0.98, top=0.88, bottom=0.13, wspace=0.22,
                                               hspace=0.3)).ravel()
    pts = [r for r in rows if r.get("key") != "reference"]
    t = np.array([r.get("wall_time_s", math.nan) for r in pts], dtype=float)
    ref_t = rows[0].get("wall_time_s", math.nan) if rows else math.nan
    floor = 1e-16
    for ax, name in zip(axes, ERROR_FIELDS):
        e = np.array([r.get(name, math.nan) for r in pts], dtype=float)
        e_plot = np.where(np.isfinite(e), np.maximum(e, floor), np.nan)
        for k, key in enumerate(keys):
            sel = [i for i, r in enumerate(pts) if r["key"] == key]
            ax.plot(e_plot[sel], t[sel], ls="", marker=markers[k % len(markers)], ms=7,
                    color=colours[k % len(colours)], label=key if key != "point" else "combinations")
            for i in sel:
                if math.isfinite(e_plot[i]) and math.isfinite(t[i]):
                    ax.annotate(pts[i]["value"] if key != "point" else pts[i]["label"], (e_plot[i], t[i]),
                                textcoords="offset points", xytext=(5, 4), fontsize=7.5,
                                color=colours[k % len(colours)])
        front = _pareto(t, e_plot)
        if front.size > 1:
            ax.step(e_plot[front], t[front], where="post", color="0.55", lw=1.0, zorder=0)
        if math.isfinite(ref_t):
            ax.axhline(ref_t, color="k", ls="--", lw=1.0, label=f"reference ({ref_t:.1f} s, error 0)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        # wall times span a decade or two: label the 2x and 5x ticks too
        ax.yaxis.set_major_locator(ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(ticker.FormatStrFormatter("%g"))
        ax.yaxis.set_minor_formatter(ticker.NullFormatter())
        ax.set_xlabel(f"relative error: {ERROR_NAMES[name]}")
        ax.set_ylabel("wall time (s)")
        ax.grid(alpha=0.3, which="both")
        if not np.any(np.isfinite(e_plot)):
            # nothing on a log axis: its limits are set, or matplotlib refuses to scale it (every point failed)
            ax.set_xlim(floor, 1.0)
            ax.text(0.5, 0.5, "no point drawn (failed, or reference value 0)", transform=ax.transAxes, ha="center",
                    color="0.4")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 4), fontsize=9, frameon=False)
    failed = [r["label"] for r in pts if not r.get("converged", True)]
    if failed:
        fig.text(0.5, 0.9, "failed (not drawn): " + ", ".join(failed), ha="center", fontsize=8, color="tab:red")
    if title:
        fig.suptitle(title + "\n(grey: Pareto frontier; errors < 1e-16 drawn at 1e-16)", fontsize=11)
    return _save(fig, Path(path))
