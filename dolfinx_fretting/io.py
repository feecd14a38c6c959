"""Results on disk: ``summary.json``, ``history.csv``, ``cycles.csv``, contact profiles, XDMF fields, plots.

Tables are written by rank 0 only and flushed after each increment (monotonic runs) or cycle (cyclic
runs), so an interrupted run leaves every finished row readable; ``summary.json`` and checkpoints are
replaced atomically (write to a temporary file, then rename). On resume the tables are truncated back to
the sizes recorded in the checkpoint, so rows written after it do not appear twice; a table shorter than
recorded (rows the checkpoint counts are gone) is refused with :class:`TableError`, never padded. ``fields.xdmf``
likewise keeps the time steps the checkpoint counts (:func:`keep_field_steps`). XDMF output is collective (every
rank calls it). ``summary.json`` is always valid JSON (:func:`write_json_atomic`).
"""

from __future__ import annotations

import ctypes
import errno
import json
import math
import os
import re
import shutil
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from .outdir import check_resume_tables
from .state import INCREMENT_COLUMNS
from .units import Units

__all__ = ["ResultWriter", "write_json_atomic", "finite_json", "non_finite_keys", "TableError", "HISTORY_FIELDS",
           "CYCLE_FIELDS", "PROFILE_FIELDS", "PROFILE_FIELDS_3D", "profile_fields", "plot_profiles",
           "RUN_DESCRIPTION", "read_run_description", "ZONE_HISTORY_FIELDS", "ZONE_HISTORY_FIELDS_3D",
           "ZONE_CYCLE_FIELDS", "FRICTION_CYCLE_FIELDS", "zone_columns", "zone_history_fields", "history_fields",
           "cycle_fields", "keep_field_steps"]

#: The machine-readable description of a run in its output folder: what was modelled (obstacle, bodies,
#: wear shares, dimension) and the columns of every table, for the readers (pictures, plots, compare).
RUN_DESCRIPTION = "run.json"

#: Columns of ``history.csv`` (one row per increment).
HISTORY_FIELDS = ["increment", "cycle", "step", "stage", "normal_displacement", "tangential_displacement",
                  "face_pressure", *INCREMENT_COLUMNS]
#: Columns of ``cycles.csv`` (one row per cycle of a cyclic run).
CYCLE_FIELDS = ["cycle", "equivalent_cycles", "jump", "jump_bound", "jump_stability_limit", "jump_error_estimate",
                "wear_error_estimate", "dissipated_energy", "wear_area", "max_wear_depth",
                "tangential_force_max", "tangential_force_min", "displacement_max", "displacement_min",
                "energy_ratio", "min_stick", "regime", "max_pressure_end", "plastic_regime", "plastic_flow",
                "plastic_net", "plastic_error_estimate", "local_iterations", "wall_time_s"]
#: Columns of ``contact_profiles.csv`` (one row per contact node and kept increment).
PROFILE_FIELDS = ["increment", "cycle", "step", "node", "position", "gap", "pressure", "shear", "slip",
                  "relative_tangential", "wear", "state"]
#: The columns a 3D contact adds to ``contact_profiles.csv``: the position along t2 and the t2 components (the
#: 2D columns ``position``, ``shear``, ``slip``, ``relative_tangential`` hold the t1 components).
PROFILE_FIELDS_3D = ("position_2", "shear_2", "slip_2", "relative_tangential_2")
#: Columns of ``flat_profiles.csv``: the master body's worn depth at its nodes (finite sliding, where the
#: master's wear is kept on its own nodes), at the end of each profiled cycle; ``position_2`` is 0 in 2D.
FLAT_PROFILE_FIELDS = ["increment", "cycle", "node", "position", "position_2", "wear"]
_TABLES = {"history": HISTORY_FIELDS, "cycles": CYCLE_FIELDS, "contact_profiles": PROFILE_FIELDS,
           "flat_profiles": FLAT_PROFILE_FIELDS}

#: Each zone's columns of ``history.csv`` when a problem has several contact zones (named ``zone<i>_<name>``,
#: :func:`zone_columns`; ``i`` the zone's place in the problem's list, 0 the first): its obstacle's position and
#: its total contact force on the body, both in the zone's own frame (n, t1), its peak pressure, the energy its
#: contacts dissipated in the increment and its worn area after it. The columns without a zone sum over every
#: zone's contacts (``normal_force``: each contact's normal component, whatever its zone's normal) and hold the
#: first zone's obstacle (``normal_displacement``, ``tangential_displacement``).
ZONE_HISTORY_FIELDS = ("normal_displacement", "tangential_displacement", "normal_force", "tangential_force",
                       "max_pressure", "dissipated_energy", "wear_area")
#: The t2 components a 3D zone adds to :data:`ZONE_HISTORY_FIELDS` (after them).
ZONE_HISTORY_FIELDS_3D = ("tangential_displacement_2", "tangential_force_2")
#: Each zone's columns of ``cycles.csv`` (``zone<i>_<name>``): the energy its contacts dissipated over the cycle,
#: its worn area at the cycle's end, the extremes of its normal and tangential (t1) forces over the cycle and its
#: peak pressure at the end.
ZONE_CYCLE_FIELDS = ("dissipated_energy", "wear_area", "normal_force_max", "normal_force_min",
                     "tangential_force_max", "tangential_force_min", "max_pressure_end")
#: The friction coefficient at a cycle's end (the state after it and its jump) when a zone's friction evolves
#: (:class:`~dolfinx_fretting.laws.EvolvingFriction`), over the contacts that carry a normal force then (none: every
#: contact): ``mu_mean`` weighted by each contact's normal force, sum mu_i r_n,i / sum r_n,i, the ratio Q/P the
#: contact carries in gross slip (what a rig measures), and the smallest and largest coefficient (equal to it for a
#: law of the cycles, which is uniform over a zone; apart for a law of the energy, which follows each contact's).
FRICTION_CYCLE_FIELDS = ("mu_mean", "mu_min", "mu_max")


def zone_columns(fields: tuple[str, ...] | list[str], zones: int) -> list[str]:
    """``zone0_<field>``, ... for each of ``zones`` zones in turn; none for one zone (its columns are the
    table's own, so a one-zone run's tables are those of a release without zones)."""
    return [f"zone{i}_{name}" for i in range(zones) for name in fields] if zones > 1 else []


def zone_history_fields(dim: int) -> tuple[str, ...]:
    """A zone's ``history.csv`` columns for a contact of dimension ``dim`` (without the ``zone<i>_`` prefix)."""
    return ZONE_HISTORY_FIELDS + (ZONE_HISTORY_FIELDS_3D if dim == 3 else ())


def history_fields(zones: int = 1, dim: int = 2) -> list[str]:
    """Columns of ``history.csv``: :data:`HISTORY_FIELDS`, then with several zones each zone's
    (:func:`zone_history_fields`)."""
    return [*HISTORY_FIELDS, *zone_columns(zone_history_fields(dim), zones)]


def cycle_fields(zones: int = 1, evolving_friction: bool = False) -> list[str]:
    """Columns of ``cycles.csv``: :data:`CYCLE_FIELDS`, with an evolving friction law
    :data:`FRICTION_CYCLE_FIELDS`, then with several zones each zone's (:data:`ZONE_CYCLE_FIELDS`, and
    :data:`FRICTION_CYCLE_FIELDS` with an evolving law)."""
    friction = FRICTION_CYCLE_FIELDS if evolving_friction else ()
    return [*CYCLE_FIELDS, *friction, *zone_columns(ZONE_CYCLE_FIELDS + friction, zones)]


def profile_fields(dim: int, zones: int = 1) -> list[str]:
    """Columns of ``contact_profiles.csv`` for a contact of dimension ``dim``: :data:`PROFILE_FIELDS` in 2D; in
    3D the t2 columns :data:`PROFILE_FIELDS_3D` before ``state`` (the integer column stays last). With several
    zones a last column ``zone`` (the zone's place in the problem's list), and ``node`` numbers each zone's
    contacts from 0: each zone's rows are a profile of their own."""
    columns = list(PROFILE_FIELDS) if dim == 2 else [*PROFILE_FIELDS[:-1], *PROFILE_FIELDS_3D, PROFILE_FIELDS[-1]]
    return columns + (["zone"] if zones > 1 else [])


def read_run_description(folder: str | Path) -> dict[str, Any] | None:
    """The folder's :data:`RUN_DESCRIPTION`, or None if it has none (a folder of an older release)."""
    try:
        return json.loads((Path(folder) / RUN_DESCRIPTION).read_text())
    except (OSError, ValueError):
        return None


def finite_json(data: Any, prefix: str = "") -> tuple[Any, list[str]]:
    """A JSON-ready copy of ``data`` with every non-finite number replaced by ``None``, and their keys.

    NumPy scalars and arrays become Python numbers and lists. Keys are dotted (``cycle_jump.stability_limit``),
    list elements indexed (``values[3]``).

    Returns:
        (copy, keys of the replaced values).
    """
    if isinstance(data, np.ndarray):
        data = data.tolist()
    elif isinstance(data, np.generic):
        data = data.item()
    if isinstance(data, dict):
        out, bad = {}, []
        for key, value in data.items():
            out[key], sub = finite_json(value, f"{prefix}.{key}" if prefix else str(key))
            bad += sub
        return out, bad
    if isinstance(data, (list, tuple)):
        out_list, bad = [], []
        for i, value in enumerate(data):
            v, sub = finite_json(value, f"{prefix}[{i}]")
            out_list.append(v)
            bad += sub
        return out_list, bad
    if isinstance(data, float) and not math.isfinite(data):
        return None, [prefix or "value"]
    return data, []


def non_finite_keys(data: Any) -> list[str]:
    """Dotted keys of the non-finite numbers (inf, nan) anywhere in ``data`` (dicts, lists, NumPy values)."""
    return finite_json(data)[1]


def write_json_atomic(path: Path, data: dict[str, Any]) -> None:
    """Write JSON through a temporary file and a rename, so readers never see half a file.

    The file is always valid JSON (RFC 8259 has no infinity or NaN; ``allow_nan=False``): a non-finite number
    is written as ``null`` and its key listed under ``"non_finite_keys"``. Written, not refused: the summary of a
    failed run is the diagnostic a user needs, and a null with its key named cannot be mistaken for a number
    (the runner also refuses to call such a run converged).
    """
    clean, bad = finite_json(data)
    if bad:
        clean = {**clean, "non_finite_keys": bad}
    tmp = path.with_suffix(path.suffix + ".tmp")
    try:
        with open(tmp, "w") as f:
            json.dump(clean, f, indent=2, default=_jsonable, allow_nan=False)
            f.write("\n")
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:  # a full disk: the old file stays, the message names the file (not the buffer)
        tmp.unlink(missing_ok=True)
        raise OSError(exc.errno, f"{path} not written: {exc.strerror or exc}{_free_space(path.parent)}") from None
    os.replace(tmp, path)


def _free_space(folder: Path) -> str:
    """``" (N bytes free ...)"`` for a message about a failed write, or an empty string."""
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        return ""
    return f" ({free} bytes free on its file system)" if free < 1 << 20 else ""


_HDF5_QUIET = []


def _quiet_hdf5() -> None:
    """Turn off the HDF5 library's own print of its error stack (a full disk: ~60 lines of ``HDF5-DIAG`` on
    stderr before DOLFINx raises); the failure is reported once, as a one-line :class:`OSError`. Done once per
    process, on every ``libhdf5`` it has loaded (DOLFINx's; found in ``/proc/self/maps``: Linux only)."""
    if _HDF5_QUIET:
        return
    _HDF5_QUIET.append(True)
    try:
        with open("/proc/self/maps") as maps:
            paths = {line.split()[-1] for line in maps if "/libhdf5" in line}
        for path in paths:
            if Path(path).name.startswith("libhdf5") and "_hl" not in Path(path).name:
                # H5Eset_auto2(H5E_DEFAULT = 0, no function, no data): no automatic print of the default stack
                ctypes.CDLL(path).H5Eset_auto2(ctypes.c_int64(0), None, None)
    except (OSError, AttributeError):  # not Linux, or another HDF5: its print stays
        pass


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def _fmt(v: Any) -> str:
    if isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return f"{float(v):.10g}"


class TableError(ValueError):
    """A table cannot be resumed: missing, or shorter than the checkpoint records (the message names it)."""


def _temporal_collections(root: ElementTree.Element) -> list[ElementTree.Element]:
    """The XDMF's time series: one ``Grid`` of ``CollectionType="Temporal"`` per function written."""
    return [grid for grid in root.iter("Grid") if grid.get("CollectionType") == "Temporal"]


def keep_field_steps(xdmf_path: str | Path, steps: int | None) -> tuple[int, str | None]:
    """Cut an XDMF file of fields back to its first ``steps`` time steps (rank 0, on resume).

    A run killed after a fields write and before its checkpoint would otherwise show that step twice once the
    resumed run writes it again. Each function's time series keeps its first ``steps`` grids; the HDF5 datasets
    of the grids dropped are deleted from the ``.h5`` (unlinked: DOLFINx cannot write a dataset of a name that
    exists, and the resumed run writes the same names again; HDF5 does not give their bytes back, ``h5repack``
    does). The XDMF is replaced atomically.

    Args:
        xdmf_path: ``fields.xdmf``.
        steps: The time steps the checkpoint counts; ``None`` (a checkpoint of an older version, which did not
            count them): the file is kept as it is.

    Returns:
        (the time steps the file now holds, ``None``), or (0, a message) if it cannot be cut: missing, unreadable,
        or holding fewer steps than ``steps``; nothing is changed then.
    """
    xdmf_path = Path(xdmf_path)
    try:
        tree = ElementTree.parse(xdmf_path)
    except (OSError, ElementTree.ParseError) as exc:
        return 0, (f"{xdmf_path} does not load ({type(exc).__name__}: {exc}) but the checkpoint counts time "
                   "steps of it; restore it, or start afresh with --overwrite")
    collections = _temporal_collections(tree.getroot())
    if steps is None:
        return max((len(collection.findall("Grid")) for collection in collections), default=0), None
    dropped: list[str] = []
    for collection in collections:
        grids = collection.findall("Grid")
        if len(grids) < steps:
            return 0, (f"{xdmf_path} holds {len(grids)} time steps of {collection.get('Name')!r}, fewer than the "
                       f"{steps} the checkpoint counts: steps it relies on are gone; restore it, or start afresh "
                       "with --overwrite")
        for grid in grids[steps:]:
            dropped += [item.text.strip() for item in grid.iter("DataItem") if item.text and ":" in item.text]
            collection.remove(grid)
    if not dropped:
        return steps, None
    # Lazy: not a declared dependency (installed with DOLFINx by scripts/setup.sh); only a resume that cuts needs it
    import h5py

    kept = {item.text.strip() for item in tree.getroot().iter("DataItem") if item.text}
    with h5py.File(xdmf_path.with_suffix(".h5"), "r+") as h5:
        for reference in dropped:
            dataset = reference.split(":", 1)[1]
            if reference not in kept and dataset in h5:   # (an older run's repeated step shares its name)
                del h5[dataset]
    # The XInclude prefix as DOLFINx declared it (its URI differs between versions): ElementTree would invent one
    namespace = re.search(r'xmlns:xi="([^"]+)"', xdmf_path.read_text())
    if namespace is not None:
        ElementTree.register_namespace("xi", namespace.group(1))
    tmp = xdmf_path.with_suffix(".xdmf.tmp")
    with open(tmp, "w") as f:   # DOLFINx's declaration, then the tree
        f.write('<?xml version="1.0"?>\n' + ElementTree.tostring(tree.getroot(), encoding="unicode") + "\n")
    os.replace(tmp, xdmf_path)
    return steps, None


class ResultWriter:
    """Writes a run's tables into ``out_dir`` (rank 0) and its fields (collective).

    Args:
        out_dir: Output folder (created).
        comm: Communicator; tables and pictures are written by its rank 0.
        profiles: Write ``contact_profiles.csv``.
        flat_profiles: Write ``flat_profiles.csv`` (with ``profiles``).
        resume_sizes: Byte sizes of the tables at the checkpoint to resume from: the tables are
            truncated to them and appended to. ``None``: new tables.
        xdmf_started: The XDMF file already holds the mesh (resume).
        fields_steps: The time steps of ``fields.xdmf`` the checkpoint counts (resume): the file is cut back to them
            (:func:`keep_field_steps`). ``None`` (a checkpoint of an older version): the file is kept as it is.
        dim: Dimension of the contact (the columns of ``contact_profiles.csv``, :func:`profile_fields`).
        zones: Contact zones of the problem (with several, each zone's columns: :func:`history_fields`,
            :func:`cycle_fields`, :func:`profile_fields`).
        evolving_friction: A zone's friction evolves (``cycles.csv``: :data:`FRICTION_CYCLE_FIELDS`).
    """

    def __init__(self, out_dir: str | Path, comm: MPI.Comm, profiles: bool = True,
                 resume_sizes: dict[str, int] | None = None, xdmf_started: bool = False, dim: int = 2,
                 flat_profiles: bool = False, zones: int = 1, evolving_friction: bool = False,
                 fields_steps: int | None = None):
        self.out = Path(out_dir)
        self.comm = comm
        self.rank0 = comm.rank == 0
        if self.rank0:
            self.out.mkdir(parents=True, exist_ok=True)
        comm.barrier()
        self._files: dict[str, Any] = {}
        self._columns = {**_TABLES, "history": history_fields(zones, dim),
                         "cycles": cycle_fields(zones, evolving_friction),
                         "contact_profiles": profile_fields(dim, zones)}
        names = ["history", "cycles"] + (["contact_profiles"] if profiles else []) + \
            (["flat_profiles"] if profiles and flat_profiles else [])
        # A table shorter than the checkpoint records (or missing) has lost rows: truncate() would extend it
        # with NUL bytes (or a new table would start without them). Checked on rank 0, raised on every rank.
        problem = None
        if self.rank0 and resume_sizes is not None:
            problem = check_resume_tables(self.out, {k: v for k, v in resume_sizes.items() if k in names})
        # fields.xdmf: the steps written after the checkpoint dropped (checked and cut on rank 0, before the bcast)
        #: Time steps written into ``fields.xdmf`` (what a checkpoint records:
        #: :meth:`~dolfinx_fretting.output.FrettingWriter.checkpoint_info`).
        self.fields_steps = 0
        if self.rank0 and resume_sizes is not None and xdmf_started and problem is None:
            self.fields_steps, problem = keep_field_steps(self.out / "fields.xdmf", fields_steps)
        if comm.size > 1:
            problem, self.fields_steps = comm.bcast((problem, self.fields_steps), root=0)
        if problem is not None:
            raise TableError(f"--resume: {problem}")
        if self.rank0:
            for name in names:
                path = self.out / f"{name}.csv"
                if resume_sizes is not None and name in resume_sizes:
                    f = open(path, "r+")
                    f.truncate(resume_sizes[name])
                    f.seek(resume_sizes[name])
                else:
                    f = open(path, "w")
                    f.write(",".join(self._columns[name]) + "\n")
                self._files[name] = f
        self._xdmf_path = self.out / "fields.xdmf"
        self._xdmf_started = xdmf_started

    def _write(self, name: str, lines: list[str]) -> None:
        f = self._files.get(name)
        if f is not None and lines:
            f.write("\n".join(lines) + "\n")

    def rows(self, name: str, rows: list[dict[str, Any]]) -> None:
        """Append rows (dicts keyed by the table's columns) to ``name`` (``history``, ``cycles``)."""
        if name in self._files:
            cols = self._columns[name]
            self._write(name, [",".join(_fmt(r[c]) for c in cols) for r in rows])

    def history_block(self, head: list[tuple], table: np.ndarray, stage: str) -> None:
        """Fast path for many increments: ``head`` holds (increment, cycle, step) per row, ``table`` the
        remaining numeric columns of :func:`history_fields` after ``stage``, in order."""
        if "history" not in self._files:
            return
        fmt = "%d,%d,%d," + stage + "," + ",".join(["%.10g"] * table.shape[1])
        self._write("history", [fmt % (*h, *row) for h, row in zip(head, table.tolist())])

    def profile_block(self, increment: int, cycle: int, step: int, columns: list[np.ndarray],
                      zone: np.ndarray | None = None) -> None:
        """Append one increment's contact profile; ``columns`` follow :func:`profile_fields` from ``position`` to
        ``state``; ``zone``: each contact's zone (several zones: the ``zone`` column, ``node`` counted per zone)."""
        if "contact_profiles" not in self._files:
            return
        n = columns[0].size
        if zone is None:
            node, extra, tail = np.arange(n), [], ",%d"
        else:  # each zone's contacts numbered from 0 (a zone's contacts are consecutive)
            starts = np.searchsorted(zone, zone)
            node, extra, tail = np.arange(n) - starts, [zone], ",%d,%d"
        data = np.column_stack([np.full(n, increment), np.full(n, cycle), np.full(n, step), node, *columns, *extra])
        fmt = "%d,%d,%d,%d," + ",".join(["%.10g"] * (len(columns) - 1)) + tail
        self._write("contact_profiles", [fmt % tuple(r) for r in data.tolist()])

    def flat_block(self, increment: int, cycle: int, positions: np.ndarray, wear: np.ndarray) -> None:
        """Append the master's worn depth at its nodes (``positions`` (n, 2): along t1 and t2)."""
        if "flat_profiles" not in self._files:
            return
        n = wear.size
        data = np.column_stack([np.full(n, increment), np.full(n, cycle), np.arange(n), positions, wear])
        self._write("flat_profiles", ["%d,%d,%d,%.10g,%.10g,%.10g" % tuple(r) for r in data.tolist()])

    def flush(self) -> None:
        for name, f in self._files.items():
            try:
                f.flush()
            except OSError as exc:  # a full disk: name the table (the buffer's error does not)
                raise OSError(exc.errno, f"{self.out / name}.csv not written: {exc.strerror or exc}"
                              f"{_free_space(self.out)}") from None

    def sizes(self) -> dict[str, int]:
        """Byte size of each table after a flush (rank 0; empty elsewhere)."""
        self.flush()
        return {name: f.tell() for name, f in self._files.items()}

    def fields(self, t: float, functions: list) -> None:
        """Append functions at time ``t`` to ``fields.xdmf`` (collective); the file is closed after each
        write so what is on disk is always complete."""
        # Lazy: DOLFINx only to write fields; compare and the pictures' child process read tables through this
        # module without it
        from dolfinx.io import XDMFFile

        msh = functions[0].function_space.mesh
        mode = "a" if self._xdmf_started else "w"
        self._check_room(functions, msh)
        _quiet_hdf5()
        try:
            with XDMFFile(self.comm, str(self._xdmf_path), mode) as f:
                if not self._xdmf_started:
                    f.write_mesh(msh)
                for fn in functions:
                    f.write_function(fn, t)
        except RuntimeError as exc:  # HDF5 (a full disk: "Failed to close HDF5 dataset."), as an output error
            raise OSError(f"{self._xdmf_path} (and its .h5) not written: {exc}{_free_space(self.out)}") from None
        self._xdmf_started = True
        self.fields_steps += 1

    def _check_room(self, functions: list, msh) -> None:
        """Refuse (:class:`OSError`, on every rank) an XDMF write the disk has no room for, before HDF5 starts it:
        HDF5 out of space leaves a file it cannot close, and the current DOLFINx wheel's HDF5 (built with its
        assertions) then aborts the process at exit. Collective. The need is over-estimated: every array as
        stored (a 2D vector padded to 3 components: 1.5 times its values), twice, plus 64 KiB of metadata."""
        from ._dolfinx import geometry_dofmap  # lazy: DOLFINx, as above

        values = sum(fn.x.array.size * 1.5 for fn in functions)
        if not self._xdmf_started:
            values += msh.geometry.x.size + geometry_dofmap(msh).size
        needed = 2 * 8 * self.comm.allreduce(values) + (64 << 10)
        free = None
        if self.rank0:
            try:
                free = shutil.disk_usage(self.out).free
            except OSError:  # a folder gone: the write's own error says so
                pass
        free = self.comm.bcast(free, root=0) if self.comm.size > 1 else free
        if free is not None and free < needed:
            raise OSError(errno.ENOSPC, f"{self._xdmf_path} (and its .h5) not written: it needs about "
                          f"{int(needed)} bytes and {free} are free on its file system")

    @property
    def xdmf_started(self) -> bool:
        return self._xdmf_started

    def summary(self, data: dict[str, Any]) -> None:
        if self.rank0:
            write_json_atomic(self.out / "summary.json", data)

    def close(self) -> None:
        for f in self._files.values():
            f.close()
        self._files = {}


def plot_profiles(path: Path, position: np.ndarray, curves: list[tuple[str, np.ndarray, np.ndarray]],
                  reference: tuple[str, np.ndarray, np.ndarray] | None = None, title: str = "",
                  units: Units | None = None) -> None:
    """Pressure and shear traction along the contact (matplotlib, PNG).

    Args:
        path: PNG file.
        position: Node positions along the surface.
        curves: (label, pressure, shear) per snapshot.
        reference: Optional (label, x, pressure) closed form drawn dashed.
        title: Figure title.
        units: The :class:`~dolfinx_fretting.units.Units` of the labels (default: the scenes' mm, N, MPa).
    """
    units = units or Units.mm_N_MPa()
    import matplotlib  # lazy: heavy, only for this picture (and its backend chosen before pyplot loads)

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_p, ax_s) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    for label, p, s in curves:
        ax_p.plot(position, p, ".-", ms=3, label=label)
        ax_s.plot(position, s, ".-", ms=3, label=label)
    if reference is not None:
        ax_p.plot(reference[1], reference[2], "k--", lw=1, label=reference[0])
    ax_p.set_ylabel(f"contact pressure p ({units.stress})")
    ax_s.set_ylabel(f"shear traction q ({units.stress})")
    ax_s.set_xlabel(f"position along the surface ({units.length})")
    for ax in (ax_p, ax_s):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
